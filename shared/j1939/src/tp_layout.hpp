#pragma once
// The TP.CM frame layout and the small helpers the transport receiver, sender and monitor
// share (private to openvcu::j1939). J1939-21 numbers bytes from 1: byte 1 is CONTROL.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "openvcu/j1939/transport.hpp"

namespace openvcu::j1939::tp {

// TP.CM byte offsets
inline constexpr std::size_t CONTROL = 0;
inline constexpr std::size_t SIZE_LOW = 1;
inline constexpr std::size_t SIZE_HIGH = 2;
inline constexpr std::size_t PACKET_COUNT = 3;
inline constexpr std::size_t PACKET_LIMIT = 4;  ///< RTS: max packets per CTS
inline constexpr std::size_t CTS_COUNT = 1;
inline constexpr std::size_t CTS_NEXT = 2;
inline constexpr std::size_t ABORT_REASON = 1;
inline constexpr std::size_t ABORT_ROLE = 2;
inline constexpr std::size_t PGN_FIELD = 5;

inline constexpr std::uint8_t RESERVED = 0xFF;
inline constexpr std::uint8_t ABORT_ROLE_MASK = 0x03;  ///< Abort byte 2, bits 1..0: the sender's role

using ControlData = std::array<std::uint8_t, TP_FRAME_LENGTH>;

/// `nowNs + delayNs`, saturating at the largest time.
constexpr std::int64_t after(std::int64_t nowNs, std::int64_t delayNs) noexcept {
  return nowNs > std::numeric_limits<std::int64_t>::max() - delayNs ? std::numeric_limits<std::int64_t>::max()
                                                                     : nowNs + delayNs;
}

constexpr std::uint8_t byteOf(std::uint32_t value, unsigned shift) noexcept {
  return static_cast<std::uint8_t>((value >> shift) & 0xFFu);
}

/// TP.CM bytes 6-8: the PGN of the message, LSB first.
constexpr std::uint32_t pgnField(std::span<const std::uint8_t> data) noexcept {
  return static_cast<std::uint32_t>(data[PGN_FIELD]) | (static_cast<std::uint32_t>(data[PGN_FIELD + 1]) << 8) |
         (static_cast<std::uint32_t>(data[PGN_FIELD + 2]) << 16);
}

/// TP.CM bytes 2-3 of RTS, BAM and EndOfMsgAck: the message size, LSB first.
constexpr std::size_t sizeField(std::span<const std::uint8_t> data) noexcept {
  return static_cast<std::size_t>(data[SIZE_LOW]) | (static_cast<std::size_t>(data[SIZE_HIGH]) << 8);
}

/// TP.DT packets a message of `size` bytes takes.
constexpr std::size_t packetsFor(std::size_t size) noexcept {
  return (size + TP_BYTES_PER_PACKET - 1) / TP_BYTES_PER_PACKET;
}
static_assert(packetsFor(TP_MAX_MESSAGE_SIZE) == TP_MAX_PACKETS);

}  // namespace openvcu::j1939::tp
