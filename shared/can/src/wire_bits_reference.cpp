// detail::referenceWireBits: the bit-by-bit wire-bit counter (classic and CAN FD frames).
//
//   referenceWireBits(extended 0x18FF50E5, DLC 8, 8 x 00) -> the whole stuffed bit stream
//   walked bit by bit: CRC-15 fed per bit, a stuff bit after every run of 5 equal bits
//
// can::wireBits uses it for CAN FD frames; classic frames go through the table-driven
// count (wire_bits_table.cpp), which the tests compare with this one.
#include "openvcu/can/wire_bits_reference.hpp"

#include <algorithm>

#include "wire_bits_internal.hpp"

namespace openvcu::can::detail {
namespace {

/// CAN FD: stuff count field = 3-bit Gray-coded count + parity (ISO 11898-1:2015, CAN FD CRC field).
constexpr std::uint32_t FD_STUFF_COUNT_BITS = 4;
constexpr std::uint32_t FD_CRC17_BITS = 17;
constexpr std::uint32_t FD_CRC21_BITS = 21;
/// CRC-17 protects data fields up to 16 bytes, CRC-21 the longer ones.
constexpr std::size_t FD_CRC17_MAX_LENGTH = 16;
/// In the stuff count + CRC field a fixed stuff bit comes first and after every 4 bits.
constexpr std::uint32_t FD_FIXED_STUFF_PERIOD = 4;

/// Counts the bits of a frame as it would be sent: dynamic stuffing with the stuff bit
/// inserted lazily (before the next bit), so that the end of the stuffed region can decide
/// what happens to a stuff bit still owed, and so that a stuff bit lands in the bit rate
/// phase of the bit that follows it.
class BitCounter {
 public:
  explicit BitCounter(bool crc15) noexcept : m_crc15On(crc15) {}

  /// One frame bit inside the dynamically stuffed region.
  void push(bool bit) noexcept {
    if (m_stuffOwed) {
      count();
      ++m_stuffBits;
      m_last = !m_last;
      m_run = 1;
      m_stuffOwed = false;
    }
    count();
    if (m_crc15On) {
      const bool feedback = bit != (((m_crc >> 14) & 1u) != 0);
      m_crc = static_cast<std::uint16_t>((m_crc << 1) & CRC15_MASK);
      if (feedback) m_crc ^= CRC15_POLYNOMIAL;
    }
    if (m_run > 0 && bit == m_last) {
      ++m_run;
    } else {
      m_last = bit;
      m_run = 1;
    }
    if (m_run == STUFF_RUN) m_stuffOwed = true;
  }

  /// `width` bits of `value`, most significant first (the order CAN sends them).
  void push(std::uint32_t value, unsigned width) noexcept {
    for (unsigned i = width; i > 0; --i) push(((value >> (i - 1)) & 1u) != 0);
  }

  /// The CRC-15 covers SOF..data; the CRC sequence that follows is stuffed but not fed back.
  void stopCrc() noexcept { m_crc15On = false; }

  /// Ends the dynamically stuffed region. Classic CAN sends a stuff bit still owed after
  /// the last CRC bit; CAN FD does not: the fixed stuff bit that starts the CRC field takes
  /// its place (it is the complement of the previous bit anyway).
  void endStuffing(bool sendOwedStuffBit) noexcept {
    if (m_stuffOwed && sendOwedStuffBit) {
      count();
      ++m_stuffBits;
    }
    m_stuffOwed = false;
  }

  /// Bits outside the dynamic stuffing (fixed-stuffed CRC field, trailer).
  void addPlain(std::uint32_t bits) noexcept { (m_dataPhase ? m_bits.dataBits : m_bits.nominalBits) += bits; }
  void addFixedStuff(std::uint32_t bits) noexcept {
    addPlain(bits);
    m_stuffBits += bits;
  }
  void setDataPhase(bool dataPhase) noexcept { m_dataPhase = dataPhase; }

  [[nodiscard]] std::uint16_t crc15() const noexcept { return m_crc; }
  [[nodiscard]] WireBits result() const noexcept {
    WireBits bits = m_bits;
    bits.stuffBits = m_stuffBits;
    return bits;
  }

 private:
  void count() noexcept { ++(m_dataPhase ? m_bits.dataBits : m_bits.nominalBits); }

  WireBits m_bits{};
  std::uint32_t m_stuffBits{};
  std::uint16_t m_crc{};
  std::uint8_t m_run{};
  bool m_last{};
  bool m_stuffOwed{};
  bool m_crc15On{};
  bool m_dataPhase{};
};

constexpr bool DOMINANT = false;
constexpr bool RECESSIVE = true;

/// SOF and the identifier bits up to (not including) RTR/RRS.
void pushIdentifier(BitCounter& counter, const Frame& frame) noexcept {
  counter.push(DOMINANT);  // SOF
  if (frame.extended()) {
    const std::uint32_t id = frame.id & EXTENDED_ID_MASK;
    counter.push(id >> 18, 11);       // base identifier ID-28..ID-18
    counter.push(RECESSIVE);          // SRR
    counter.push(RECESSIVE);          // IDE: extended
    counter.push(id & 0x3FFFFu, 18);  // identifier extension ID-17..ID-0
  } else {
    counter.push(frame.id & STANDARD_ID_MASK, 11);
  }
}

void pushData(BitCounter& counter, const Frame& frame, std::size_t length) noexcept {
  for (std::size_t i = 0; i < length; ++i) {
    // Bytes past frame.length (CAN FD padding up to a DLC length) go out as 0.
    counter.push(i < frame.length ? frame.data[i] : 0u, 8);
  }
}

/// Classic data or remote frame up to the end of the CRC sequence; `crc` receives the CRC-15.
BitCounter classicBits(const Frame& frame, std::uint16_t& crc) noexcept {
  const bool remote = (frame.flags & FLAG_RTR) != 0;
  const auto length = static_cast<std::uint8_t>(std::min<std::size_t>(frame.length, CLASSIC_DATA_LENGTH));
  BitCounter counter(true);
  pushIdentifier(counter, frame);
  counter.push(remote ? RECESSIVE : DOMINANT);    // RTR
  counter.push(DOMINANT);                         // IDE (standard) or r1 (extended)
  counter.push(DOMINANT);                         // r0
  counter.push(length, 4);                        // DLC
  if (!remote) pushData(counter, frame, length);  // a remote frame has no data field
  crc = counter.crc15();
  counter.stopCrc();
  counter.push(crc, 15);
  counter.endStuffing(true);
  counter.addPlain(TRAILER_BITS);
  return counter;
}

/// Smallest CAN FD DLC whose length holds `length` bytes.
std::uint8_t fdDlc(std::size_t length) noexcept {
  for (std::uint8_t dlc = 0; dlc < 16; ++dlc) {
    if (dlcToLength(dlc) >= length) return dlc;
  }
  return 15;
}

BitCounter fdBits(const Frame& frame) noexcept {
  const bool bitRateSwitch = (frame.flags & FLAG_BRS) != 0;
  const std::uint8_t dlc = fdDlc(frame.length);
  const std::uint8_t length = dlcToLength(dlc);
  BitCounter counter(false);  // the FD CRC's value does not change the frame's length
  pushIdentifier(counter, frame);
  counter.push(DOMINANT);  // RRS
  // A standard frame sends IDE here; an extended one sent it before the ID extension.
  if (!frame.extended()) counter.push(DOMINANT);  // IDE: standard
  counter.push(RECESSIVE);                        // FDF
  counter.push(DOMINANT);                         // res
  counter.push(bitRateSwitch);                    // BRS: the data phase starts at its sample point
  counter.setDataPhase(bitRateSwitch);
  counter.push((frame.flags & FLAG_ESI) != 0);  // ESI
  counter.push(dlc, 4);                         // DLC
  pushData(counter, frame, length);
  counter.endStuffing(false);
  const std::uint32_t fixedField =
      FD_STUFF_COUNT_BITS + (length <= FD_CRC17_MAX_LENGTH ? FD_CRC17_BITS : FD_CRC21_BITS);
  // One fixed stuff bit before the stuff count, then one after every 4 bits that follow
  // while bits remain: 6 for CRC-17 (21 bits), 7 for CRC-21 (25 bits).
  const std::uint32_t fixedStuff = 1 + (fixedField - 1) / FD_FIXED_STUFF_PERIOD;
  counter.addPlain(fixedField);
  counter.addFixedStuff(fixedStuff);
  counter.setDataPhase(false);  // back to nominal at the CRC delimiter's sample point
  counter.addPlain(TRAILER_BITS);
  return counter;
}


}  // namespace

WireBits referenceWireBits(const Frame& frame) noexcept {
  if ((frame.flags & FLAG_ERROR) != 0) return WireBits{ERROR_FRAME_BITS, 0, 0};
  if (frame.fd()) return fdBits(frame).result();
  std::uint16_t crc = 0;
  return classicBits(frame, crc).result();
}

std::uint16_t referenceClassicCrc15(const Frame& frame) noexcept {
  if ((frame.flags & FLAG_ERROR) != 0 || frame.fd()) return 0;
  std::uint16_t crc = 0;
  (void)classicBits(frame, crc);
  return crc;
}

}  // namespace openvcu::can::detail
