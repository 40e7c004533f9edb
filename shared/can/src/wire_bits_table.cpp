// detail::classicWireBits: the wire bits of a classic frame counted with a CRC-15 byte
// table and a bit-stuffing table, the implementation behind can::wireBits / classicCrc15.
//
//   stuffing state = (length of the current run of equal bits 0..5, its bit value); a run
//   of 5 owes a complementary stuff bit before the next bit (ISO 11898-1:2015, bit stuffing)
//   stuff table[state x 256 + byte] -> (stuff bits the byte's 8 bits add, next state)
//
// Why tables: the bit-by-bit count (wire_bits_reference.cpp) costs about 0.4 us a frame,
// and can::BusLoadMeter and `vcu trace stats` count every frame they see.
#include <algorithm>
#include <array>
#include <cstdint>

#include "wire_bits_internal.hpp"

namespace openvcu::can::detail {
namespace {

/// SOF + 11-bit identifier + RTR + IDE + r0 + DLC (4).
constexpr unsigned STANDARD_HEADER_BITS = 19;
/// SOF + base identifier (11) + SRR + IDE + extension (18) + RTR + r1 + r0 + DLC (4).
constexpr unsigned EXTENDED_HEADER_BITS = 39;
constexpr unsigned STUFF_STATES = 2 * (STUFF_RUN + 1);  ///< run 0..5 x last bit

struct Step {
  std::uint8_t state;
  std::uint8_t stuffBits;
};

/// One frame bit through the stuffing state (as the bit-by-bit counter's BitCounter::push).
constexpr Step stuffStep(std::uint8_t state, bool bit) {
  unsigned run = state / 2;
  bool last = (state % 2) != 0;
  std::uint8_t stuffBits = 0;
  if (run == STUFF_RUN) {  // the owed stuff bit goes out first and starts a new run
    ++stuffBits;
    last = !last;
    run = 1;
  }
  if (run > 0 && bit == last) {
    ++run;
  } else {
    last = bit;
    run = 1;
  }
  return Step{static_cast<std::uint8_t>(run * 2 + (last ? 1u : 0u)), stuffBits};
}

struct Tables {
  std::array<std::uint16_t, 256> crc{};
  std::array<Step, STUFF_STATES * 256> stuff{};  ///< [state x 256 + byte]: 8 bits, MSB first
};

constexpr Tables makeTables() {
  Tables tables;
  for (unsigned byte = 0; byte < 256; ++byte) {
    auto crc = static_cast<std::uint16_t>(byte << (CRC15_BITS - 8));
    for (int bit = 0; bit < 8; ++bit) {
      const bool feedback = (crc & 0x4000u) != 0;
      crc = static_cast<std::uint16_t>((crc << 1) & CRC15_MASK);
      if (feedback) crc ^= CRC15_POLYNOMIAL;
    }
    tables.crc[byte] = crc;
  }
  for (unsigned state = 0; state < STUFF_STATES; ++state) {
    for (unsigned byte = 0; byte < 256; ++byte) {
      Step total{static_cast<std::uint8_t>(state), 0};
      for (int bit = 7; bit >= 0; --bit) {
        const Step step = stuffStep(total.state, ((byte >> bit) & 1u) != 0);
        total.state = step.state;
        total.stuffBits = static_cast<std::uint8_t>(total.stuffBits + step.stuffBits);
      }
      tables.stuff[state * 256 + byte] = total;
    }
  }
  return tables;
}

constexpr Tables TABLES = makeTables();

constexpr std::uint16_t crcByte(std::uint16_t crc, std::uint8_t byte) {
  return static_cast<std::uint16_t>(((crc << 8) & CRC15_MASK) ^ TABLES.crc[((crc >> (CRC15_BITS - 8)) ^ byte) & 0xFFu]);
}

__extension__ using Bits128 = unsigned __int128;  // SOF..CRC of a classic frame: at most 118 bits

}  // namespace

WireBits classicWireBits(const Frame& frame, std::uint16_t& crcOut) noexcept {
  const bool remote = (frame.flags & FLAG_RTR) != 0;
  const auto length = static_cast<std::uint8_t>(std::min<std::size_t>(frame.length, CLASSIC_DATA_LENGTH));
  std::uint64_t header = 0;  // SOF (dominant 0) first
  unsigned headerBits = 0;
  if (frame.extended()) {
    const std::uint32_t id = frame.id & EXTENDED_ID_MASK;
    header = (header << 11) | (id >> 18);
    header = (header << 2) | 0b11u;  // SRR, IDE recessive
    header = (header << 18) | (id & 0x3FFFFu);
    header = (header << 1) | (remote ? 1u : 0u);
    header = (header << 2);  // r1, r0
    headerBits = EXTENDED_HEADER_BITS;
  } else {
    header = (header << 11) | (frame.id & STANDARD_ID_MASK);
    header = (header << 1) | (remote ? 1u : 0u);
    header = (header << 2);  // IDE (standard), r0
    headerBits = STANDARD_HEADER_BITS;
  }
  header = (header << 4) | length;

  // CRC-15 with initial value 0: leading zero bits do not change it, so the header is fed
  // as whole bytes (3 or 5) zero-padded in front.
  std::uint16_t crc = 0;
  for (int byte = static_cast<int>((headerBits + 7) / 8) - 1; byte >= 0; --byte) {
    crc = crcByte(crc, static_cast<std::uint8_t>(header >> (8 * byte)));
  }
  const unsigned dataBytes = remote ? 0u : length;
  Bits128 stream = header;
  for (unsigned i = 0; i < dataBytes; ++i) {
    crc = crcByte(crc, frame.data[i]);
    stream = (stream << 8) | frame.data[i];
  }
  crcOut = crc;
  stream = (stream << CRC15_BITS) | crc;
  const unsigned streamBits = headerBits + 8 * dataBytes + CRC15_BITS;

  std::uint8_t state = 0;
  std::uint32_t stuffBits = 0;
  unsigned left = streamBits;
  for (; left >= 8; left -= 8) {
    const Step step = TABLES.stuff[state * 256u + static_cast<std::uint8_t>(stream >> (left - 8))];
    state = step.state;
    stuffBits += step.stuffBits;
  }
  for (; left > 0; --left) {
    const Step step = stuffStep(state, ((stream >> (left - 1)) & 1u) != 0);
    state = step.state;
    stuffBits += step.stuffBits;
  }
  if (state / 2 == STUFF_RUN) ++stuffBits;  // classic CAN sends a stuff bit still owed after the CRC
  return WireBits{streamBits + stuffBits + TRAILER_BITS, 0, stuffBits};
}

}  // namespace openvcu::can::detail
