// Issue #19, "every bad input refused", for vcu's own arguments: a cansend frame ending in
// '.' is refused with the column of the dot, `vcu dbc decode --limit` refuses a negative
// count (it used to wrap to 2^64 - 1). `vcu schedule import` takes whole-ms cycles only:
// test_schedule_import.cpp ("CycleTime '10.5'").

#include <string>

#include "cansend_syntax.hpp"
#include "vcu_test_support.hpp"

using openvcu::cli::parseCansendFrame;
using namespace openvcu::cli::test;

TEST_CASE("#19 a '.' with no byte after it is refused at its column") {
  const auto trailing = parseCansendFrame("123#11.22.");
  const auto alone = parseCansendFrame("123#.");
  const auto afterEight = parseCansendFrame("123#11.22.33.44.55.66.77.88.");
  const auto fdTrailing = parseCansendFrame("123##1AA.");

  REQUIRE_FALSE(trailing.ok());
  CHECK(trailing.error().message == "a '.' with no byte after it at column 10 (remove the trailing '.')");
  CHECK(trailing.error().location.column == 10);
  REQUIRE_FALSE(alone.ok());
  CHECK(alone.error().location.column == 5);
  REQUIRE_FALSE(afterEight.ok());
  CHECK(afterEight.error().location.column == 28);
  REQUIRE_FALSE(fdTrailing.ok());
  CHECK(fdTrailing.error().location.column == 9);
  CHECK(parseCansendFrame("123#11.22").ok());  // a '.' between bytes stays fine
}

TEST_CASE("#19 vcu send refuses a trailing '.' before it touches a bus") {
  const RunResult sut = runVcu({"send", "vehicle", "123#11.22."});

  CHECK(sut.exitCode == EXIT_USAGE);
  CHECK(sut.out.empty());
  CHECK(contains(sut.err, "column 10"));
}

TEST_CASE("#19 vcu dbc decode refuses a negative --limit as a usage error") {
  const std::string log = writeScratchFile("issue19-one.log", "(0.000000) can0 123#1122\n");
  const RunResult sut = runVcu({"dbc", "decode", "--limit", "-1", dataPath("vehicle.dbc"), log});
  const RunResult zero = runVcu({"dbc", "decode", "--limit", "0", dataPath("vehicle.dbc"), log});

  CHECK(sut.exitCode == EXIT_USAGE);
  CHECK(sut.err == "vcu: error: --limit: must be 0 or more, not -1 (see --help)\n");  // no 309-digit bound
  CHECK(sut.out.empty());
  CHECK(zero.exitCode == EXIT_OK);
}

TEST_CASE("#19 negative or non-numeric durations are refused with a short message, not a 309-digit bound") {
  const RunResult top = runVcu({"top", "--for", "-1"});
  const RunResult send = runVcu({"send", "--interval", "abc", "vehicle", "123#11"});

  CHECK(top.exitCode == EXIT_USAGE);
  CHECK(top.err == "vcu: error: --for: must be 0 or more, not -1 (see --help)\n");
  CHECK(send.exitCode == EXIT_USAGE);
  CHECK(send.err == "vcu: error: --interval: 'abc' is not a number (see --help)\n");
}
