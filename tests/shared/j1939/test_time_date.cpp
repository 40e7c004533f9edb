#include "openvcu/j1939/time_date.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cstdint>

using namespace openvcu::j1939;

namespace {

// 2026-11-21 13:45:30.75 UTC, worked by hand:
//   days 1970-01-01 .. 2026-01-01 = 56 * 365 + 14 leap days (1972 .. 2024) = 20454
//   + Jan..Oct 2026 (304) + 20 = 20778 days
//   20778 * 86400 + 13 * 3600 + 45 * 60 + 30 = 1795268730 s (Python's datetime agrees)
// bytes: 30.75 s x 4 = 123 = 0x7B, 45 min = 0x2D, 13 h = 0x0D, month 11 = 0x0B,
//        day 21 x 4 = 84 = 0x54, 2026 - 1985 = 41 = 0x29, offsets 0 + 125 = 0x7D, 0x7D
constexpr std::int64_t FIXED_UNIX_SECONDS = 1'795'268'730;
constexpr std::uint32_t THREE_QUARTERS_NS = 750'000'000;
constexpr TimeDatePayload FIXED_BYTES{0x7B, 0x2D, 0x0D, 0x0B, 0x54, 0x29, 0x7D, 0x7D};
constexpr UtcInstant FIXED_INSTANT{FIXED_UNIX_SECONDS, THREE_QUARTERS_NS, 0, 0};

constexpr std::int64_t FIRST_ENCODABLE_SECOND = 473'385'600;   // 1985-01-01 00:00:00
constexpr std::int64_t LAST_ENCODABLE_SECOND = 8'394'105'599;  // 2235-12-31 23:59:59
constexpr std::int64_t SECONDS_PER_DAY = 86'400;
constexpr TimeDatePayload ALL_NOT_AVAILABLE{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};

}  // namespace

TEST_CASE("Time/Date of 2026-11-21 13:45:30.75 UTC encodes to the hand-computed bytes") {
  const std::optional<TimeDatePayload> maybeSut = encodeTimeDate(FIXED_INSTANT);

  REQUIRE(maybeSut);
  CHECK(*maybeSut == FIXED_BYTES);
}

TEST_CASE("Time/Date decodes the hand-computed bytes back to the fixed instant") {
  const std::optional<TimeDate> maybeSut = decodeTimeDate(FIXED_BYTES);

  REQUIRE(maybeSut);
  CHECK(maybeSut->quarterSeconds == 123);
  CHECK(maybeSut->minutes == 45);
  CHECK(maybeSut->hours == 13);
  CHECK(maybeSut->month == 11);
  CHECK(maybeSut->day == 21);
  CHECK(maybeSut->year == 2026);
  CHECK(maybeSut->localMinuteOffset == 0);
  CHECK(maybeSut->localHourOffset == 0);
  CHECK(maybeSut->toUtcInstant() == FIXED_INSTANT);
}

TEST_CASE("Time/Date carries positive and negative local offsets biased by 125") {
  constexpr UtcInstant INDIA{FIXED_UNIX_SECONDS, 0, 30, 5};           // UTC+05:30
  constexpr UtcInstant NEWFOUNDLAND{FIXED_UNIX_SECONDS, 0, -30, -3};  // UTC-03:30

  const std::optional<TimeDatePayload> maybeIndia = encodeTimeDate(INDIA);
  const std::optional<TimeDatePayload> maybeNewfoundland = encodeTimeDate(NEWFOUNDLAND);

  REQUIRE(maybeIndia);
  REQUIRE(maybeNewfoundland);
  CHECK((*maybeIndia)[6] == 155);         // 30 + 125
  CHECK((*maybeIndia)[7] == 130);         // 5 + 125
  CHECK((*maybeNewfoundland)[6] == 95);   // -30 + 125
  CHECK((*maybeNewfoundland)[7] == 122);  // -3 + 125
  CHECK(decodeTimeDate(*maybeNewfoundland)->toUtcInstant() == NEWFOUNDLAND);
}

TEST_CASE("Time/Date truncates the fraction to quarter seconds") {
  constexpr std::uint32_t ALMOST_ONE_SECOND_NS = 999'999'999;
  constexpr std::uint32_t JUST_BELOW_QUARTER_NS = 249'999'999;

  const auto maybeLate = encodeTimeDate({FIXED_UNIX_SECONDS, ALMOST_ONE_SECOND_NS, 0, 0});
  const auto maybeEarly = encodeTimeDate({FIXED_UNIX_SECONDS, JUST_BELOW_QUARTER_NS, 0, 0});

  REQUIRE(maybeLate);
  REQUIRE(maybeEarly);
  CHECK((*maybeLate)[0] == 123);   // 30 s x 4 + 3
  CHECK((*maybeEarly)[0] == 120);  // 30 s x 4 + 0
}

TEST_CASE("Time/Date covers exactly the years 1985 to 2235") {
  CHECK(encodeTimeDate({FIRST_ENCODABLE_SECOND, 0, 0, 0}) ==
        TimeDatePayload{0, 0, 0, 1, 4, 0, 125, 125});
  CHECK(encodeTimeDate({LAST_ENCODABLE_SECOND, 750'000'000, 0, 0}) ==
        TimeDatePayload{239, 59, 23, 12, 124, 250, 125, 125});
  CHECK_FALSE(encodeTimeDate({FIRST_ENCODABLE_SECOND - 1, 0, 0, 0}));
  CHECK_FALSE(encodeTimeDate({LAST_ENCODABLE_SECOND + 1, 0, 0, 0}));
  CHECK_FALSE(encodeTimeDate({0, 0, 0, 0}));  // 1970: a clock that was never set
  CHECK_FALSE(encodeTimeDate({-1, 0, 0, 0}));
}

TEST_CASE("Time/Date refuses an invalid fraction or offset") {
  CHECK_FALSE(encodeTimeDate({FIXED_UNIX_SECONDS, 1'000'000'000, 0, 0}));
  CHECK_FALSE(encodeTimeDate({FIXED_UNIX_SECONDS, 0, 60, 0}));
  CHECK_FALSE(encodeTimeDate({FIXED_UNIX_SECONDS, 0, 0, -24}));
}

TEST_CASE("Time/Date round-trips every 77777th second from 1985 to 2235") {
  constexpr std::int64_t STEP_SECONDS = 77'777;
  constexpr std::uint32_t QUARTER_NS = 250'000'000;
  int failures = 0;
  int samples = 0;

  for (std::int64_t second = FIRST_ENCODABLE_SECOND; second <= LAST_ENCODABLE_SECOND;
       second += STEP_SECONDS) {
    const UtcInstant instant{second, static_cast<std::uint32_t>(samples % 4) * QUARTER_NS,
                             static_cast<std::int8_t>(samples % 119 - 59),
                             static_cast<std::int8_t>(samples % 47 - 23)};
    const auto maybeBytes = encodeTimeDate(instant);
    const auto maybeDecoded = maybeBytes ? decodeTimeDate(*maybeBytes) : std::nullopt;
    if (!maybeDecoded || maybeDecoded->toUtcInstant() != instant) ++failures;
    ++samples;
  }

  CHECK(samples > 100'000);
  CHECK(failures == 0);
}

TEST_CASE("Time/Date reports 0xFB to 0xFF as not available") {
  const std::optional<TimeDate> maybeSut = decodeTimeDate(ALL_NOT_AVAILABLE);

  REQUIRE(maybeSut);
  CHECK(*maybeSut == TimeDate{});
  CHECK_FALSE(maybeSut->toUtcInstant());
  for (std::uint8_t raw = 0xFB; raw != 0; ++raw) {
    TimeDatePayload bytes = FIXED_BYTES;
    bytes[1] = raw;
    const auto maybeDecoded = decodeTimeDate(bytes);
    REQUIRE(maybeDecoded);
    CHECK_FALSE(maybeDecoded->minutes);
    CHECK(maybeDecoded->hours == 13);
  }
}

TEST_CASE("Time/Date treats month 0 and day 0 as null") {
  TimeDatePayload bytes = FIXED_BYTES;
  bytes[3] = 0;
  bytes[4] = 0;

  const std::optional<TimeDate> maybeSut = decodeTimeDate(bytes);

  REQUIRE(maybeSut);
  CHECK_FALSE(maybeSut->month);
  CHECK_FALSE(maybeSut->day);
  CHECK(maybeSut->year == 2026);
}

TEST_CASE("Time/Date rounds quarter days up so 1 to 4 is the first day") {
  constexpr std::array<std::uint8_t, 6> RAW_DAYS{1, 2, 3, 4, 5, 124};
  constexpr std::array<std::uint8_t, 6> EXPECTED_DAYS{1, 1, 1, 1, 2, 31};

  for (std::size_t i = 0; i < RAW_DAYS.size(); ++i) {
    TimeDatePayload bytes = FIXED_BYTES;
    bytes[4] = RAW_DAYS[i];
    const auto maybeSut = decodeTimeDate(bytes);
    REQUIRE(maybeSut);
    CHECK(maybeSut->day == EXPECTED_DAYS[i]);
  }
}

TEST_CASE("Time/Date rejects a frame with an out-of-range byte below 0xFB") {
  struct Corruption {
    std::size_t index;
    std::uint8_t raw;
  };
  constexpr std::array<Corruption, 5> CORRUPTIONS{{{0, 240}, {1, 60}, {2, 24}, {3, 13}, {4, 125}}};

  for (const Corruption corruption : CORRUPTIONS) {
    TimeDatePayload bytes = FIXED_BYTES;
    bytes[corruption.index] = corruption.raw;
    CHECK_FALSE(decodeTimeDate(bytes));
  }
}

TEST_CASE("Time/Date needs 8 bytes") {
  const std::span<const std::uint8_t> shortFrame{FIXED_BYTES.data(), 7};

  CHECK_FALSE(decodeTimeDate(shortFrame));
}

TEST_CASE("Time/Date gives no instant for a day that its month does not have") {
  TimeDatePayload bytes = FIXED_BYTES;
  bytes[3] = 2;       // February
  bytes[4] = 30 * 4;  // the 30th

  const std::optional<TimeDate> maybeSut = decodeTimeDate(bytes);

  REQUIRE(maybeSut);
  CHECK(maybeSut->day == 30);
  CHECK_FALSE(maybeSut->toUtcInstant());
}

TEST_CASE("civil date arithmetic walks day by day from 1900 to 2400 without a gap") {
  const std::int64_t firstDay = daysFromCivil(1900, 1, 1);
  const std::int64_t lastDay = daysFromCivil(2400, 12, 31);
  CivilDate expected{1900, 1, 1};
  int failures = 0;

  for (std::int64_t day = firstDay; day <= lastDay; ++day) {
    const CivilDate sut = civilFromDays(day);
    if (sut != expected || daysFromCivil(sut.year, sut.month, sut.day) != day) ++failures;
    // advance `expected` by one calendar day
    if (expected.day < daysInMonth(expected.year, expected.month)) {
      ++expected.day;
    } else if (expected.month < 12) {
      expected = {expected.year, static_cast<std::uint8_t>(expected.month + 1), 1};
    } else {
      expected = {expected.year + 1, 1, 1};
    }
  }

  CHECK(failures == 0);
  CHECK(lastDay - firstDay + 1 ==
        182'987);  // 501 x 365 + 122 leap days (1900, 2100, 2200, 2300 are not leap)
}

TEST_CASE("civil date arithmetic knows 2000 and 2028 are leap years and 1900 and 2100 are not") {
  CHECK(daysInMonth(2000, 2) == 29);
  CHECK(daysInMonth(2028, 2) == 29);
  CHECK(daysInMonth(1900, 2) == 28);
  CHECK(daysInMonth(2100, 2) == 28);
  CHECK(civilFromDays(1'835'481'599 / SECONDS_PER_DAY) == CivilDate{2028, 2, 29});
}
