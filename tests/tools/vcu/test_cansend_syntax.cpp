// The cansend frame syntax of `vcu send` (tools/vcu/src/cansend_syntax.hpp), and how the
// command reports a malformed frame before it touches any bus or iox-roudi.
#include <algorithm>
#include <array>
#include <string>
#include <string_view>

#include "cansend_syntax.hpp"
#include "openvcu/can/log_writer.hpp"
#include "vcu_test_support.hpp"

using openvcu::cli::parseCansendFrame;
namespace can = openvcu::can;
using namespace openvcu::cli::test;

namespace {

constexpr std::uint32_t STANDARD_ID = 0x123;
constexpr std::uint32_t EXTENDED_ID = 0x18FEF121;
constexpr std::size_t CLASSIC_MAX = 8;
constexpr std::size_t FD_MAX = 64;

const std::string INTEGRATION_CONFIG = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/integration/vehicle.json";

/// The payload as "DE AD BE EF".
std::string bytes(const can::Frame& frame) {
  std::string text;
  constexpr std::string_view HEX = "0123456789ABCDEF";
  for (const std::uint8_t byte : frame.payload()) {
    if (!text.empty()) text += ' ';
    text += HEX[byte >> 4];
    text += HEX[byte & 0x0F];
  }
  return text;
}

/// The error message of a text that must not parse.
std::string errorOf(std::string_view text) {
  const auto parseResult = parseCansendFrame(text);
  REQUIRE_MESSAGE(!parseResult.ok(), (std::string(text) + " parsed"));
  return parseResult.error().message;
}

/// `count` bytes as hex digits: 00 01 02 ...
std::string hexBytes(std::size_t count) {
  std::string text;
  constexpr std::string_view HEX = "0123456789ABCDEF";
  for (std::size_t i = 0; i < count; ++i) {
    text += HEX[(i >> 4) & 0x0F];
    text += HEX[i & 0x0F];
  }
  return text;
}

}  // namespace

TEST_CASE("three ID digits make a standard frame with the bytes after '#'") {
  const auto sut = parseCansendFrame("123#DEADBEEF");

  REQUIRE(sut.ok());
  CHECK(sut->id == STANDARD_ID);
  CHECK_FALSE(sut->extended());
  CHECK_FALSE(sut->fd());
  CHECK(sut->flags == 0);
  CHECK(bytes(*sut) == "DE AD BE EF");
}

TEST_CASE("eight ID digits make an extended frame, even for a small ID") {
  const auto big = parseCansendFrame("18FEF121#0102");
  const auto small = parseCansendFrame("00000123#");

  REQUIRE(big.ok());
  CHECK(big->id == EXTENDED_ID);
  CHECK(big->extended());
  CHECK(bytes(*big) == "01 02");
  REQUIRE(small.ok());
  CHECK(small->id == STANDARD_ID);
  CHECK(small->extended());
  CHECK(small->length == 0);
}

TEST_CASE("hex digits are read in either case and '.' may separate bytes") {
  const auto lower = parseCansendFrame("1ab#de.ad.be.ef");
  const auto leadingDot = parseCansendFrame("123#.11");

  REQUIRE(lower.ok());
  CHECK(lower->id == 0x1AB);
  CHECK(bytes(*lower) == "DE AD BE EF");
  REQUIRE(leadingDot.ok());
  CHECK(bytes(*leadingDot) == "11");
}

TEST_CASE("a frame with no data after '#' has length 0") {
  const auto sut = parseCansendFrame("7FF#");

  REQUIRE(sut.ok());
  CHECK(sut->id == can::STANDARD_ID_MASK);
  CHECK(sut->length == 0);
}

TEST_CASE("eight classic bytes are accepted and a ninth is an error at its column") {
  const auto eight = parseCansendFrame("123#" + hexBytes(CLASSIC_MAX));
  const std::string nine = errorOf("123#" + hexBytes(CLASSIC_MAX + 1));

  REQUIRE(eight.ok());
  CHECK(eight->length == CLASSIC_MAX);
  CHECK(nine == "more than 8 data bytes at column 21 (classic CAN; CAN FD is ID##<flags><data>)");
}

TEST_CASE("R or r after '#' is a remote request with an optional length digit 0..8") {
  const auto bare = parseCansendFrame("123#R");
  const auto withLength = parseCansendFrame("18FEF121#r3");

  REQUIRE(bare.ok());
  CHECK((bare->flags & can::FLAG_RTR) != 0);
  CHECK(bare->length == 0);
  REQUIRE(withLength.ok());
  CHECK((withLength->flags & can::FLAG_RTR) != 0);
  CHECK(withLength->extended());
  CHECK(withLength->length == 3);
  CHECK(errorOf("123#R9") == "a remote request takes one length digit 0..8 at column 6 (e.g. 123#R or 123#R4)");
  CHECK(errorOf("123#R3x") == "unexpected text after the remote request at column 7");
}

TEST_CASE("'##' and a flags digit make a CAN FD frame: 1 is BRS, 2 is ESI") {
  const auto brs = parseCansendFrame("123##1DEADBEEF");
  const auto esi = parseCansendFrame("123##2");
  const auto both = parseCansendFrame("18FEF121##311");
  const auto none = parseCansendFrame("123##0AA");

  REQUIRE(brs.ok());
  CHECK(brs->fd());
  CHECK((brs->flags & can::FLAG_BRS) != 0);
  CHECK((brs->flags & can::FLAG_ESI) == 0);
  CHECK(bytes(*brs) == "DE AD BE EF");
  REQUIRE(esi.ok());
  CHECK((esi->flags & can::FLAG_ESI) != 0);
  CHECK((esi->flags & can::FLAG_BRS) == 0);
  CHECK(esi->length == 0);
  REQUIRE(both.ok());
  CHECK(both->extended());
  CHECK((both->flags & (can::FLAG_BRS | can::FLAG_ESI)) == (can::FLAG_BRS | can::FLAG_ESI));
  REQUIRE(none.ok());
  CHECK(none->fd());
  CHECK((none->flags & (can::FLAG_BRS | can::FLAG_ESI)) == 0);
}

TEST_CASE("a CAN FD length between the FD sizes is padded with zeros, like cansend") {
  const auto sut = parseCansendFrame("123##0" + hexBytes(9));

  REQUIRE(sut.ok());
  CHECK(sut->length == 12);
  CHECK(bytes(*sut) == "00 01 02 03 04 05 06 07 08 00 00 00");
}

TEST_CASE("a CAN FD frame takes 64 bytes and a 65th is an error") {
  const auto full = parseCansendFrame("123##1" + hexBytes(FD_MAX));
  const std::string over = errorOf("123##1" + hexBytes(FD_MAX + 1));

  REQUIRE(full.ok());
  CHECK(full->length == FD_MAX);
  CHECK(over == "more than 64 data bytes at column 135 (the CAN FD limit)");
}

TEST_CASE("a character that is not a hex digit is reported with its 1-based column") {
  const auto sut = parseCansendFrame("12G#00");

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message == "not a hexadecimal digit at column 3");
  CHECK(sut.error().location.column == 3);
  CHECK(errorOf("123#00X1") == "not a hexadecimal digit at column 7");
  CHECK(errorOf("123#0X11") == "not a hexadecimal digit at column 6");
  CHECK(errorOf("123#11..22") == "not a hexadecimal digit at column 8");
  CHECK(errorOf("123##G00") == "not a hexadecimal digit at column 6 (the CAN FD flags after '##': 0..F)");
}

TEST_CASE("an odd number of data digits is half a byte at the lone digit") {
  CHECK(errorOf("123#ABC") == "half a byte at column 7 (each byte is two hex digits)");
}

TEST_CASE("an ID that is not 3 or 8 digits long is an error that shows the syntax") {
  CHECK(errorOf("12#00") ==
        "an ID has 3 hex digits (standard) or 8 (extended), not 2 at column 1 "
        "(e.g. 123#DEADBEEF or 18FEF121#0102)");
  CHECK(errorOf("1234567#00").find("not 7 at column 1") != std::string::npos);
  CHECK(errorOf("123456789#00").find("not 9 at column 1") != std::string::npos);
  CHECK(errorOf("#00") == "no ID before '#' at column 1 (e.g. 123#DEADBEEF or 18FEF121#0102)");
  CHECK(errorOf("12345#00").find("CAN XL") != std::string::npos);
}

TEST_CASE("a text without '#' is an error at its end") {
  CHECK(errorOf("123DEAD") == "no '#' between ID and data at column 8 (e.g. 123#DEADBEEF or 18FEF121#0102)");
  CHECK(errorOf("") == "no '#' between ID and data at column 1 (e.g. 123#DEADBEEF or 18FEF121#0102)");
}

TEST_CASE("IDs beyond 11 or 29 bits are refused instead of being sent as flags") {
  const auto largestExtended = parseCansendFrame("1FFFFFFF#");

  REQUIRE(largestExtended.ok());
  CHECK(largestExtended->id == can::EXTENDED_ID_MASK);
  CHECK(errorOf("800#00") ==
        "standard ID 0x800 is above 0x7FF at column 1 (write 8 digits for an extended ID, e.g. 00000800)");
  CHECK(errorOf("20000000#00") == "extended ID 0x20000000 is above 0x1FFFFFFF at column 1");
}

TEST_CASE("the raw DLC suffix of can-utils is refused: a frame carries no DLC above 8") {
  CHECK(errorOf("123#1122334455667788_9").find("raw DLC suffix '_' is not supported at column 21") !=
        std::string::npos);
  CHECK(errorOf("123#R8_9").find("at column 7") != std::string::npos);
}

TEST_CASE("a missing CAN FD flags digit is an error after '##'") {
  CHECK(errorOf("123##") == "no CAN FD flags digit after '##' at column 6 (e.g. 123##1DEADBEEF)");
}

TEST_CASE("parsed frames print back as the same candump -L frame text") {
  constexpr std::array<std::string_view, 6> CANONICAL = {
      "123#DEADBEEF", "18FEF121#0102030405060708", "123#R", "123#R4", "123##1DEADBEEF", "7FF#"};
  for (const std::string_view text : CANONICAL) {
    CAPTURE(text);
    const auto sut = parseCansendFrame(text);
    REQUIRE(sut.ok());

    const std::string line = can::formatCandumpL(*sut, "vehicle");

    CHECK(line == "(0.000000) vehicle " + std::string(text));
  }
}

TEST_CASE("vcu send reports every malformed frame with its column, sends nothing and exits 2") {
  const RunResult result = runVcu({"send", "vehicle", "12G#00", "123#00", "123#R9"});

  CHECK(result.exitCode == EXIT_USAGE);
  CHECK(result.out.empty());
  CHECK(splitLines(result.err) ==
        std::vector<std::string>{"vcu: error: '12G#00': not a hexadecimal digit at column 3",
                                 "vcu: error: '123#R9': a remote request takes one length digit 0..8 at column 6 "
                                 "(e.g. 123#R or 123#R4)"});
}

TEST_CASE("vcu send and vcu dump answer an unknown bus with a did-you-mean before opening anything") {
  const RunResult send = runVcu({"send", "--config", INTEGRATION_CONFIG, "vehicel", "123#00"});
  const RunResult dump = runVcu({"dump", "--config", INTEGRATION_CONFIG, "vehicel"});

  CHECK(send.exitCode == EXIT_INPUT_ERROR);
  CHECK(send.err == "vcu: error: unknown bus 'vehicel' (did you mean 'vehicle'?)\n");
  CHECK(dump.exitCode == EXIT_INPUT_ERROR);
  CHECK(dump.err == "vcu: error: unknown bus 'vehicel' (did you mean 'vehicle'?)\n");
}

TEST_CASE("vcu send refuses a CAN FD frame for a classic bus before opening anything") {
  const RunResult result = runVcu({"send", "--direct", "--config", INTEGRATION_CONFIG, "vehicle", "123##1AA"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "'123##1AA': bus 'vehicle' is classic CAN"));
}
