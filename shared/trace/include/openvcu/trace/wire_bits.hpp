#pragma once
// The wire bits of a frame as can::wireBits counts them (ISO 11898-1: stuff bits,
// intermission), for the trace statistics that count every frame of a log.
//
//   frameWireBits(standard 0x555, DLC 8, A5 x 8) -> {111 nominal bits, 0 data bits, 0 stuff bits}
//
// Why not can::wireBits directly: it builds the stuffed bit stream one bit at a time
// (about 1 us a frame on the benchmark machine); here classic frames go through a
// CRC-15 byte table and a stuffing table (state x byte -> stuff bits, next state), about
// 20x faster with the same result (tests/shared/trace compares both on random frames).
// CAN FD and error frames are handed to can::wireBits.

#include "openvcu/can/wire_time.hpp"

namespace openvcu::trace {

/// The same as can::wireBits(frame).
/// @note thread-safe, noexcept, allocation-free (the tables are built at compile time).
[[nodiscard]] can::WireBits frameWireBits(const can::Frame& frame) noexcept;

}  // namespace openvcu::trace
