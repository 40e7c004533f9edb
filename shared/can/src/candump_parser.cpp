#include "candump_parser.hpp"

namespace openvcu::can::detail {
namespace {

/// SocketCAN error-frame flag in can_id (linux/can.h CAN_ERR_FLAG 0x20000000 = 536870912);
/// candump prints error frames as 8 hex digits with this bit set.
constexpr std::uint64_t CAN_ERR_FLAG = 0x20000000u;
/// can_id bits above the 29-bit identifier and the error flag (RTR 0x40000000, EFF 0x80000000).
constexpr std::uint64_t CAN_FLAG_BITS_ABOVE_ERR = 0xC0000000u;
/// candump -L CAN FD flags nibble (linux/can.h CANFD_BRS 0x01, CANFD_ESI 0x02).
constexpr int CANFD_BRS = 0x01;
constexpr int CANFD_ESI = 0x02;

constexpr std::string_view REMOTE_REQUEST = "remote request";
constexpr std::string_view ERRORFRAME = "ERRORFRAME";

/// "(1436509052.249713)", "(-0.5)" or "(2015-07-10 08:17:32.249713)" at the cursor.
LineResult parseTimestamp(Scanner& s, LogRecord& record, LineError& error) noexcept {
  const std::uint32_t openColumn = s.column();
  s.advance();  // '('
  const bool negative = s.consume('-');
  std::uint64_t whole = 0;
  const int wholeDigits = s.digits(whole, ~std::uint64_t{0} / 16);
  if (wholeDigits <= 0) {
    return fail(error, s.column(), wholeDigits < 0 ? "timestamp out of range" : "expected digits in the timestamp");
  }
  std::int64_t seconds = 0;
  if (s.peek() == '-' && wholeDigits == 4 && !negative) {  // candump -tA: local date, read as UTC
    std::uint64_t month = 0, day = 0, hour = 0, minute = 0, second = 0;
    const bool shapeOk = s.consume('-') && s.digits(month, 99) > 0 && s.consume('-') && s.digits(day, 99) > 0 &&
                         s.consume(' ') && s.digits(hour, 99) > 0 && s.consume(':') && s.digits(minute, 99) > 0 &&
                         s.consume(':') && s.digits(second, 99) > 0;
    if (!shapeOk) return fail(error, s.column(), "expected 'YYYY-MM-DD HH:MM:SS.ffffff' in the timestamp");
    if (!civilToEpochSeconds(static_cast<int>(whole), static_cast<unsigned>(month), static_cast<unsigned>(day),
                             static_cast<unsigned>(hour), static_cast<unsigned>(minute), static_cast<unsigned>(second),
                             seconds)) {
      return fail(error, openColumn + 1, "invalid date or time in the timestamp");
    }
    const auto magnitude = static_cast<std::uint64_t>(seconds < 0 ? -seconds : seconds);  // civil years 0-9999
    if (magnitude > MAX_SECONDS) return fail(error, openColumn + 1, "timestamp out of range");
  } else {
    if (whole > MAX_SECONDS) return fail(error, openColumn + 1, "timestamp out of range");
    seconds = static_cast<std::int64_t>(whole);
  }
  std::int64_t fractionNs = 0;
  if (s.consume('.')) fractionNs = fractionToNs(s);
  if (!s.consume(')')) return fail(error, s.column(), "expected ')' after the timestamp");
  const std::int64_t sign = negative ? -1 : 1;
  record.hasTime = true;
  record.frame.timestampNs = sign * (seconds * NS_PER_SECOND + fractionNs);
  record.timeSeconds =
      static_cast<double>(sign) * (static_cast<double>(seconds) + static_cast<double>(fractionNs) * 1e-9);
  return LineResult::Frame;
}

/// Hex identifier as candump prints it: 3 digits standard, 8 digits extended or error frame.
LineResult parseId(std::string_view digits, std::uint32_t column, Frame& frame, LineError& error) noexcept {
  std::uint64_t value = 0;
  if (digits.empty()) return fail(error, column, "missing CAN identifier");
  if (digits.size() > 8 || !parseUnsigned(digits, 16, 0xFFFFFFFFu, value)) {
    const Excerpt text = excerpt(digits);
    return fail(error, column, "invalid CAN identifier '%.*s' (expected 3 or 8 hex digits)", text.length, text.data);
  }
  if (digits.size() <= 3) {
    if (value > STANDARD_ID_MASK) {
      return fail(error, column, "standard identifier 0x%X exceeds 0x7FF", static_cast<unsigned>(value));
    }
    frame.id = static_cast<std::uint32_t>(value);
    return LineResult::Frame;
  }
  if ((value & CAN_FLAG_BITS_ABOVE_ERR) != 0) {
    return fail(error, column, "extended identifier 0x%X exceeds 0x1FFFFFFF", static_cast<unsigned>(value));
  }
  if (digits.size() == 8 && (value & CAN_ERR_FLAG) != 0) {
    frame.flags |= FLAG_ERROR;  // id = the SocketCAN error class bits
  } else {
    frame.flags |= FLAG_EXTENDED;
  }
  frame.id = static_cast<std::uint32_t>(value & EXTENDED_ID_MASK);
  return LineResult::Frame;
}

LineResult checkLength(std::size_t length, bool fd, std::uint32_t column, LineError& error) noexcept {
  if (!fd && length > CLASSIC_DATA_LENGTH) {
    return fail(error, column, "data length %u exceeds 8 for a classic frame", static_cast<unsigned>(length));
  }
  if (fd && !isValidFdLength(length)) {
    return fail(error, column, "data length %u is not a valid CAN FD length (0-8, 12, 16, 20, 24, 32, 48, 64)",
                static_cast<unsigned>(length));
  }
  return LineResult::Frame;
}

/// Optional trailing direction of a -L line: "R" or "T".
LineResult parseTrailingDirection(Scanner& s, LogRecord& record, LineError& error) noexcept {
  s.skipSpaces();
  const std::string_view tail = s.rest();
  const std::string_view direction = s.token();
  if (direction.empty()) return LineResult::Frame;
  if (direction.size() == 1 && (direction[0] == 'R' || direction[0] == 'T') && s.token().empty()) {
    record.direction = direction[0];
    return LineResult::Frame;
  }
  const Excerpt text = excerpt(tail);
  return fail(error, s.columnOf(tail.data()), "unexpected text '%.*s' after the frame", text.length, text.data);
}

/// "18FEF100#0102", "123##1DEADBEEF", "123#R5", "123#11.22", "123#1122334455667788_9".
LineResult parseCompact(std::string_view token, std::size_t hash, Scanner& line, LogRecord& record,
                        LineError& error) noexcept {
  Frame& frame = record.frame;
  const std::uint32_t idColumn = line.columnOf(token.data());
  if (parseId(token.substr(0, hash), idColumn, frame, error) != LineResult::Frame) return LineResult::Error;
  Scanner s(token.substr(hash + 1), line.origin());
  const bool isError = (frame.flags & FLAG_ERROR) != 0;
  bool fd = false;
  if (s.consume('#')) {
    if (s.peek() == '#') return fail(error, s.column(), "CAN XL frames ('###') are not supported");
    const int fdFlags = hexValue(s.peek());
    if (fdFlags < 0) return fail(error, s.column(), "expected the CAN FD flags digit after '##'");
    if (isError) return fail(error, idColumn, "an error frame cannot be a CAN FD frame");
    s.advance();
    fd = true;
    frame.flags |= FLAG_FD;
    if ((fdFlags & CANFD_BRS) != 0) frame.flags |= FLAG_BRS;
    if ((fdFlags & CANFD_ESI) != 0) frame.flags |= FLAG_ESI;
  } else if (s.peek() == 'R' || s.peek() == 'r') {
    if (isError) return fail(error, s.column(), "an error frame cannot be a remote request");
    s.advance();
    frame.flags |= FLAG_RTR;
    if (!s.atEnd()) {
      if (!isDigit(s.peek()) || s.peek() > '8' || s.remaining() != 1) {
        return fail(error, s.column(), "expected a remote request length 0-8 after 'R'");
      }
      frame.length = static_cast<std::uint8_t>(s.peek() - '0');
    }
    return parseTrailingDirection(line, record, error);
  }
  std::size_t length = 0;
  while (!s.atEnd()) {
    if (s.consume('.')) continue;  // cansend-style byte separator
    if (s.peek() == '_') {         // len8_dlc: "_9".."_F" after 8 bytes (raw DLC, not kept)
      const int dlc = hexValue(s.peekAt(1));
      if (fd || length != CLASSIC_DATA_LENGTH || dlc < 9 || s.remaining() != 2) {
        return fail(error, s.column(), "'_' must follow 8 data bytes and carry a DLC 9-F");
      }
      break;
    }
    const int high = hexValue(s.peek());
    const int low = hexValue(s.peekAt(1));
    if (high < 0) return fail(error, s.column(), "invalid hex digit '%c' in data", s.peek());
    if (s.remaining() < 2 || s.peekAt(1) == '.') return fail(error, s.column(), "odd number of hex digits in data");
    if (low < 0) return fail(error, s.column() + 1, "invalid hex digit '%c' in data", s.peekAt(1));
    if (length == MAX_DATA_LENGTH) return fail(error, s.column(), "data longer than 64 bytes");
    frame.data[length++] = static_cast<std::uint8_t>((high << 4) | low);
    s.advance(2);
  }
  if (checkLength(length, fd, idColumn, error) != LineResult::Frame) return LineResult::Error;
  frame.length = static_cast<std::uint8_t>(length);
  return parseTrailingDirection(line, record, error);
}

/// After the data of a console line: nothing, "ERRORFRAME" (+ text), or the -a ASCII view.
LineResult parseConsoleTail(Scanner& s, const Frame& frame, LineError& error) noexcept {
  s.skipSpaces();
  if (s.atEnd() || s.peek() == '\'' || s.peek() == '`') return LineResult::Frame;
  const std::string_view rest = s.rest();
  if (rest.substr(0, ERRORFRAME.size()) == ERRORFRAME) {
    if ((frame.flags & FLAG_ERROR) != 0) return LineResult::Frame;
    return fail(error, s.column(), "ERRORFRAME on an identifier without the error flag 0x20000000");
  }
  const std::string_view next = s.token();
  if (next.size() == 2 && hexValue(next[0]) >= 0 && hexValue(next[1]) >= 0) {
    return fail(error, s.columnOf(next.data()), "more data bytes than the length in brackets says (%u)",
                static_cast<unsigned>(frame.length));
  }
  const Excerpt text = excerpt(rest);
  return fail(error, s.columnOf(rest.data()), "unexpected text '%.*s' after the data", text.length, text.data);
}

/// "can0  RX B -  123  [12]  00 11 ..." after the interface name.
LineResult parseConsole(std::string_view token, Scanner& s, LogRecord& record, LineError& error) noexcept {
  Frame& frame = record.frame;
  bool brs = false;
  bool esi = false;
  if (token == "RX" || token == "TX") {  // candump -x: direction, then BRS and ESI marks
    record.direction = token[0] == 'R' ? 'R' : 'T';
    const std::string_view brsMark = s.token();
    const std::string_view esiMark = s.token();
    if (!(brsMark == "B" || brsMark == "-") || !(esiMark == "E" || esiMark == "-")) {
      return fail(error, s.column(), "expected 'B'/'-' and 'E'/'-' after %s", token[0] == 'R' ? "RX" : "TX");
    }
    brs = brsMark == "B";
    esi = esiMark == "E";
    token = s.token();
  }
  const std::uint32_t idColumn = s.columnOf(token.data());
  if (parseId(token, idColumn, frame, error) != LineResult::Frame) return LineResult::Error;
  s.skipSpaces();
  if (!s.consume('[')) return fail(error, s.column(), "expected '[length]' or '#' after the identifier");
  const std::uint32_t lengthColumn = s.column();
  std::uint64_t length = 0;
  const int lengthDigits = s.digits(length, 999);
  if (lengthDigits <= 0 || lengthDigits > 2 || !s.consume(']')) {
    return fail(error, lengthColumn, "expected a length of 1 or 2 digits in '[...]'");
  }
  const bool fd = lengthDigits == 2;  // candump prints "[%d]" for classic, "[%02d]" for CAN FD
  const bool isError = (frame.flags & FLAG_ERROR) != 0;
  if (fd && isError) return fail(error, lengthColumn, "an error frame cannot be a CAN FD frame");
  if (checkLength(length, fd, lengthColumn, error) != LineResult::Frame) return LineResult::Error;
  frame.length = static_cast<std::uint8_t>(length);
  if (fd) {
    frame.flags |= FLAG_FD;
    if (brs) frame.flags |= FLAG_BRS;
    if (esi) frame.flags |= FLAG_ESI;
  }
  s.skipSpaces();
  if (s.rest().substr(0, REMOTE_REQUEST.size()) == REMOTE_REQUEST) {
    if (fd || isError) return fail(error, s.column(), "only classic data frames can be remote requests");
    frame.flags |= FLAG_RTR;
    s.advance(REMOTE_REQUEST.size());
    return parseConsoleTail(s, frame, error);
  }
  for (std::size_t i = 0; i < length; ++i) {
    const std::string_view byte = s.token();
    if (byte.empty()) {
      return fail(error, s.column(), "expected %u data bytes, found %u", static_cast<unsigned>(length),
                  static_cast<unsigned>(i));
    }
    const int high = hexValue(byte[0]);
    const int low = byte.size() == 2 ? hexValue(byte[1]) : -1;
    if (high < 0 || low < 0) {
      const Excerpt text = excerpt(byte);
      return fail(error, s.columnOf(byte.data()), "invalid data byte '%.*s' (expected 2 hex digits)", text.length,
                  text.data);
    }
    frame.data[i] = static_cast<std::uint8_t>((high << 4) | low);
  }
  return parseConsoleTail(s, frame, error);
}

}  // namespace

LineResult parseCandumpLine(std::string_view line, LogRecord& record, LineError& error) noexcept {
  Scanner s(line);
  s.skipSpaces();
  if (s.peek() == '(' && parseTimestamp(s, record, error) != LineResult::Frame) return LineResult::Error;
  const std::string_view channel = s.token();
  if (channel.empty()) return fail(error, s.column(), "missing interface name");
  record.channel = channel;
  const std::string_view token = s.token();
  if (token.empty()) return fail(error, s.column(), "missing frame after the interface name");
  const std::size_t hash = token.find('#');
  if (hash != std::string_view::npos) return parseCompact(token, hash, s, record, error);
  return parseConsole(token, s, record, error);
}

}  // namespace openvcu::can::detail
