// `vcu j1939` without a stack (issue 24): the PGN and address parsers,
// and the argument errors, all answered before any IPC. The commands against a stack are
// in tests/integration/test_j1939_commands.cpp.

#include <doctest/doctest.h>

#include "j1939_commands.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu::cli;
using namespace openvcu::cli::test;

namespace {

const std::string CONFIG = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/integration/vehicle.json";

}  // namespace

TEST_CASE("parsePgn and parseJ1939Address take decimal and 0x hex within range and nothing else") {
  CHECK(parsePgn("65242") == 65242u);
  CHECK(parsePgn("0xFEDA") == 0xFEDAu);
  CHECK(parsePgn("0x3FFFF") == 0x3FFFFu);
  CHECK_FALSE(parsePgn("0x40000"));
  CHECK_FALSE(parsePgn("-1"));
  CHECK_FALSE(parsePgn("12a"));
  CHECK_FALSE(parsePgn("0x"));
  CHECK_FALSE(parsePgn(""));
  CHECK(parseJ1939Address("255") == std::uint8_t{255});
  CHECK(parseJ1939Address("0x21") == std::uint8_t{0x21});
  CHECK_FALSE(parseJ1939Address("256"));
  CHECK_FALSE(parseJ1939Address("0x100"));
}

TEST_CASE("vcu j1939 request names a bad PGN, destination or source address and exits 2") {
  const RunResult badPgn = runVcu({"j1939", "request", "0x40000", "--to", "0x21", "--config", CONFIG});
  const RunResult badTo = runVcu({"j1939", "request", "65242", "--to", "300", "--config", CONFIG});
  const RunResult badFrom = runVcu({"j1939", "request", "65242", "--to", "0x21", "--from", "0xFE", "--config", CONFIG});
  const RunResult noTo = runVcu({"j1939", "request", "65242", "--config", CONFIG});

  CHECK(badPgn.exitCode == EXIT_USAGE);
  CHECK(badPgn.err == "vcu: error: PGN '0x40000': not a PGN (0..262143 or 0x0..0x3FFFF)\n");
  CHECK(badTo.exitCode == EXIT_USAGE);
  CHECK(badTo.err == "vcu: error: --to '300': not a J1939 address (0..255 or 0x00..0xFF; 255 = global)\n");
  CHECK(badFrom.exitCode == EXIT_USAGE);
  CHECK(badFrom.err == "vcu: error: --from '0xFE': not a source address (0..253 or 0x00..0xFD)\n");
  CHECK(noTo.exitCode == EXIT_USAGE);
  CHECK_MESSAGE(contains(noTo.err, "--to is required"), noTo.err);
  CHECK(badPgn.out.empty());
}

TEST_CASE("vcu j1939 and its request name an unknown bus with a did-you-mean before any IPC") {
  const RunResult request =
      runVcu({"j1939", "request", "65242", "--to", "0x21", "--bus", "vehicel", "--config", CONFIG});
  const RunResult show = runVcu({"j1939", "--bus", "vehicel", "--config", CONFIG});

  CHECK(request.exitCode == EXIT_INPUT_ERROR);
  CHECK(request.err == "vcu: error: unknown bus 'vehicel' (did you mean 'vehicle'?)\n");
  CHECK(show.exitCode == EXIT_INPUT_ERROR);
  CHECK(show.err == "vcu: error: unknown bus 'vehicel' (did you mean 'vehicle'?)\n");
}
