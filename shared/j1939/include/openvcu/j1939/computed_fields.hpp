#pragma once
// The fields a sender computes for every frame: a rolling counter, checksums and CRCs.
// can-tx's Scheduler::compute calls exactly these; each takes the bytes the field covers
// (the caller leaves out the field's own bytes or zeroes its bits first).
//
//   crc8SaeJ1850("123456789")                 -> 0x4B (the CRC catalogue's check value)
//   j1939Checksum4({0x01, 0x02}, 0x18FEF121)  -> 0x0D
//   RollingCounter counter(14, 16); counter.next(), counter.next(), counter.next() -> 14, 15, 0

#include <cstdint>
#include <span>

namespace openvcu::j1939 {

inline constexpr std::uint8_t CRC8_SAE_J1850_POLYNOMIAL = 0x1D;  ///< SAE J1850 x^8+x^4+x^3+x^2+1, 0x1d (29)
inline constexpr std::uint8_t CRC8_SAE_J1850_INITIAL = 0xFF;     ///< SAE J1850 initial value, 0xff (255)
inline constexpr std::uint8_t CRC8_SAE_J1850_FINAL_XOR = 0xFF;   ///< SAE J1850 final XOR, 0xff (255)

/// A message counter: next() returns the current value and advances it by one, wrapping
/// to 0 at `modulo` (0: never wraps here; the caller keeps as many bits as the signal has).
/// @note not thread-safe (one sender); real-time safe.
class RollingCounter {
 public:
  constexpr RollingCounter(std::uint64_t start, std::uint64_t modulo) noexcept : m_next(start), m_modulo(modulo) {}
  constexpr std::uint64_t next() noexcept {
    const std::uint64_t value = m_next;
    m_next = m_modulo != 0 ? (m_next + 1) % m_modulo : m_next + 1;
    return value;
  }
  [[nodiscard]] constexpr std::uint64_t peek() const noexcept { return m_next; }

 private:
  std::uint64_t m_next;
  std::uint64_t m_modulo;
};

/// CRC-8 SAE J1850: polynomial 0x1D, initial 0xFF, final XOR 0xFF, MSB first.
/// "123456789" -> 0x4B. @note thread-safe and real-time safe.
[[nodiscard]] constexpr std::uint8_t crc8SaeJ1850(std::span<const std::uint8_t> data) noexcept {
  std::uint8_t crc = CRC8_SAE_J1850_INITIAL;
  for (const std::uint8_t byte : data) {
    crc = static_cast<std::uint8_t>(crc ^ byte);
    for (int bit = 0; bit < 8; ++bit) {
      crc = static_cast<std::uint8_t>((crc & 0x80) != 0 ? (crc << 1) ^ CRC8_SAE_J1850_POLYNOMIAL : crc << 1);
    }
  }
  return static_cast<std::uint8_t>(crc ^ CRC8_SAE_J1850_FINAL_XOR);
}

/// The 8-bit sum of `data` (modulo 256). {0xFF, 0x02} -> 0x01. @note real-time safe.
[[nodiscard]] constexpr std::uint8_t sum8(std::span<const std::uint8_t> data) noexcept {
  std::uint8_t sum = 0;
  for (const std::uint8_t byte : data) sum = static_cast<std::uint8_t>(sum + byte);
  return sum;
}

/// The XOR of `data`. {0x0F, 0xF1} -> 0xFE. @note real-time safe.
[[nodiscard]] constexpr std::uint8_t xor8(std::span<const std::uint8_t> data) noexcept {
  std::uint8_t result = 0;
  for (const std::uint8_t byte : data) result = static_cast<std::uint8_t>(result ^ byte);
  return result;
}

/// SAE J1939-71 4-bit message checksum (e.g. TSC1 SPN 4207): s = the sum of the payload
/// bytes (the checksum's own bits zero) and the 4 bytes of the 29-bit CAN ID;
/// checksum = ((s >> 4) + s) & 0x0F.
/// {0x01, 0x02}, 0x18FEF121: s = 0x03 + 0x18 + 0xFE + 0xF1 + 0x21 = 0x22B -> (0x22 + 0x22B) & 0xF = 0x0D.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr std::uint8_t j1939Checksum4(std::span<const std::uint8_t> payload,
                                                    std::uint32_t canId) noexcept {
  std::uint32_t sum = 0;
  for (const std::uint8_t byte : payload) sum += byte;
  for (int shift = 0; shift < 32; shift += 8) sum += (canId >> shift) & 0xFFu;
  return static_cast<std::uint8_t>((((sum >> 4) & 0x0Fu) + sum) & 0x0Fu);
}

}  // namespace openvcu::j1939
