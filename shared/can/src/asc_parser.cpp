#include "asc_parser.hpp"

namespace openvcu::can::detail {
namespace {

/// ASC CANFD flags column (the same bits as BLF CAN_FD_MESSAGE_64 flags):
/// 0x0010 remote frame, 0x1000 EDL (a CAN FD frame).
constexpr std::uint64_t ASC_FD_FLAG_REMOTE = 0x0010;
constexpr std::uint64_t ASC_FD_FLAG_EDL = 0x1000;

constexpr std::string_view MONTHS[] = {"jan", "feb", "mar", "apr", "may", "jun",
                                       "jul", "aug", "sep", "oct", "nov", "dec"};

/// English or German month abbreviation ("Sep", "Mai", "Okt", "Dez", "Mär", "Mrz") -> 1..12, 0 if unknown.
unsigned monthFromName(std::string_view name) noexcept {
  if (name.size() < 3) return 0;
  const std::string_view lowerPrefix = name.substr(0, 3);
  char lower[3] = {toLower(lowerPrefix[0]), toLower(lowerPrefix[1]), toLower(lowerPrefix[2])};
  const std::string_view key(lower, 3);
  for (unsigned i = 0; i < 12; ++i) {
    if (key == MONTHS[i]) return i + 1;
  }
  if (key == "mai") return 5;
  if (key == "okt") return 10;
  if (key == "dez") return 12;
  if (key == "mrz" || (name.size() >= 4 && toLower(name[0]) == 'm' && name.substr(1, 2) == "\xC3\xA4")) return 3;
  return 0;
}

/// "Sam Sep 30 15:06:13.191 2017" or "Tue May 27 04:09:35.000 pm 2014" -> ns since 1970 (as UTC).
bool parseAscDate(Scanner& s, std::int64_t& ns) noexcept {
  s.token();  // weekday, in the recording machine's language
  const unsigned month = monthFromName(s.token());
  std::uint64_t day = 0, hour = 0, minute = 0, second = 0, year = 0;
  if (month == 0 || !parseUnsigned(s.token(), 10, 31, day)) return false;
  Scanner clock(s.token());
  if (clock.digits(hour, 23) <= 0 || !clock.consume(':') || clock.digits(minute, 59) <= 0 || !clock.consume(':') ||
      clock.digits(second, 60) <= 0) {
    return false;
  }
  std::int64_t fractionNs = clock.consume('.') ? fractionToNs(clock) : 0;
  if (!clock.atEnd()) return false;
  std::string_view next = s.token();
  if (equalsIgnoreCase(next, "am") || equalsIgnoreCase(next, "pm")) {
    if (hour == 0 || hour > 12) return false;
    hour = (hour % 12) + (toLower(next[0]) == 'p' ? 12 : 0);
    next = s.token();
  }
  std::int64_t seconds = 0;
  if (!parseUnsigned(next, 10, 9999, year) ||
      !civilToEpochSeconds(static_cast<int>(year), month, static_cast<unsigned>(day), static_cast<unsigned>(hour),
                           static_cast<unsigned>(minute), static_cast<unsigned>(second), seconds) ||
      seconds < 0 || static_cast<std::uint64_t>(seconds) > MAX_SECONDS) {
    return false;
  }
  ns = seconds * NS_PER_SECOND + fractionNs;
  return true;
}

/// "17.876708" -> ns; false when it is not a time.
bool parseTime(std::string_view token, std::int64_t& ns) noexcept {
  Scanner s(token);
  std::uint64_t whole = 0;
  if (s.digits(whole, MAX_SECONDS) <= 0) return false;
  const std::int64_t fractionNs = s.consume('.') ? fractionToNs(s) : 0;
  ns = static_cast<std::int64_t>(whole) * NS_PER_SECOND + fractionNs;
  return s.atEnd();
}

bool isNumber(std::string_view token) noexcept {
  std::uint64_t ignored = 0;
  return parseUnsigned(token, 10, ~std::uint64_t{0} / 16, ignored);
}

/// "18FEF100x" / "123" (in the file's base) -> frame id and FLAG_EXTENDED; false if not an id.
bool parseAscId(std::string_view token, unsigned base, Frame& frame) noexcept {
  bool extended = false;
  if (!token.empty() && (token.back() == 'x' || token.back() == 'X')) {
    extended = true;
    token.remove_suffix(1);
  }
  std::uint64_t id = 0;
  if (!parseUnsigned(token, base, extended ? EXTENDED_ID_MASK : STANDARD_ID_MASK, id)) return false;
  frame.id = static_cast<std::uint32_t>(id);
  if (extended) frame.flags |= FLAG_EXTENDED;
  return true;
}

/// The error for an identifier token parseAscId() refused: out of range or not a number.
LineResult invalidId(LineError& error, std::uint32_t column, std::string_view token, unsigned base) noexcept {
  const bool extended = !token.empty() && (token.back() == 'x' || token.back() == 'X');
  std::string_view digits = token;
  if (extended) digits.remove_suffix(1);
  std::uint64_t id = 0;
  const Excerpt text = excerpt(token);
  if (parseUnsigned(digits, base, UINT64_MAX, id)) {
    return extended ? fail(error, column, "extended identifier '%.*s' exceeds 0x1FFFFFFF", text.length, text.data)
                    : fail(error, column, "standard identifier '%.*s' exceeds 0x7FF (a 29-bit one ends in 'x')",
                           text.length, text.data);
  }
  return fail(error, column, "invalid CAN identifier '%.*s'", text.length, text.data);
}

LineResult errorFrame(LogRecord& record) noexcept {
  record.frame.flags = FLAG_ERROR;  // ASC does not log the SocketCAN error class: id 0, no data
  record.frame.id = 0;
  return LineResult::Frame;
}

}  // namespace

LineResult AscParser::parseBytes(Scanner& s, std::size_t count, Frame& frame, LineError& error) const noexcept {
  for (std::size_t i = 0; i < count; ++i) {
    const std::string_view byte = s.token();
    std::uint64_t value = 0;
    if (byte.empty()) {
      return fail(error, s.column(), "expected %u data bytes, found %u", static_cast<unsigned>(count),
                  static_cast<unsigned>(i));
    }
    if (!parseUnsigned(byte, m_base, 0xFF, value)) {
      const Excerpt text = excerpt(byte);
      return fail(error, s.columnOf(byte.data()), "invalid data byte '%.*s'", text.length, text.data);
    }
    frame.data[i] = static_cast<std::uint8_t>(value);
  }
  frame.length = static_cast<std::uint8_t>(count);
  return LineResult::Frame;
}

LineResult AscParser::parseHeader(Scanner& s, LineError& error) noexcept {
  const std::uint32_t column = s.column();
  const std::string_view keyword = s.token();
  if (keyword == "date") {
    std::int64_t startNs = 0;
    if (!parseAscDate(s, startNs)) return fail(error, column, "unrecognised date in the ASC 'date' header");
    if (!m_startFromTrigger) m_startNs = startNs;
    return LineResult::Skip;
  }
  if (keyword == "base") {
    const std::string_view base = s.token();
    const std::string_view timestamps = s.token();
    const std::string_view kind = s.token();
    if ((base != "hex" && base != "dec") || timestamps != "timestamps" || (kind != "absolute" && kind != "relative")) {
      return fail(error, column, "expected 'base hex|dec timestamps absolute|relative'");
    }
    m_base = base == "hex" ? 16 : 10;
    m_relative = kind == "relative";
    return LineResult::Skip;
  }
  if (equalsIgnoreCase(keyword, "Begin") && equalsIgnoreCase(s.token(), "Triggerblock")) {
    s.skipSpaces();
    std::int64_t startNs = 0;
    if (!s.atEnd() && parseAscDate(s, startNs)) {
      m_startNs = startNs;
      m_startFromTrigger = true;
    }
    m_previousNs = 0;
    return LineResult::Skip;
  }
  if (equalsIgnoreCase(keyword, "End") || keyword == "internal" || keyword == "no") return LineResult::Skip;
  const Excerpt text = excerpt(keyword);
  return fail(error, column, "unrecognised line in an ASC log ('%.*s')", text.length, text.data);
}

/// "<channel> <id>[x] Rx|Tx d <dlc> <bytes>..." / "... r [<dlc>]" / "<channel> ErrorFrame ..."
LineResult AscParser::parseClassic(Scanner& s, std::string_view channel, LogRecord& record, LineError& error) noexcept {
  Frame& frame = record.frame;
  record.channel = channel;
  s.skipSpaces();
  const std::uint32_t idColumn = s.column();
  const std::string_view idToken = s.token();
  if (equalsIgnoreCase(idToken, "ErrorFrame")) return errorFrame(record);
  if (!parseAscId(idToken, m_base, frame)) {
    // Other events (Statistic:, J1939TP ...) are skipped; a line shaped like a frame
    // ("<id> Rx|Tx d|r ...") whose identifier cannot be read is an error, as in candump.
    Scanner lookahead = s;
    const std::string_view next = lookahead.token();
    const std::string_view type = lookahead.token();
    const bool frameShape = (next == "Rx" || next == "Tx") && (type == "d" || type == "D" || type == "r" || type == "R");
    return frameShape ? invalidId(error, idColumn, idToken, m_base) : LineResult::Skip;
  }
  const std::string_view direction = s.token();
  if (direction != "Rx" && direction != "Tx") return LineResult::Skip;  // TxRq and other events
  record.direction = direction[0] == 'R' ? 'R' : 'T';
  const std::uint32_t typeColumn = s.column() + 1;
  const std::string_view type = s.token();
  std::uint64_t dlc = 0;
  if (type == "r" || type == "R") {
    frame.flags |= FLAG_RTR;
    Scanner lookahead = s;
    if (parseUnsigned(lookahead.token(), m_base, 15, dlc)) {
      frame.length = static_cast<std::uint8_t>(dlc < CLASSIC_DATA_LENGTH ? dlc : CLASSIC_DATA_LENGTH);
    }
    return LineResult::Frame;
  }
  if (type != "d" && type != "D") {
    const Excerpt text = excerpt(type);
    return fail(error, typeColumn, "expected 'd' or 'r' after %s, found '%.*s'", direction[0] == 'R' ? "Rx" : "Tx",
                text.length, text.data);
  }
  const std::uint32_t dlcColumn = s.column() + 1;
  const std::string_view dlcToken = s.token();
  if (!parseUnsigned(dlcToken, m_base, 0xFF, dlc)) return fail(error, dlcColumn, "expected a DLC after 'd'");
  if (dlc > 15)
    return fail(error, dlcColumn, "data length %u exceeds 8 for a classic frame", static_cast<unsigned>(dlc));
  // A classic DLC of 9-15 still carries 8 bytes (ISO 11898-1).
  return parseBytes(s, dlc < CLASSIC_DATA_LENGTH ? dlc : CLASSIC_DATA_LENGTH, frame, error);
}

/// "CANFD <ch> Rx|Tx <id>[x] [<name>] <brs> <esi> <dlc> <length> <bytes>... <duration> <bits> <flags> ..."
LineResult AscParser::parseCanFd(Scanner& s, LogRecord& record, LineError& error) noexcept {
  Frame& frame = record.frame;
  record.channel = s.token();
  const std::string_view direction = s.token();
  if (direction != "Rx" && direction != "Tx") return LineResult::Skip;  // TxRq
  record.direction = direction[0] == 'R' ? 'R' : 'T';
  s.skipSpaces();
  const std::uint32_t idColumn = s.column();
  const std::string_view idToken = s.token();
  if (equalsIgnoreCase(idToken, "ErrorFrame")) return errorFrame(record);
  if (!parseAscId(idToken, m_base, frame)) return invalidId(error, idColumn, idToken, m_base);
  std::string_view brs = s.token();
  if (brs != "0" && brs != "1") brs = s.token();  // skip the symbolic message name
  const std::string_view esi = s.token();
  std::uint64_t dlc = 0;
  std::uint64_t length = 0;
  const std::uint32_t fieldsColumn = s.column();
  if ((brs != "0" && brs != "1") || (esi != "0" && esi != "1") || !parseUnsigned(s.token(), 16, 15, dlc) ||
      !parseUnsigned(s.token(), 10, 255, length)) {
    return fail(error, fieldsColumn, "expected '<brs> <esi> <dlc> <data length>' after the identifier");
  }
  if (length > MAX_DATA_LENGTH || !isValidFdLength(length)) {
    return fail(error, fieldsColumn, "data length %u is not a valid CAN FD length (0-8, 12, 16, 20, 24, 32, 48, 64)",
                static_cast<unsigned>(length));
  }
  if (parseBytes(s, length, frame, error) != LineResult::Frame) return LineResult::Error;
  s.token();  // message duration
  s.token();  // bit count
  std::uint64_t flags = 0;
  const bool hasFlags = parseUnsigned(s.token(), 16, 0xFFFFFFFFu, flags);
  // Synthetic logs write flags 0 for FD frames, so more than 8 bytes also means FD.
  const bool remote = hasFlags && (flags & ASC_FD_FLAG_REMOTE) != 0 && length == 0;
  const bool fd = !remote && (!hasFlags || (flags & ASC_FD_FLAG_EDL) != 0 || length > CLASSIC_DATA_LENGTH);
  if (remote) {
    frame.flags |= FLAG_RTR;
    frame.length = static_cast<std::uint8_t>(dlc < CLASSIC_DATA_LENGTH ? dlc : CLASSIC_DATA_LENGTH);
  } else if (fd) {
    frame.flags |= FLAG_FD;
    if (brs == "1") frame.flags |= FLAG_BRS;
    if (esi == "1") frame.flags |= FLAG_ESI;
  }
  return LineResult::Frame;
}

LineResult AscParser::parseLine(std::string_view line, LogRecord& record, LineError& error) noexcept {
  Scanner s(line);
  s.skipSpaces();
  if (!isDigit(s.peek())) return parseHeader(s, error);
  const std::uint32_t timeColumn = s.column();
  std::int64_t offsetNs = 0;
  if (!parseTime(s.token(), offsetNs)) return fail(error, timeColumn, "invalid ASC timestamp");
  if (m_relative && __builtin_add_overflow(m_previousNs, offsetNs, &offsetNs)) {
    return fail(error, timeColumn, "timestamp out of range");
  }
  m_previousNs = offsetNs;
  std::int64_t timestampNs = 0;
  if (__builtin_add_overflow(m_startNs, offsetNs, &timestampNs))
    return fail(error, timeColumn, "timestamp out of range");
  record.frame.timestampNs = timestampNs;
  record.timeSeconds = static_cast<double>(offsetNs) * 1e-9;
  record.hasTime = true;
  const std::string_view second = s.token();
  if (second == "CANFD") return parseCanFd(s, record, error);
  if (isNumber(second)) return parseClassic(s, second, record, error);
  return LineResult::Skip;  // "Start of measurement", "CAN 1 Status:...", "SV:", ...
}

}  // namespace openvcu::can::detail
