#pragma once
// The bit-by-bit wire-bit counter: the reference can::wireBits is tested against for
// classic frames, and the implementation it uses for CAN FD frames.
//
//   detail::referenceWireBits(standard 0x555, DLC 8, A5 x 8) -> {111 nominal, 0 data, 0 stuff}
//
// It builds the frame's bit stream one bit at a time (SOF, arbitration, control, data,
// CRC), stuffing as it goes, which is simple to check against ISO 11898-1:2015 but costs
// about 0.4 us a classic frame; can::wireBits counts classic frames with a CRC-15 byte
// table and a stuffing table instead (shared/can/src/wire_bits_table.cpp), bit-identical
// (tests/shared/can/test_wire_time.cpp compares both). Use can::wireBits, not this.

#include <cstdint>

#include "openvcu/can/wire_time.hpp"

namespace openvcu::can::detail {

/// The same contract as can::wireBits(frame), counted bit by bit.
/// @note thread-safe, noexcept, allocation-free.
[[nodiscard]] WireBits referenceWireBits(const Frame& frame) noexcept;

/// The same contract as can::classicCrc15(frame), computed bit by bit.
/// @note thread-safe, noexcept, allocation-free.
[[nodiscard]] std::uint16_t referenceClassicCrc15(const Frame& frame) noexcept;

}  // namespace openvcu::can::detail
