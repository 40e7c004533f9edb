// cantools' candump line cases (team kit corpus, not copied into the repository) checked
// against LogReader. Differences in policy, decided on purpose:
//  - error frames: cantools drops them ("none"); openvcu returns them with FLAG_ERROR, so
//    "none" means "no data or remote frame".
//  - a length that is neither classic (0-8) nor a CAN FD length ("[10]") is rejected.
//  - PEAK TRC lines (test_pcan_*) are another format: they must be rejected, not misread.

#include <doctest/doctest.h>

#include "skip.hpp"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "log_test_support.hpp"

using namespace openvcu::can;
using nlohmann::json;

namespace {

const std::string CORPUS = OPENVCU_TEAM_KIT "/corpus/logs/cantools_logreader_cases.jsonl";

std::string hexOf(const Frame& frame) {
  static constexpr char DIGITS[] = "0123456789abcdef";
  std::string text;
  for (std::size_t i = 0; i < frame.length; ++i) {
    text += DIGITS[frame.data[i] >> 4];
    text += DIGITS[frame.data[i] & 0xF];
  }
  return text;
}

/// "bytes(range(8))" is how the corpus writes 00 01 .. 07.
std::string expectedHex(const std::string& data) {
  if (data == "bytes(range(8))") return "0001020304050607";
  return data;
}

bool isValidLength(std::size_t length) {
  return length <= 8 || length == 12 || length == 16 || length == 20 || length == 24 || length == 32 || length == 48 ||
         length == 64;
}

/// Broken-down civil time of `timestampNs` shifted by `offsetHours` (the corpus' tzinfo).
struct Civil {
  int year;
  unsigned month, day;
  long hour, minute, second, microsecond;
};
Civil civilOf(std::int64_t timestampNs, int offsetHours) {
  using namespace std::chrono;
  const sys_time<nanoseconds> time{nanoseconds{timestampNs + std::int64_t{offsetHours} * 3'600'000'000'000}};
  const auto day = floor<days>(time);
  const year_month_day date{day};
  const hh_mm_ss clock{floor<microseconds>(time - day)};
  return {int(date.year()),
          unsigned(date.month()),
          unsigned(date.day()),
          clock.hours().count(),
          clock.minutes().count(),
          clock.seconds().count(),
          long(clock.subseconds().count())};
}

/// How a case was checked, for the summary line.
struct Tally {
  std::size_t frames{}, rejectedOtherFormat{}, noFrame{}, parsesOnly{}, rejectedLength{};
};

void checkCase(const json& testCase, Tally& tally) {
  const std::string name = testCase.at("test");
  const std::string line = testCase.at("line");
  const json& expect = testCase.at("expect");
  INFO(name << ": '" << line << "'");
  const auto result = openvcu::can::test::readText(line + "\n");
  const bool gotDataFrame = !result.records.empty() && (result.records[0].frame.flags & FLAG_ERROR) == 0;

  if (name.rfind("test_pcan", 0) == 0 || expect.value("none", false)) {
    CHECK_FALSE(gotDataFrame);
    ++(name.rfind("test_pcan", 0) == 0 ? tally.rejectedOtherFormat : tally.noFrame);
    return;
  }
  if (expect.empty()) {  // the case only asks that the line parses
    CHECK(gotDataFrame);
    ++tally.parsesOnly;
    return;
  }
  const std::string data = expectedHex(expect.value("data", std::string()));
  if (!isValidLength(data.size() / 2)) {  // policy: invalid lengths are rejected
    CHECK(result.records.empty());
    CHECK(result.errorCount == 1);
    ++tally.rejectedLength;
    return;
  }
  ++tally.frames;
  REQUIRE(gotDataFrame);
  CHECK(result.errorCount == 0);
  const auto& record = result.records[0];
  CHECK(record.channel == expect.at("channel").get<std::string>());
  CHECK(record.frame.id == expect.at("frame_id").get<std::uint32_t>());
  CHECK(hexOf(record.frame) == data);
  if (expect.contains("is_extended_frame")) CHECK(record.frame.extended() == expect["is_extended_frame"].get<bool>());
  if (expect.contains("is_remote_frame")) {
    CHECK(((record.frame.flags & FLAG_RTR) != 0) == expect["is_remote_frame"].get<bool>());
  }
  const std::string format = expect.value("timestamp_format", std::string());
  if (!format.empty()) CHECK(record.hasTime == (format.find("MISSING") == std::string::npos));
  if (expect.contains("timestamp.seconds")) {  // a relative time (Python timedelta)
    const auto micros = static_cast<std::int64_t>(expect["timestamp.seconds"].get<double>()) * 1'000'000 +
                        expect.value("timestamp.microseconds", std::int64_t{0});
    CHECK(record.frame.timestampNs == micros * 1000);
  }
  if (expect.contains("timestamp.year")) {  // an absolute time (Python datetime)
    const json tz = expect.value("timestamp.tzinfo", json());
    const int offsetHours = tz.is_string() && tz.get<std::string>() == "utc_plus(2)" ? 2 : 0;
    const Civil civil = civilOf(record.frame.timestampNs, offsetHours);
    CHECK(civil.year == expect["timestamp.year"].get<int>());
    CHECK(civil.month == expect["timestamp.month"].get<unsigned>());
    CHECK(civil.day == expect["timestamp.day"].get<unsigned>());
    CHECK(civil.hour == expect["timestamp.hour"].get<long>());
    CHECK(civil.minute == expect["timestamp.minute"].get<long>());
    CHECK(civil.second == expect["timestamp.second"].get<long>());
    if (expect.contains("timestamp.microsecond"))
      CHECK(civil.microsecond == expect["timestamp.microsecond"].get<long>());
  }
}

}  // namespace

TEST_CASE("every cantools candump case the reader can express parses as cantools expects") {
  std::ifstream corpus(CORPUS);
  if (!corpus) {
    OPENVCU_SKIP("skipped: " << CORPUS << " not found (the team kit is not beside the repository)");
  }
  std::size_t cases = 0;
  Tally tally;
  std::string text;
  while (std::getline(corpus, text)) {
    if (text.empty()) continue;
    checkCase(json::parse(text), tally);
    ++cases;
  }
  CHECK(cases > 0);
  MESSAGE("checked " << cases << " cantools cases: " << tally.frames << " frames field by field, " << tally.noFrame
                     << " without a data frame, " << tally.parsesOnly << " parse-only, " << tally.rejectedLength
                     << " rejected for an invalid length, " << tally.rejectedOtherFormat << " PEAK TRC lines rejected");
}
