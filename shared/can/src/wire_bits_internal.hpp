#pragma once
// Private to wire_time / wire_bits_table / wire_bits_reference: the ISO 11898-1:2015
// constants both wire-bit counters use, and the table-driven classic count that
// can::wireBits and can::classicCrc15 call.
//
//   classicWireBits(standard 0x555, DLC 8, A5 x 8, crc) -> {111, 0, 0}, crc = the CRC-15

#include <cstdint>

#include "openvcu/can/wire_time.hpp"

namespace openvcu::can::detail {

/// CRC-15 generator x^15+x^14+x^10+x^8+x^7+x^4+x^3+1 without its x^15 term
/// (ISO 11898-1:2015, CRC sequence): 0x4599 (17817).
inline constexpr std::uint16_t CRC15_POLYNOMIAL = 0x4599;
inline constexpr std::uint16_t CRC15_MASK = 0x7FFF;
inline constexpr unsigned CRC15_BITS = 15;

/// Consecutive equal bits after which a complementary stuff bit follows (ISO 11898-1:2015, bit stuffing).
inline constexpr std::uint8_t STUFF_RUN = 5;

/// CRC delimiter (1) + ACK slot (1) + ACK delimiter (1) + EOF (7) + intermission (3).
inline constexpr std::uint32_t TRAILER_BITS = 13;

/// Wire bits of a classic (not FD, not error) data or remote frame, counted with a CRC-15
/// byte table and a bit-stuffing table; `crc` receives the CRC-15 the frame carries.
/// The same result as referenceWireBits() / referenceClassicCrc15().
/// @note thread-safe, noexcept, allocation-free (the tables are built at compile time).
[[nodiscard]] WireBits classicWireBits(const Frame& frame, std::uint16_t& crc) noexcept;

}  // namespace openvcu::can::detail
