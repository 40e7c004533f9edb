// Vector ASC logs: header state, classic, CAN FD, remote and error frames, skipped events.

#include <doctest/doctest.h>

#include "skip.hpp"

#include <filesystem>
#include <string>

#include "log_test_support.hpp"

using namespace openvcu::can;
using openvcu::can::test::payloadOf;
using openvcu::can::test::readAll;
using openvcu::can::test::readFixture;
using openvcu::can::test::readText;

namespace {
using Bytes = std::vector<std::uint8_t>;
constexpr std::int64_t MARCH_1_2024_NS = 1709251200LL * 1'000'000'000;  // Begin Triggerblock date
}  // namespace

TEST_CASE("ASC fixture gives classic, remote, error and CAN FD frames and skips events") {
  const auto result = readFixture("vector.asc");

  CHECK(result.format == LogFormat::VectorAsc);
  REQUIRE(result.records.size() == 8);
  const auto& eec1 = result.records[0];
  CHECK(eec1.line == 8);
  CHECK(eec1.frame.id == 0x18FEF100);
  CHECK(eec1.frame.flags == FLAG_EXTENDED);
  CHECK(payloadOf(eec1.frame) == Bytes{1, 2, 3, 4, 5, 6, 7, 8});
  CHECK(eec1.frame.timestampNs == MARCH_1_2024_NS + 1234000);
  CHECK(eec1.timeSeconds == doctest::Approx(0.001234));
  CHECK(eec1.channel == "1");
  CHECK(eec1.direction == 'R');

  CHECK(result.records[1].direction == 'T');
  CHECK(result.records[1].channel == "2");
  CHECK(result.records[2].frame.flags == FLAG_RTR);
  CHECK(result.records[2].frame.length == 0);
  CHECK(result.records[3].frame.length == 5);
  CHECK(result.records[4].frame.flags == FLAG_ERROR);

  const auto& fd = result.records[5];
  CHECK(fd.frame.flags == (FLAG_FD | FLAG_BRS));
  CHECK(fd.frame.id == 0x456);
  CHECK(fd.frame.length == 12);
  CHECK(fd.frame.data[11] == 0xBB);
  CHECK(result.records[6].frame.flags == (FLAG_EXTENDED | FLAG_FD | FLAG_ESI));
  CHECK(result.records[6].frame.id == 0x1ABCDEF0);
  CHECK(result.records[7].frame.length == 8);  // DLC F on a classic frame carries 8 bytes

  REQUIRE(result.errors.size() == 1);
  CHECK(result.errors[0].location.line == 16);
  CHECK(result.errors[0].message == "expected 8 data bytes, found 2");
}

TEST_CASE("ASC is detected from its header lines on a stream") {
  const auto result = readText(
      "date Tue May 27 04:09:35.000 pm 2014\nbase hex  timestamps absolute\n"
      "   0.019968 1  64              Rx   d 4 64 00 00 00\n");

  CHECK(result.format == LogFormat::VectorAsc);
  REQUIRE(result.records.size() == 1);
  CHECK(result.records[0].frame.timestampNs == 1401206975LL * 1'000'000'000 + 19968000);
  CHECK(payloadOf(result.records[0].frame) == Bytes{0x64, 0, 0, 0});
}

TEST_CASE("ASC relative timestamps accumulate and decimal base reads decimal ids") {
  const auto result = readText(
      "base dec  timestamps relative\n"
      "   1.5 1  100  Rx   d 2 10 255\n"
      "   0.25 1  Statistic: D 0\n"
      "   0.25 1  101  Rx   d 1 7\n",
      LogFormat::VectorAsc);

  REQUIRE(result.records.size() == 2);
  CHECK(result.records[0].frame.id == 100);
  CHECK(payloadOf(result.records[0].frame) == Bytes{10, 255});
  CHECK(result.records[1].frame.timestampNs == 2000000000);
  CHECK(result.records[1].timeSeconds == doctest::Approx(2.0));
}

TEST_CASE("ASC German month names and remote CANFD lines are understood") {
  const auto result = readText(
      "date Mi Okt 4 10:00:00.500 2023\n"
      "  1.0 CANFD   3 Tx     50005x      0 1 5 0 140000 73 200050 7a60\n");

  REQUIRE(result.records.size() == 1);
  CHECK(result.records[0].frame.flags == (FLAG_EXTENDED | FLAG_RTR));
  CHECK(result.records[0].frame.length == 5);
  CHECK(result.records[0].frame.timestampNs == 1696413601500000000);
}

TEST_CASE("ASC lines that are neither headers nor events are reported") {
  const auto result = readText("date Fri Mar 1 00:00:00.000 2024\nsomething odd\n  0.1 1 123 Rx x\n");

  CHECK(result.records.empty());
  REQUIRE(result.errors.size() == 2);
  CHECK(result.errors[0].message == "unrecognised line in an ASC log ('something')");
  CHECK(result.errors[1].message == "expected 'd' or 'r' after Rx, found 'x'");
}

// Public python-can ASC logs from the team kit (not copied into the repository).
TEST_CASE("python-can ASC corpus files are read without unexpected errors") {
  const std::filesystem::path folder = OPENVCU_TEAM_KIT "/corpus/logs/python-can";
  if (!std::filesystem::is_directory(folder)) {
    OPENVCU_SKIP("skipped: " << folder.string() << " not found (the team kit is not beside the repository)");
  }
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().extension() != ".asc") continue;
    auto openResult = LogReader::open(entry.path().string());
    REQUIRE(openResult.ok());
    const auto result = readAll(*openResult);
    ++files;
    INFO(entry.path().filename().string());
    // single_frame.asc writes a 64-byte frame as a classic "d 40" line: rejected on purpose.
    const std::size_t expectedErrors = entry.path().filename() == "single_frame.asc" ? 1 : 0;
    CHECK(result.errors.size() == expectedErrors);
    for (const auto& record : result.records) CHECK(record.frame.length <= MAX_DATA_LENGTH);
  }
  MESSAGE("read " << files << " python-can ASC files");
}
