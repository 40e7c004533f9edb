#pragma once
// SAE J1939-71 Time/Date (PGN 65254), 8 bytes, UTC:
//
//   byte 0 seconds       0.25 s/bit    0..239 = 0..59.75 s
//   byte 1 minutes       1 min/bit     0..59
//   byte 2 hours         1 h/bit       0..23
//   byte 3 month         1/bit         1..12 (0 = null)
//   byte 4 day           0.25 day/bit  1..124; 1..4 = day 1, 5..8 = day 2 (0 = null)
//   byte 5 year          1/bit, +1985  0..250 = 1985..2235
//   byte 6 local minute offset, 1 min/bit, -125 offset
//   byte 7 local hour offset,   1 h/bit,   -125 offset
//   0xFB..0xFF in any byte: not available / error.
//
//   2026-11-21 13:45:30.75 UTC, offsets 0 -> 7B 2D 0D 0B 54 29 7D 7D
//
// Calendar arithmetic is plain proleptic Gregorian on POSIX seconds (no leap seconds), no
// locale or time-zone state.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_TIME_DATE = 0xFEE6;  ///< SAE J1939-71 PGN 65254 Time/Date
inline constexpr std::size_t TIME_DATE_LENGTH = 8;
inline constexpr std::int32_t TIME_DATE_FIRST_YEAR = 1985;   ///< year byte 0 (its offset)
inline constexpr std::int32_t TIME_DATE_LAST_YEAR = 2235;    ///< year byte 250 (0xfa)
inline constexpr std::int32_t TIME_DATE_LOCAL_OFFSET = 125;  ///< bias of both local offset bytes

using TimeDatePayload = std::array<std::uint8_t, TIME_DATE_LENGTH>;

/// A date in the proleptic Gregorian calendar.
struct CivilDate {
  std::int32_t year{1970};
  std::uint8_t month{1};  ///< 1..12
  std::uint8_t day{1};    ///< 1..31
  friend constexpr bool operator==(const CivilDate&, const CivilDate&) = default;
};

[[nodiscard]] constexpr bool isLeapYear(std::int64_t year) noexcept {
  return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
}

/// 28..31; 0 for a month outside 1..12.
[[nodiscard]] constexpr std::uint8_t daysInMonth(std::int64_t year, unsigned month) noexcept {
  constexpr std::array<std::uint8_t, 12> LENGTHS{31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (month < 1 || month > 12) return 0;
  return month == 2 && isLeapYear(year) ? 29 : LENGTHS[month - 1];
}

/// Rounds towards minus infinity (C++ division truncates towards zero).
[[nodiscard]] constexpr std::int64_t floorDivide(std::int64_t value,
                                                 std::int64_t divisor) noexcept {
  const std::int64_t quotient = value / divisor;
  return (value % divisor != 0 && (value < 0) != (divisor < 0)) ? quotient - 1 : quotient;
}

/// Days from 1970-01-01 to the given date (negative before it). 2026-11-21 -> 20778.
/// Valid for |year| < 10^9; month 1..12 and day 1..31 are the caller's to check.
[[nodiscard]] constexpr std::int64_t daysFromCivil(std::int64_t year, unsigned month,
                                                   unsigned day) noexcept {
  // Leap years in [1, y - 1]; floorDivide keeps the count right for years <= 0.
  const auto leapYearsBefore = [](std::int64_t y) {
    return floorDivide(y - 1, 4) - floorDivide(y - 1, 100) + floorDivide(y - 1, 400);
  };
  constexpr std::array<std::int64_t, 12> DAYS_BEFORE_MONTH{0,   31,  59,  90,  120, 151,
                                                           181, 212, 243, 273, 304, 334};
  const std::int64_t leapDay = month > 2 && isLeapYear(year) ? 1 : 0;
  return 365 * (year - 1970) + (leapYearsBefore(year) - leapYearsBefore(1970)) +
         DAYS_BEFORE_MONTH[(month - 1) % 12] + leapDay + static_cast<std::int64_t>(day) - 1;
}

/// The date `days` after 1970-01-01. 20778 -> 2026-11-21. Valid for years that fit int32.
[[nodiscard]] constexpr CivilDate civilFromDays(std::int64_t days) noexcept {
  // Estimate the year from the mean Gregorian year (146097 days per 400 years), then
  // correct the estimate by at most a step or two either way.
  std::int64_t year = 1970 + floorDivide(days * 400, 146097);
  while (daysFromCivil(year, 1, 1) > days) --year;
  while (daysFromCivil(year + 1, 1, 1) <= days) ++year;
  std::int64_t dayOfYear = days - daysFromCivil(year, 1, 1);
  unsigned month = 1;
  while (dayOfYear >= daysInMonth(year, month)) {
    dayOfYear -= daysInMonth(year, month);
    ++month;
  }
  return CivilDate{static_cast<std::int32_t>(year), static_cast<std::uint8_t>(month),
                   static_cast<std::uint8_t>(dayOfYear + 1)};
}

static_assert(daysFromCivil(1970, 1, 1) == 0);
static_assert(daysFromCivil(2026, 11, 21) == 20778);
static_assert(daysFromCivil(2000, 2, 29) == 11016);
static_assert(civilFromDays(20778) == CivilDate{2026, 11, 21});
static_assert(civilFromDays(-1) == CivilDate{1969, 12, 31});

/// The instant to send: POSIX time plus the sender's local offset (local = UTC + hours + minutes).
struct UtcInstant {
  std::int64_t unixSeconds{};       ///< seconds since 1970-01-01T00:00:00Z, no leap seconds
  std::uint32_t nanoseconds{};      ///< 0..999'999'999; the wire keeps quarter seconds
  std::int8_t localMinuteOffset{};  ///< -59..59
  std::int8_t localHourOffset{};    ///< -23..23
  friend constexpr bool operator==(const UtcInstant&, const UtcInstant&) = default;
};

/// The 8 Time/Date bytes; the fraction is truncated to quarter seconds. Empty when the year
/// is outside 1985..2235, nanoseconds exceed 999'999'999 or an offset is outside its range.
/// 1795268730 s + 750 ms, offsets 0 -> 7B 2D 0D 0B 54 29 7D 7D.
/// @note thread-safe and real-time safe.
[[nodiscard]] std::optional<TimeDatePayload> encodeTimeDate(const UtcInstant& instant) noexcept;

/// A received Time/Date; a field is empty when its byte says not available or error
/// (0xFB..0xFF) or, for month and day, null (0).
struct TimeDate {
  std::optional<std::uint8_t> quarterSeconds;    ///< 0..239 (seconds x 4)
  std::optional<std::uint8_t> minutes;           ///< 0..59
  std::optional<std::uint8_t> hours;             ///< 0..23
  std::optional<std::uint8_t> month;             ///< 1..12
  std::optional<std::uint8_t> day;               ///< 1..31 (quarter days rounded up, see top)
  std::optional<std::int32_t> year;              ///< 1985..2235
  std::optional<std::int8_t> localMinuteOffset;  ///< -125..125 as the wire allows
  std::optional<std::int8_t> localHourOffset;    ///< -125..125 as the wire allows

  /// The instant when every field is available, the day exists in its month and the
  /// offsets lie within UtcInstant's ranges; otherwise empty.
  [[nodiscard]] std::optional<UtcInstant> toUtcInstant() const noexcept;
  friend bool operator==(const TimeDate&, const TimeDate&) = default;
};

/// Time/Date bytes -> fields. Empty when fewer than 8 bytes arrive or a byte below 0xFB lies
/// outside its range (seconds > 239, minutes > 59, hours > 23, month > 12, day > 124):
/// such a frame is corrupt, not "not available".
/// 7B 2D 0D 0B 54 29 7D 7D -> 13:45:30.75, 2026-11-21, offsets 0.
/// @note thread-safe and real-time safe.
[[nodiscard]] std::optional<TimeDate> decodeTimeDate(std::span<const std::uint8_t> data) noexcept;

}  // namespace openvcu::j1939
