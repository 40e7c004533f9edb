// candump line formats: -L (compact) and the console formats (default, -ta/-td/-tz/-tA, -x, -a, -e).

#include <doctest/doctest.h>

#include "log_test_support.hpp"

using namespace openvcu::can;
using openvcu::can::test::payloadOf;
using openvcu::can::test::readText;

namespace {
using Bytes = std::vector<std::uint8_t>;
constexpr std::int64_t EPOCH_NS = 1436509052249713000;  // (1436509052.249713)
constexpr std::uint32_t J1939_EEC1_ID = 0x18FEF100;
}  // namespace

TEST_CASE("candump -L extended data frame is read with its full-precision timestamp") {
  const auto result = readText("(1436509052.249713) can0 18FEF100#0102030405060708\n");

  REQUIRE(result.records.size() == 1);
  const auto& record = result.records[0];
  CHECK(record.frame.id == J1939_EEC1_ID);
  CHECK(record.frame.flags == FLAG_EXTENDED);
  CHECK(payloadOf(record.frame) == Bytes{1, 2, 3, 4, 5, 6, 7, 8});
  CHECK(record.frame.timestampNs == EPOCH_NS);
  CHECK(record.timeSeconds == doctest::Approx(1436509052.249713).epsilon(1e-15));
  CHECK(record.hasTime);
  CHECK(record.channel == "can0");
  CHECK(record.line == 1);
  CHECK(record.direction == 0);
  CHECK(result.errorCount == 0);
}

TEST_CASE("candump -L timestamps keep nanoseconds and never go through a double") {
  const auto result = readText(
      "(1436509052.123456789) can0 001#00\n(1700000000.1) can0 001#00\n"
      "(9.0000000019) can0 001#00\n");

  REQUIRE(result.records.size() == 3);
  CHECK(result.records[0].frame.timestampNs == 1436509052123456789);
  CHECK(result.records[1].frame.timestampNs == 1700000000100000000);
  CHECK(result.records[2].frame.timestampNs == 9000000001);  // digits past the ninth are truncated
}

TEST_CASE("candump -L standard id has three digits and extended ids more") {
  const auto result = readText("(0.1) can0 7FF#\n(0.2) can0 00000123#11\n(0.3) can0 1FFFFFFF#\n");

  REQUIRE(result.records.size() == 3);
  CHECK(result.records[0].frame.id == 0x7FF);
  CHECK_FALSE(result.records[0].frame.extended());
  CHECK(result.records[0].frame.length == 0);
  CHECK(result.records[1].frame.id == 0x123);
  CHECK(result.records[1].frame.extended());
  CHECK(result.records[2].frame.id == EXTENDED_ID_MASK);
}

TEST_CASE("candump -L CAN FD frame carries BRS and ESI from the flags digit") {
  const auto result = readText(
      "(0.1) can0 123##1DEADBEEF\n(0.2) can0 123##2\n"
      "(0.3) can0 18DAF100##3000102030405060708090A0B\n");

  REQUIRE(result.records.size() == 3);
  CHECK(result.records[0].frame.flags == (FLAG_FD | FLAG_BRS));
  CHECK(payloadOf(result.records[0].frame) == Bytes{0xDE, 0xAD, 0xBE, 0xEF});
  CHECK(result.records[1].frame.flags == (FLAG_FD | FLAG_ESI));
  CHECK(result.records[1].frame.length == 0);
  CHECK(result.records[2].frame.flags == (FLAG_EXTENDED | FLAG_FD | FLAG_BRS | FLAG_ESI));
  CHECK(result.records[2].frame.length == 12);
  CHECK(result.records[2].frame.data[11] == 0x0B);
}

TEST_CASE("candump -L remote request has an optional length digit") {
  const auto result = readText("(0.1) can0 123#R\n(0.2) can0 123#R5\n(0.3) can0 12345678#r\n");

  REQUIRE(result.records.size() == 3);
  CHECK(result.records[0].frame.flags == FLAG_RTR);
  CHECK(result.records[0].frame.length == 0);
  CHECK(result.records[1].frame.length == 5);
  CHECK(result.records[2].frame.flags == (FLAG_RTR | FLAG_EXTENDED));
}

TEST_CASE("candump -L error frame keeps the error class as id and its data") {
  const auto result = readText("(0.1) can0 20000004#0004000000000000\n");

  REQUIRE(result.records.size() == 1);
  CHECK(result.records[0].frame.flags == FLAG_ERROR);
  CHECK(result.records[0].frame.id == 0x4);  // CAN_ERR_CRTL: controller problem
  CHECK(payloadOf(result.records[0].frame) == Bytes{0, 4, 0, 0, 0, 0, 0, 0});
}

TEST_CASE("candump -L direction suffix, byte separators and len8_dlc suffix are accepted") {
  const auto result = readText(
      "(0.1) can0 123#AA R\n(0.2) can0 123#BB T\n(0.3) can0 123#11.22.33\n"
      "(0.4) can0 123#1122334455667788_9\n");

  REQUIRE(result.records.size() == 4);
  CHECK(result.records[0].direction == 'R');
  CHECK(result.records[1].direction == 'T');
  CHECK(payloadOf(result.records[2].frame) == Bytes{0x11, 0x22, 0x33});
  CHECK(result.records[3].frame.length == 8);
  CHECK(result.errorCount == 0);
}

TEST_CASE("candump -L line without timestamp has no time") {
  const auto result = readText("can0 123#11\n");

  REQUIRE(result.records.size() == 1);
  CHECK_FALSE(result.records[0].hasTime);
  CHECK(result.records[0].frame.timestampNs == 0);
}

TEST_CASE("candump default format without timestamp is read") {
  const auto result = readText("  can0  18FEF100   [8]  01 02 03 04 05 06 07 08\n");

  REQUIRE(result.records.size() == 1);
  CHECK(result.records[0].frame.id == J1939_EEC1_ID);
  CHECK(result.records[0].frame.extended());
  CHECK(payloadOf(result.records[0].frame) == Bytes{1, 2, 3, 4, 5, 6, 7, 8});
  CHECK_FALSE(result.records[0].hasTime);
  CHECK(result.records[0].channel == "can0");
}

TEST_CASE("candump -ta, -td and -tz timestamps are read as written") {
  const auto result = readText(
      " (1436509052.249713)  can0  123   [2]  11 22\n"
      " (002.047817)  vcan0  064   [1]  F0\n");

  REQUIRE(result.records.size() == 2);
  CHECK(result.records[0].frame.timestampNs == EPOCH_NS);
  CHECK(result.records[1].frame.timestampNs == 2047817000);
  CHECK(result.records[1].timeSeconds == doctest::Approx(2.047817));
}

TEST_CASE("candump -tA date timestamp is read as UTC") {
  const auto result = readText(" (2015-07-10 08:17:32.249713)  can0  123   [1]  01\n");

  REQUIRE(result.records.size() == 1);
  CHECK(result.records[0].frame.timestampNs == 1436516252249713000);
}

TEST_CASE("candump console CAN FD frame has a two-digit length") {
  const auto result = readText(
      "  can0  456  [12]  00 11 22 33 44 55 66 77 88 99 AA BB\n"
      "  can0  456  [08]  01 02 03 04 05 06 07 08\n");

  REQUIRE(result.records.size() == 2);
  CHECK(result.records[0].frame.flags == FLAG_FD);
  CHECK(result.records[0].frame.length == 12);
  CHECK(result.records[0].frame.data[11] == 0xBB);
  CHECK(result.records[1].frame.flags == FLAG_FD);
  CHECK(result.records[1].frame.length == 8);
}

TEST_CASE("candump -x direction and BRS/ESI marks are read") {
  const auto result = readText(
      " (0.1)  can0  RX B E  456  [08]  01 02 03 04 05 06 07 08\n"
      " (0.2)  can0  TX - -  123   [1]  41\n");

  REQUIRE(result.records.size() == 2);
  CHECK(result.records[0].direction == 'R');
  CHECK(result.records[0].frame.flags == (FLAG_FD | FLAG_BRS | FLAG_ESI));
  CHECK(result.records[1].direction == 'T');
  CHECK(result.records[1].frame.flags == 0);
}

TEST_CASE("candump console remote request, ASCII column and ERRORFRAME are read") {
  const auto result = readText(
      "  can0  123   [3]  remote request\n"
      "  can1  123   [8]  31 30 30 2E 35 20 46 4D   '100.5 FM'\n"
      "  can0  20000004   [8]  00 04 00 00 00 00 00 00   ERRORFRAME\n"
      "\tcontroller-problem{rx-error-warning}\n"
      "  can0  00000123   [0]\n");

  REQUIRE(result.records.size() == 4);
  CHECK(result.records[0].frame.flags == FLAG_RTR);
  CHECK(result.records[0].frame.length == 3);
  CHECK(payloadOf(result.records[1].frame) == Bytes{0x31, 0x30, 0x30, 0x2E, 0x35, 0x20, 0x46, 0x4D});
  CHECK(result.records[2].frame.flags == FLAG_ERROR);
  CHECK(result.records[2].frame.id == 0x4);
  CHECK(result.records[2].frame.data[1] == 0x04);
  CHECK(result.records[3].frame.extended());
  CHECK(result.records[3].line == 5);
  CHECK(result.errorCount == 0);  // the -e description line belongs to the error frame
}

TEST_CASE("candump console line with more bytes than its length is rejected") {
  const auto result = readText("  can0  123   [2]  11 22 33\n");

  CHECK(result.records.empty());
  REQUIRE(result.errors.size() == 1);
  CHECK(result.errors[0].message == "more data bytes than the length in brackets says (2)");
  CHECK(result.errors[0].location.column == 26);
}
