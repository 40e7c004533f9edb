#include "openvcu/j1939/time_date.hpp"

namespace openvcu::j1939 {
namespace {

constexpr std::uint8_t FIRST_NOT_AVAILABLE = 0xFB;  // 0xFB..0xFF: not available / error
constexpr std::int64_t SECONDS_PER_DAY = 86'400;
constexpr std::int64_t SECONDS_PER_HOUR = 3'600;
constexpr std::int64_t SECONDS_PER_MINUTE = 60;
constexpr std::uint32_t NANOSECONDS_PER_SECOND = 1'000'000'000;
constexpr std::uint32_t NANOSECONDS_PER_QUARTER = 250'000'000;
constexpr std::uint8_t QUARTERS = 4;  // 0.25 s/bit and 0.25 day/bit
constexpr std::uint8_t MAX_QUARTER_SECONDS = 239;
constexpr std::uint8_t MAX_MINUTES = 59;
constexpr std::uint8_t MAX_HOURS = 23;
constexpr std::uint8_t MAX_MONTH = 12;
constexpr std::uint8_t MAX_QUARTER_DAYS = 124;  // day 31
constexpr std::int8_t MAX_LOCAL_MINUTE_OFFSET = 59;
constexpr std::int8_t MAX_LOCAL_HOUR_OFFSET = 23;

constexpr bool available(std::uint8_t raw) noexcept { return raw < FIRST_NOT_AVAILABLE; }

constexpr std::uint8_t toByte(std::int64_t value) noexcept {
  return static_cast<std::uint8_t>(value);
}

constexpr bool offsetsValid(std::int8_t minutes, std::int8_t hours) noexcept {
  return minutes >= -MAX_LOCAL_MINUTE_OFFSET && minutes <= MAX_LOCAL_MINUTE_OFFSET &&
         hours >= -MAX_LOCAL_HOUR_OFFSET && hours <= MAX_LOCAL_HOUR_OFFSET;
}

// A field whose byte may be not available, with the largest in-range raw value: empty
// optional for not available, false when the byte is corrupt.
template <typename T, typename Convert>
bool decodeField(std::uint8_t raw, std::uint8_t maxRaw, std::optional<T>& field,
                 Convert convert) noexcept {
  if (!available(raw)) return true;
  if (raw > maxRaw) return false;
  field = convert(raw);
  return true;
}

}  // namespace

std::optional<TimeDatePayload> encodeTimeDate(const UtcInstant& instant) noexcept {
  if (instant.nanoseconds >= NANOSECONDS_PER_SECOND) return std::nullopt;
  if (!offsetsValid(instant.localMinuteOffset, instant.localHourOffset)) return std::nullopt;
  const std::int64_t days = floorDivide(instant.unixSeconds, SECONDS_PER_DAY);
  const std::int64_t secondOfDay = instant.unixSeconds - days * SECONDS_PER_DAY;
  const CivilDate date = civilFromDays(days);
  if (date.year < TIME_DATE_FIRST_YEAR || date.year > TIME_DATE_LAST_YEAR) return std::nullopt;

  const std::int64_t seconds = secondOfDay % SECONDS_PER_MINUTE;
  const std::uint32_t quarter = instant.nanoseconds / NANOSECONDS_PER_QUARTER;
  return TimeDatePayload{toByte(seconds * QUARTERS + quarter),
                         toByte((secondOfDay / SECONDS_PER_MINUTE) % SECONDS_PER_MINUTE),
                         toByte(secondOfDay / SECONDS_PER_HOUR),
                         date.month,
                         toByte(date.day * QUARTERS),
                         toByte(date.year - TIME_DATE_FIRST_YEAR),
                         toByte(instant.localMinuteOffset + TIME_DATE_LOCAL_OFFSET),
                         toByte(instant.localHourOffset + TIME_DATE_LOCAL_OFFSET)};
}

std::optional<TimeDate> decodeTimeDate(std::span<const std::uint8_t> data) noexcept {
  if (data.size() < TIME_DATE_LENGTH) return std::nullopt;
  const auto same = [](std::uint8_t raw) { return raw; };
  const auto localOffset = [](std::uint8_t raw) {
    return static_cast<std::int8_t>(raw - TIME_DATE_LOCAL_OFFSET);
  };
  TimeDate timeDate;
  bool intact = decodeField(data[0], MAX_QUARTER_SECONDS, timeDate.quarterSeconds, same);
  intact = decodeField(data[1], MAX_MINUTES, timeDate.minutes, same) && intact;
  intact = decodeField(data[2], MAX_HOURS, timeDate.hours, same) && intact;
  if (data[3] != 0) intact = decodeField(data[3], MAX_MONTH, timeDate.month, same) && intact;
  if (data[4] != 0) {
    // 1..4 = day 1, 5..8 = day 2: round quarter days up.
    const auto quarterDays = [](std::uint8_t raw) {
      return static_cast<std::uint8_t>((raw + QUARTERS - 1) / QUARTERS);
    };
    intact = decodeField(data[4], MAX_QUARTER_DAYS, timeDate.day, quarterDays) && intact;
  }
  intact = decodeField(data[5], FIRST_NOT_AVAILABLE - 1, timeDate.year,
                       [](std::uint8_t raw) { return TIME_DATE_FIRST_YEAR + raw; }) &&
           intact;
  intact = decodeField(data[6], FIRST_NOT_AVAILABLE - 1, timeDate.localMinuteOffset, localOffset) &&
           intact;
  intact = decodeField(data[7], FIRST_NOT_AVAILABLE - 1, timeDate.localHourOffset, localOffset) &&
           intact;
  if (!intact) return std::nullopt;
  return timeDate;
}

std::optional<UtcInstant> TimeDate::toUtcInstant() const noexcept {
  if (!quarterSeconds || !minutes || !hours || !month || !day || !year || !localMinuteOffset ||
      !localHourOffset) {
    return std::nullopt;
  }
  if (*day > daysInMonth(*year, *month)) return std::nullopt;
  if (!offsetsValid(*localMinuteOffset, *localHourOffset)) return std::nullopt;
  UtcInstant instant;
  instant.unixSeconds = daysFromCivil(*year, *month, *day) * SECONDS_PER_DAY +
                        *hours * SECONDS_PER_HOUR + *minutes * SECONDS_PER_MINUTE +
                        *quarterSeconds / QUARTERS;
  instant.nanoseconds = (*quarterSeconds % QUARTERS) * NANOSECONDS_PER_QUARTER;
  instant.localMinuteOffset = *localMinuteOffset;
  instant.localHourOffset = *localHourOffset;
  return instant;
}

}  // namespace openvcu::j1939
