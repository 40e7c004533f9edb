#pragma once
// candump -L line formatting, for tools that record traffic in the format canplayer,
// python-can, cantools and openvcu's LogReader read back.
//
//   Frame{timestampNs 1436509052249713000, id 0x18FEF100, FLAG_EXTENDED, length 8, 01..08}, "can0"
//     -> "(1436509052.249713) can0 18FEF100#0102030405060708"
//   CAN FD with BRS -> "(...) can0 123##1DEADBEEF"; RTR length 5 -> "(...) can0 123#R5";
//   error frame (FLAG_ERROR, id = error class 0x4) -> "(...) can0 20000004#0004000000000000"
//
// The timestamp is written with 6 decimals, as candump does (canplayer reads the fraction
// as microseconds): nanoseconds below the microsecond are dropped (rounded towards minus
// infinity). No line ending is written.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>

#include "openvcu/can/frame.hpp"

namespace openvcu::can {

/// Longest line formatCandumpL writes for a channel name of `channelLength` characters:
/// "(" sign, 20 digits "." 6 ") " channel " " 8-digit id "##" flag, 128 hex digits, " R".
constexpr std::size_t candumpLMaxLength(std::size_t channelLength) noexcept {
  return 1 + 1 + 20 + 1 + 6 + 2 + channelLength + 1 + 8 + 3 + 2 * MAX_DATA_LENGTH + 2;
}

/// Writes one candump -L line into `out`; `direction` 'R' or 'T' appends " R"/" T"
/// (0: nothing). Returns the characters written, or 0 when `out` is shorter than
/// candumpLMaxLength(channel.size()) (nothing useful is written then).
/// @note thread-safe, real-time safe: no allocation, no locale.
std::size_t formatCandumpL(const Frame& frame, std::string_view channel, std::span<char> out,
                           char direction = 0) noexcept;

/// The same line as a string.
[[nodiscard]] std::string formatCandumpL(const Frame& frame, std::string_view channel, char direction = 0);

}  // namespace openvcu::can
