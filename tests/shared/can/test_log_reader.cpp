// LogReader as a stream: files, line endings, comments, error reporting and recovery.

#include <doctest/doctest.h>

#include <sstream>
#include <string>

#include "log_test_support.hpp"

using namespace openvcu::can;
using openvcu::can::test::payloadOf;
using openvcu::can::test::readAll;
using openvcu::can::test::readFixture;
using openvcu::can::test::readText;

namespace {
using Bytes = std::vector<std::uint8_t>;
}  // namespace

TEST_CASE("reader returns every frame of the candump -L fixture and skips comments") {
  const auto result = readFixture("candump_l.log");

  CHECK(result.errorCount == 0);
  CHECK(result.format == LogFormat::Candump);
  REQUIRE(result.records.size() == 10);
  CHECK(result.records[0].line == 2);
  CHECK(result.records[3].line == 6);  // after a blank line
  CHECK(result.records[3].channel == "can1");
  CHECK(result.records[5].frame.flags == (FLAG_EXTENDED | FLAG_FD | FLAG_BRS | FLAG_ESI));
  CHECK(result.records[6].line == 10);  // after a // comment
  CHECK(result.records[6].frame.flags == FLAG_ERROR);
  CHECK(result.records[7].direction == 'R');
  CHECK(result.records[8].direction == 'T');
  CHECK(result.records[9].frame.timestampNs == 1436509052123456789);
  CHECK(result.lineCount == 13);
}

TEST_CASE("reader returns every frame of the candump console fixture") {
  const auto result = readFixture("candump_console.log");

  CHECK(result.errorCount == 0);
  REQUIRE(result.records.size() == 8);
  CHECK_FALSE(result.records[0].hasTime);
  CHECK(result.records[2].frame.flags == FLAG_RTR);
  CHECK(result.records[2].timeSeconds == 0.0);
  CHECK(result.records[2].hasTime);
  CHECK(result.records[3].frame.length == 12);
  CHECK(result.records[4].frame.flags == (FLAG_FD | FLAG_BRS | FLAG_ESI));
  CHECK(result.records[6].frame.flags == FLAG_ERROR);
  CHECK(result.records[7].line == 9);
}

TEST_CASE("malformed lines are reported with line, column and reason and reading carries on") {
  const auto result = readFixture("candump_malformed.log");

  REQUIRE(result.records.size() == 2);
  CHECK(result.records[0].line == 1);
  CHECK(result.records[1].line == 10);
  CHECK(payloadOf(result.records[1].frame) == Bytes{0x33});
  CHECK(result.errorCount == 8);
  REQUIRE(result.errors.size() == 8);
  const std::string file = openvcu::can::test::LOG_FIXTURE_DIR + "candump_malformed.log";
  CHECK(result.errors[0].toString() == file + ":2:23: odd number of hex digits in data");
  CHECK(result.errors[1].toString() == file + ":3:17: data length 9 exceeds 8 for a classic frame");
  CHECK(result.errors[2].toString() == file + ":4:17: standard identifier 0x800 exceeds 0x7FF");
  CHECK(result.errors[3].toString() == file + ":5:23: invalid hex digit 'G' in data");
  CHECK(result.errors[4].message == "data length 9 is not a valid CAN FD length (0-8, 12, 16, 20, 24, 32, 48, 64)");
  CHECK(result.errors[5].toString() == file + ":7:16: data length 9 exceeds 8 for a classic frame");
  CHECK(result.errors[6].location.line == 8);
  CHECK(result.errors[6].message == "invalid CAN identifier 'ERROR' (expected 3 or 8 hex digits)");
  CHECK(result.errors[7].toString() == file + ":9:10: expected ')' after the timestamp");
}

TEST_CASE("lastError keeps the most recent problem and next never throws") {
  std::istringstream input("(1.0) can0 123#1\n(1.0) can0 123#11\n");
  LogReader sut(input, "bus.log");

  const auto maybeRecord = sut.next();

  REQUIRE(maybeRecord.has_value());
  CHECK(maybeRecord->line == 2);
  CHECK(sut.errorCount() == 1);
  REQUIRE(sut.lastError().has_value());
  CHECK(sut.lastError()->toString() == "bus.log:1:16: odd number of hex digits in data");
  CHECK_FALSE(sut.next().has_value());
  CHECK(sut.recordCount() == 1);
}

TEST_CASE("CRLF line endings and a missing final newline are read") {
  const auto result = readFixture("candump_crlf_no_final_newline.log");

  CHECK(result.errorCount == 0);
  REQUIRE(result.records.size() == 3);
  CHECK(payloadOf(result.records[0].frame) == Bytes{1, 2});
  CHECK(payloadOf(result.records[1].frame) == Bytes{0xAA, 0xBB});
  CHECK(result.records[1].line == 3);
  CHECK(result.records[2].frame.id == 0x456);
  CHECK(payloadOf(result.records[2].frame) == Bytes{3});
  CHECK(result.records[2].line == 4);
}

TEST_CASE("empty input and comment-only input give no frames and no errors") {
  CHECK(readText("").records.empty());
  const auto result = readText("\n   \n# candump\n// notes\r\n\t\n");
  CHECK(result.records.empty());
  CHECK(result.errorCount == 0);
  CHECK(result.lineCount == 5);
}

TEST_CASE("a line longer than the limit is reported and the next line is read") {
  const std::string longLine = "(1.0) can0 123#" + std::string(LogReader::MAX_LINE_LENGTH * 40, 'A');
  const auto result = readText(longLine + "\n(2.0) can0 124#11\n" + longLine);

  REQUIRE(result.records.size() == 1);
  CHECK(result.records[0].line == 2);
  REQUIRE(result.errors.size() == 2);
  CHECK(result.errors[0].location.line == 1);
  CHECK(result.errors[0].message == "line longer than 4096 characters");
  CHECK(result.errors[1].location.line == 3);
}

TEST_CASE("many lines stream through a constant buffer with correct line numbers") {
  constexpr int LINE_COUNT = 20000;
  std::string text;
  for (int i = 0; i < LINE_COUNT; ++i) text += "(1.000000) can0 18FEF100#0102030405060708\n";

  const auto result = readText(text);

  REQUIRE(result.records.size() == LINE_COUNT);
  CHECK(result.records.back().line == LINE_COUNT);
  CHECK(result.errorCount == 0);
}

TEST_CASE("channel view stays valid until the next call, also after moving the reader") {
  std::istringstream input("(1.0) vcan7 123#11\n(1.0) can9 123#11\n");
  LogReader first(input);
  const auto maybeRecord = first.next();
  REQUIRE(maybeRecord.has_value());

  LogReader sut(std::move(first));

  CHECK(maybeRecord->channel == "vcan7");
  const auto second = sut.next();
  REQUIRE(second.has_value());
  CHECK(second->channel == "can9");
}

TEST_CASE("opening a missing file fails with the file name and the reason") {
  const auto openResult = LogReader::open(openvcu::can::test::LOG_FIXTURE_DIR + "does_not_exist.log");

  REQUIRE_FALSE(openResult.ok());
  CHECK(openResult.error().location.file == openvcu::can::test::LOG_FIXTURE_DIR + "does_not_exist.log");
  CHECK(openResult.error().message.find("cannot open log") == 0);
}

TEST_CASE("format can be forced and Auto stays undecided until a significant line") {
  std::istringstream input("// only a comment\n");
  LogReader sut(input);
  CHECK_FALSE(sut.next().has_value());
  CHECK(sut.format() == LogFormat::Auto);

  const auto forced = readText("  0.5 1  123  Rx d 1 AA\n", LogFormat::VectorAsc);
  REQUIRE(forced.records.size() == 1);
  CHECK(forced.records[0].frame.timestampNs == 500000000);
}

TEST_CASE("binary garbage produces errors, not frames or crashes") {
  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage += static_cast<char>((i * 37) % 256);

  const auto result = readText(garbage);

  CHECK(result.records.empty());
  CHECK(result.errorCount > 0);
}
