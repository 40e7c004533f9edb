#pragma once
// Private scanning helpers shared by the candump and ASC line parsers: a cursor over one
// line, hex/decimal digit tables and the per-line result type. Nothing here allocates.
//
// Why hand-written: a benchmark streams 1,000,000 lines; regex or iostream extraction
// per field costs 10-50x more than walking the characters once.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "openvcu/can/log_reader.hpp"

namespace openvcu::can::detail {

/// What a parser made of one line.
enum class LineResult : std::uint8_t {
  Frame,  ///< `record` holds a frame
  Skip,   ///< nothing to report (header, comment, non-frame event)
  Error,  ///< malformed; `LineError` says why
};

/// Why a line was rejected: a fixed buffer so that reporting needs no allocation here.
struct LineError {
  std::uint32_t column{};  ///< 1-based column of the offending text
  char message[160]{};
};

/// Hex digit value, or -1. Table-free switch: compilers turn it into a jump table.
constexpr int hexValue(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}
constexpr bool isDigit(char c) noexcept {
  return c >= '0' && c <= '9';
}
constexpr bool isSpace(char c) noexcept {
  return c == ' ' || c == '\t';
}
constexpr char toLower(char c) noexcept {
  return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
}
constexpr bool equalsIgnoreCase(std::string_view a, std::string_view b) noexcept {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (toLower(a[i]) != toLower(b[i])) return false;
  }
  return true;
}

/// The CAN FD payload lengths (ISO 11898-1:2015 DLC 0..15).
constexpr bool isValidFdLength(std::size_t length) noexcept {
  return length <= 8 || length == 12 || length == 16 || length == 20 || length == 24 || length == 32 || length == 48 ||
         length == 64;
}

/// Cursor over one line; `column()` is 1-based for error messages.
class Scanner {
 public:
  explicit constexpr Scanner(std::string_view line) noexcept
      : m_begin(line.data()), m_pos(line.data()), m_end(line.data() + line.size()) {}
  /// Scans `text`, a part of a line starting at `lineBegin` (columns count from there).
  constexpr Scanner(std::string_view text, const char* lineBegin) noexcept
      : m_begin(lineBegin), m_pos(text.data()), m_end(text.data() + text.size()) {}

  [[nodiscard]] constexpr bool atEnd() const noexcept { return m_pos == m_end; }
  [[nodiscard]] constexpr char peek() const noexcept { return m_pos == m_end ? '\0' : *m_pos; }
  [[nodiscard]] constexpr char peekAt(std::size_t offset) const noexcept {
    return offset < static_cast<std::size_t>(m_end - m_pos) ? m_pos[offset] : '\0';
  }
  [[nodiscard]] constexpr std::uint32_t column() const noexcept {
    return static_cast<std::uint32_t>(m_pos - m_begin) + 1;
  }
  [[nodiscard]] constexpr std::uint32_t columnOf(const char* at) const noexcept {
    return static_cast<std::uint32_t>(at - m_begin) + 1;
  }
  [[nodiscard]] constexpr const char* position() const noexcept { return m_pos; }
  /// Start of the line (column 1).
  [[nodiscard]] constexpr const char* origin() const noexcept { return m_begin; }
  [[nodiscard]] constexpr std::size_t remaining() const noexcept { return static_cast<std::size_t>(m_end - m_pos); }
  [[nodiscard]] constexpr std::string_view rest() const noexcept {
    return {m_pos, static_cast<std::size_t>(m_end - m_pos)};
  }
  constexpr void advance(std::size_t count = 1) noexcept {
    const auto left = static_cast<std::size_t>(m_end - m_pos);
    m_pos += count < left ? count : left;
  }
  constexpr bool consume(char c) noexcept {
    if (m_pos == m_end || *m_pos != c) return false;
    ++m_pos;
    return true;
  }
  constexpr void skipSpaces() noexcept {
    while (m_pos != m_end && isSpace(*m_pos)) ++m_pos;
  }
  /// The next run of non-blank characters (empty at the end of the line).
  constexpr std::string_view token() noexcept {
    skipSpaces();
    const char* start = m_pos;
    while (m_pos != m_end && !isSpace(*m_pos)) ++m_pos;
    return {start, static_cast<std::size_t>(m_pos - start)};
  }
  /// Reads decimal digits into `value`; returns how many digits were read (0: none),
  /// or -1 when the number exceeds `maxValue`.
  constexpr int digits(std::uint64_t& value, std::uint64_t maxValue) noexcept {
    value = 0;
    int count = 0;
    while (m_pos != m_end && isDigit(*m_pos)) {
      const auto digit = static_cast<std::uint64_t>(*m_pos - '0');
      if (value > (maxValue - digit) / 10) return -1;
      value = value * 10 + digit;
      ++m_pos;
      ++count;
    }
    return count;
  }

 private:
  const char* m_begin;
  const char* m_pos;
  const char* m_end;
};

/// Parses a whole token as an unsigned number in `base` (10 or 16). false on any
/// non-digit, on an empty token or above `maxValue`.
constexpr bool parseUnsigned(std::string_view token, unsigned base, std::uint64_t maxValue,
                             std::uint64_t& value) noexcept {
  if (token.empty()) return false;
  value = 0;
  for (const char c : token) {
    const int digit = base == 16 ? hexValue(c) : (isDigit(c) ? c - '0' : -1);
    if (digit < 0) return false;
    if (value > (maxValue - static_cast<std::uint64_t>(digit)) / base) return false;
    value = value * base + static_cast<std::uint64_t>(digit);
  }
  return true;
}

/// Fraction digits ("249713") -> nanoseconds; digits beyond the ninth are truncated.
/// Reads every digit at the cursor.
inline std::int64_t fractionToNs(Scanner& scanner) noexcept {
  std::int64_t ns = 0;
  int count = 0;
  while (isDigit(scanner.peek())) {
    if (count < 9) {
      ns = ns * 10 + (scanner.peek() - '0');
      ++count;
    }
    scanner.advance();
  }
  for (; count < 9; ++count) ns *= 10;
  return ns;
}

inline constexpr std::int64_t NS_PER_SECOND = 1'000'000'000;
/// Largest whole-second count whose nanoseconds fit an int64 (year 2262).
inline constexpr std::uint64_t MAX_SECONDS = 9'223'372'035;

/// Civil date and time (proleptic Gregorian, UTC) -> seconds since 1970-01-01, or false
/// when a field is out of range (month 13, 31 April, hour 24...).
inline bool civilToEpochSeconds(int year, unsigned month, unsigned day, unsigned hour, unsigned minute, unsigned second,
                                std::int64_t& seconds) noexcept {
  using namespace std::chrono;
  const year_month_day date{std::chrono::year{year}, std::chrono::month{month}, std::chrono::day{day}};
  if (!date.ok() || hour > 23 || minute > 59 || second > 60) return false;
  const auto days = sys_days{date}.time_since_epoch().count();
  seconds = static_cast<std::int64_t>(days) * 86'400 + hour * 3'600 + minute * 60 + second;
  return true;
}

/// Fills `error` and returns LineResult::Error; `format` is a printf format.
template <typename... Args>
LineResult fail(LineError& error, std::uint32_t column, const char* format, Args... args) noexcept {
  error.column = column;
  if constexpr (sizeof...(Args) == 0) {
    std::snprintf(error.message, sizeof(error.message), "%s", format);
  } else {
    std::snprintf(error.message, sizeof(error.message), format, args...);
  }
  return LineResult::Error;
}

/// Quotes at most 24 characters of `text` into an error message ("'...'").
struct Excerpt {
  int length;
  const char* data;
};
constexpr Excerpt excerpt(std::string_view text) noexcept {
  return {static_cast<int>(text.size() < 24 ? text.size() : 24), text.data()};
}

}  // namespace openvcu::can::detail
