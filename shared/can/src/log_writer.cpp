#include "openvcu/can/log_writer.hpp"

#include <cstdint>
#include <cstring>

namespace openvcu::can {
namespace {

constexpr char HEX_DIGITS[] = "0123456789ABCDEF";
/// SocketCAN CAN_ERR_FLAG (linux/can.h 0x20000000 = 536870912), set in error frame ids.
constexpr std::uint32_t CAN_ERR_FLAG = 0x20000000u;
/// candump -L CAN FD flags nibble (linux/can.h CANFD_BRS 0x01, CANFD_ESI 0x02).
constexpr unsigned CANFD_BRS = 0x01;
constexpr unsigned CANFD_ESI = 0x02;

char* writeHex(char* out, std::uint32_t value, int digits) noexcept {
  for (int shift = (digits - 1) * 4; shift >= 0; shift -= 4) *out++ = HEX_DIGITS[(value >> shift) & 0xF];
  return out;
}

char* writeDecimal(char* out, std::uint64_t value) noexcept {
  char reversed[20];
  int count = 0;
  do {
    reversed[count++] = static_cast<char>('0' + value % 10);
    value /= 10;
  } while (value != 0);
  while (count > 0) *out++ = reversed[--count];
  return out;
}

}  // namespace

std::size_t formatCandumpL(const Frame& frame, std::string_view channel, std::span<char> out, char direction) noexcept {
  if (out.size() < candumpLMaxLength(channel.size())) return 0;
  char* p = out.data();

  // Sign and magnitude in microseconds, rounded towards minus infinity.
  const bool negative = frame.timestampNs < 0;
  const std::uint64_t magnitudeNs =
      negative ? 0 - static_cast<std::uint64_t>(frame.timestampNs) : static_cast<std::uint64_t>(frame.timestampNs);
  const std::uint64_t micros = negative ? (magnitudeNs + 999) / 1000 : magnitudeNs / 1000;
  *p++ = '(';
  if (negative && micros != 0) *p++ = '-';
  p = writeDecimal(p, micros / 1'000'000);
  *p++ = '.';
  std::uint64_t fraction = micros % 1'000'000;
  for (int i = 5; i >= 0; --i) {
    p[i] = static_cast<char>('0' + fraction % 10);
    fraction /= 10;
  }
  p += 6;
  *p++ = ')';
  *p++ = ' ';
  std::memcpy(p, channel.data(), channel.size());
  p += channel.size();
  *p++ = ' ';

  const std::size_t length = frame.length <= MAX_DATA_LENGTH ? frame.length : MAX_DATA_LENGTH;
  if ((frame.flags & FLAG_ERROR) != 0) {
    p = writeHex(p, (frame.id & EXTENDED_ID_MASK) | CAN_ERR_FLAG, 8);
  } else if ((frame.flags & FLAG_EXTENDED) != 0) {
    p = writeHex(p, frame.id & EXTENDED_ID_MASK, 8);
  } else {
    p = writeHex(p, frame.id & STANDARD_ID_MASK, 3);
  }
  *p++ = '#';
  if ((frame.flags & FLAG_FD) != 0) {
    const unsigned fdFlags =
        ((frame.flags & FLAG_BRS) != 0 ? CANFD_BRS : 0u) | ((frame.flags & FLAG_ESI) != 0 ? CANFD_ESI : 0u);
    *p++ = '#';
    *p++ = HEX_DIGITS[fdFlags];
  } else if ((frame.flags & FLAG_RTR) != 0) {
    *p++ = 'R';
    if (length > 0 && length <= CLASSIC_DATA_LENGTH) *p++ = static_cast<char>('0' + length);
  }
  if ((frame.flags & FLAG_RTR) == 0 || (frame.flags & FLAG_FD) != 0) {  // a remote request has no data
    for (std::size_t i = 0; i < length; ++i) {
      *p++ = HEX_DIGITS[frame.data[i] >> 4];
      *p++ = HEX_DIGITS[frame.data[i] & 0xF];
    }
  }
  if (direction == 'R' || direction == 'T') {
    *p++ = ' ';
    *p++ = direction;
  }
  return static_cast<std::size_t>(p - out.data());
}

std::string formatCandumpL(const Frame& frame, std::string_view channel, char direction) {
  std::string line(candumpLMaxLength(channel.size()), '\0');
  line.resize(formatCandumpL(frame, channel, std::span<char>(line.data(), line.size()), direction));
  return line;
}

}  // namespace openvcu::can
