#pragma once
// SAE J1939-76 functional-safety layer: every Safety Data Message (SDM) is preceded by a
// Safety Header Message (SHM) that carries a sequence number, the SDM's inverted identifier
// fields and a CRC-32 of the SDM data (design note: docs/design/j1939.md).
//
//   SHM byte 0    sequence (0..31) << 3 | 1 << 2 (reserved) | ~SDM EDP << 1 | ~SDM DP
//   SHM bytes 1-3 ~SDM SA, ~SDM PS, ~SDM PF
//   SHM bytes 4-7 CRC-32 of the 8 SDM data bytes, least significant byte first
//
//   SDM 0x0CEFF321 EF FF FF FF FF FF FF FF, sequence 15
//     -> SHM 0x0C0EF321 7F DE 0C 10 A3 EF 00 81   (thesis Figures 6.11 and 6.13)

#include "openvcu/j1939/id.hpp"

#include <array>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_SAFETY_HEADER = 0x0E00;  ///< SAE J1939-76 PGN 3584 SHM
inline constexpr std::size_t SAFETY_MESSAGE_LENGTH = 8;  ///< SHM and SDM are single 8-byte frames
inline constexpr std::uint8_t SAFETY_SEQUENCE_MODULO = 32;  ///< the sequence number has 5 bits

using SafetyPayload = std::array<std::uint8_t, SAFETY_MESSAGE_LENGTH>;
using SafetyDataView = std::span<const std::uint8_t, SAFETY_MESSAGE_LENGTH>;

/// CRC-32 of J1939-76: polynomial 0x6938392D, initial value 0xFFFFFFFF, no reflection,
/// final XOR 0. EF FF FF FF FF FF FF FF -> 0x8100EFA3.
/// @note thread-safe and real-time safe: table-driven, no allocation.
[[nodiscard]] std::uint32_t crc32J1939_76(std::span<const std::uint8_t> data) noexcept;

/// CAN ID of the SHM that guards the SDM `dataCanId`: PGN 0x0E00 (PDU1) from the SDM's source
/// address, to the SDM's destination (its PS for a PDU1 SDM, global 0xFF for a PDU2 SDM),
/// with the SDM's priority. 0x0CEFF321 -> 0x0C0EF321.
[[nodiscard]] constexpr std::uint32_t safetyHeaderCanId(std::uint32_t dataCanId) noexcept {
  const Id data = Id::fromCanId(dataCanId);
  return Id::fromPgn(PGN_SAFETY_HEADER, data.priority, data.sourceAddress, data.destination())
      .toCanId();
}
static_assert(safetyHeaderCanId(0x0CEFF321u) == 0x0C0EF321u);
static_assert(safetyHeaderCanId(0x0C010305u) == 0x0C0E0305u);

/// The bits of a 29-bit identifier a J1939-76 receiver identifies an SDM by: EDP, DP, PF, PS
/// and SA, i.e. its PGN, source and destination address. The priority is not among them.
inline constexpr std::uint32_t SAFETY_IDENTITY_MASK = 0x03FFFFFFu;

/// true when a J1939-76 receiver cannot tell the frames `a` and `b` apart: equal PGN, SA and
/// DA, whatever their priorities. After the SHM of `a` it takes the next frame `b` as the SDM.
/// 0x0CEFF321 (S1_ES, priority 3) and 0x18EFF321 (PropA_C4, priority 6) -> true.
[[nodiscard]] constexpr bool sameSafetyIdentity(std::uint32_t a, std::uint32_t b) noexcept {
  return ((a ^ b) & SAFETY_IDENTITY_MASK) == 0;
}
static_assert(sameSafetyIdentity(0x0CEFF321u, 0x18EFF321u));
static_assert(!sameSafetyIdentity(0x0CEFF321u, 0x0CEFF421u));  // another SA
static_assert(!sameSafetyIdentity(0x0CEFF321u, 0x0CEF2121u));  // another DA

/// The fields of an SHM, with the SDM identifier fields already un-inverted.
struct SafetyHeader {
  std::uint8_t sequence{};          ///< 0..31
  bool sdmExtendedDataPage{};       ///< the SDM's EDP
  bool sdmDataPage{};               ///< the SDM's DP
  std::uint8_t sdmSourceAddress{};  ///< the SDM's SA
  std::uint8_t sdmPduSpecific{};    ///< the SDM's PS
  std::uint8_t sdmPduFormat{};      ///< the SDM's PF
  std::uint32_t sdmCrc{};           ///< CRC-32 of the SDM data

  /// true when EDP, DP, PF, PS and SA equal those of `dataCanId` (priority is not carried).
  [[nodiscard]] constexpr bool matchesData(std::uint32_t dataCanId) const noexcept {
    const Id data = Id::fromCanId(dataCanId);
    return sdmExtendedDataPage == data.extendedDataPage && sdmDataPage == data.dataPage &&
           sdmSourceAddress == data.sourceAddress && sdmPduSpecific == data.pduSpecific &&
           sdmPduFormat == data.pduFormat;
  }
  friend constexpr bool operator==(const SafetyHeader&, const SafetyHeader&) = default;
};

/// The 8 SHM bytes for the SDM `dataCanId` carrying `data`, with sequence number `sequence`
/// (0..31; checked by assert, masked to 5 bits in release builds).
/// @note thread-safe and real-time safe.
[[nodiscard]] SafetyPayload buildSafetyHeader(std::uint32_t dataCanId, SafetyDataView data,
                                              std::uint8_t sequence) noexcept;

/// SHM bytes -> fields; empty unless exactly 8 bytes. The reserved bit 2 of byte 0 is
/// not checked (J1939 receivers ignore reserved bits).
/// 7F DE 0C 10 A3 EF 00 81 -> sequence 15, SDM EDP 0, DP 0, SA 0x21, PS 0xF3, PF 0xEF,
/// CRC 0x8100EFA3.
[[nodiscard]] std::optional<SafetyHeader> parseSafetyHeader(
    std::span<const std::uint8_t> headerData) noexcept;

/// The checker's verdict on one SDM (one safety pair), most fundamental fault first.
enum class SafetyResult : std::uint8_t {
  Ok,              ///< intact, timely and in sequence: the SDM data may be used
  Synchronising,   ///< intact and timely, sets the sequence reference: do not use the data yet
  MissingHeader,   ///< SDM without an unused SHM before it
  BadLength,       ///< SHM or SDM not 8 bytes
  Timeout,         ///< SDM later than the SRVT after its SHM
  CycleTimeout,    ///< the SHM came later than the SCT after the previous SHM
  HeaderMismatch,  ///< inverted DP/EDP/SA/PS/PF in the SHM do not match the SDM identifier
  CrcMismatch,     ///< CRC in the SHM differs from the CRC of the SDM data
  Repetition,      ///< same sequence number as the previous pair (unintended repetition)
  SequenceError,   ///< sequence number neither repeated nor previous + 1 mod 32 (lost pairs)
};
inline constexpr std::size_t SAFETY_RESULT_COUNT = 10;

/// "Ok", "CrcMismatch", ... for logs.
[[nodiscard]] std::string_view safetyResultName(SafetyResult result) noexcept;

struct SafetyPairConfig {
  std::uint32_t dataCanId{};         ///< the SDM identifier; the SHM identifier follows from it
  std::int64_t maxHeaderToDataNs{};  ///< SRVT: longest accepted SHM -> SDM time, > 0
  std::int64_t maxHeaderCycleNs{};   ///< SCT: longest accepted SHM -> next SHM time, > 0
};

/// Receiver side of one safety pair (SDG with one SDM). Feed it the SHM and SDM frames
/// routed by identifier (headerCanId(), dataCanId(); priority bits are the caller's to
/// ignore) with monotonic timestamps; each SDM gets one SafetyResult.
///
/// Sequence rule: the checker starts without a sequence reference. An intact, timely pair
/// then yields Synchronising and becomes the reference; a following pair numbered
/// reference + 1 (mod 32) yields Ok and becomes the new reference. Any fault drops the
/// reference, so after a fault the data is used again from the second consecutive good pair
/// on. Faulty pairs never become the reference.
///
/// @note not thread-safe: one thread feeds one checker. Real-time safe: noexcept, no
///       allocation, O(1) per frame.
class SafetyPairChecker {
 public:
  explicit SafetyPairChecker(const SafetyPairConfig& config) noexcept;

  [[nodiscard]] std::uint32_t headerCanId() const noexcept { return m_headerCanId; }
  [[nodiscard]] std::uint32_t dataCanId() const noexcept { return m_config.dataCanId; }
  [[nodiscard]] const SafetyPairConfig& config() const noexcept { return m_config; }

  /// Stores an SHM until its SDM arrives. An SHM still waiting for its SDM is replaced
  /// and counted in droppedHeaders().
  void onHeader(std::span<const std::uint8_t> headerData, std::int64_t timestampNs) noexcept;

  /// Checks the SDM against the stored SHM, consumes the SHM and counts the result.
  [[nodiscard]] SafetyResult onData(std::span<const std::uint8_t> data,
                                    std::int64_t timestampNs) noexcept;

  /// true when no SHM arrived yet or the last one is older than the SCT at `nowNs`:
  /// poll it to detect a silent sender, for which no onData() verdict ever comes.
  [[nodiscard]] bool headerOverdue(std::int64_t nowNs) const noexcept;

  /// How many SDMs got `result` since construction.
  [[nodiscard]] std::uint64_t count(SafetyResult result) const noexcept {
    return m_counts[static_cast<std::size_t>(result)];
  }
  /// SHMs replaced by a newer SHM before an SDM arrived.
  [[nodiscard]] std::uint64_t droppedHeaders() const noexcept { return m_droppedHeaders; }

  /// Forgets the stored SHM, the timing history and the sequence reference; keeps counters.
  void reset() noexcept;

 private:
  SafetyResult check(std::span<const std::uint8_t> data, std::int64_t timestampNs) noexcept;

  SafetyPairConfig m_config;
  std::uint32_t m_headerCanId{};
  SafetyPayload m_pendingHeader{};
  std::int64_t m_pendingHeaderNs{};
  std::int64_t m_lastHeaderNs{};
  std::array<std::uint64_t, SAFETY_RESULT_COUNT> m_counts{};
  std::uint64_t m_droppedHeaders{};
  std::uint8_t m_reference{};
  bool m_hasPendingHeader{};
  bool m_pendingLengthOk{};
  bool m_pendingCycleLate{};
  bool m_hasLastHeader{};
  bool m_hasReference{};
};

/// Sender side of one safety pair: owns the sequence number and builds each SHM.
/// Usage per cycle: send (headerCanId(), nextHeader(sdm)), then (dataCanId(), sdm).
/// @note not thread-safe: one thread per builder. Real-time safe.
class SafetyPairBuilder {
 public:
  /// `firstSequence` 0..31 (asserted) is the number the first SHM carries.
  explicit SafetyPairBuilder(std::uint32_t dataCanId, std::uint8_t firstSequence = 0) noexcept
      : m_dataCanId(dataCanId), m_sequence(firstSequence) {
    assert(firstSequence < SAFETY_SEQUENCE_MODULO);
    m_sequence %= SAFETY_SEQUENCE_MODULO;
  }

  [[nodiscard]] std::uint32_t headerCanId() const noexcept {
    return safetyHeaderCanId(m_dataCanId);
  }
  [[nodiscard]] std::uint32_t dataCanId() const noexcept { return m_dataCanId; }
  /// The sequence number the next SHM will carry.
  [[nodiscard]] std::uint8_t sequence() const noexcept { return m_sequence; }

  /// SHM payload for the SDM payload `data`; then the sequence advances (31 -> 0).
  [[nodiscard]] SafetyPayload nextHeader(SafetyDataView data) noexcept {
    const SafetyPayload header = buildSafetyHeader(m_dataCanId, data, m_sequence);
    m_sequence = static_cast<std::uint8_t>((m_sequence + 1u) % SAFETY_SEQUENCE_MODULO);
    return header;
  }

 private:
  std::uint32_t m_dataCanId;
  std::uint8_t m_sequence;
};

}  // namespace openvcu::j1939
