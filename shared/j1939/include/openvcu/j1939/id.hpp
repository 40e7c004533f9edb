#pragma once
// SAE J1939-21 29-bit identifier fields and the PGN rule.
//
//   bits 28..26 priority | 25 EDP | 24 DP | 23..16 PF | 15..8 PS | 7..0 SA
//   PF < 240 (0xF0): PDU1, PS is the destination address, the PGN's low byte is 0.
//   PF >= 240:       PDU2, PS is the group extension and part of the PGN.
//
//   0x0CEFF321 -> priority 3, PF 0xEF, PS/DA 0xF3, SA 0x21, PGN 0xEF00 (61184)
//   0x18FEF121 -> priority 6, PF 0xFE, PS 0xF1, SA 0x21, PGN 0xFEF1 (65265), DA global

#include <cstdint>

namespace openvcu::j1939 {

inline constexpr std::uint8_t GLOBAL_ADDRESS = 0xFF;  ///< J1939-81 global destination 0xff (255)
inline constexpr std::uint8_t NULL_ADDRESS = 0xFE;    ///< J1939-81 null address 0xfe (254)
inline constexpr std::uint8_t PDU2_THRESHOLD = 0xF0;  ///< PF from which the format is PDU2, 0xf0 (240)
inline constexpr std::uint32_t PGN_MASK = 0x3FFFF;     ///< a PGN has 18 bits: EDP, DP, PF, PS

struct Id {
  std::uint8_t priority{6};  ///< 0..7
  bool extendedDataPage{};   ///< EDP
  bool dataPage{};           ///< DP
  std::uint8_t pduFormat{};  ///< PF
  std::uint8_t pduSpecific{};///< PS: destination (PDU1) or group extension (PDU2)
  std::uint8_t sourceAddress{};

  [[nodiscard]] constexpr bool isPdu1() const noexcept { return pduFormat < PDU2_THRESHOLD; }
  /// 18-bit PGN: EDP, DP, PF and (PDU2 only) PS.
  [[nodiscard]] constexpr std::uint32_t pgn() const noexcept {
    const std::uint32_t high = (static_cast<std::uint32_t>(extendedDataPage) << 17) |
                               (static_cast<std::uint32_t>(dataPage) << 16) |
                               (static_cast<std::uint32_t>(pduFormat) << 8);
    return isPdu1() ? high : high | pduSpecific;
  }
  /// Destination address: PS for PDU1, global (0xFF) for PDU2.
  [[nodiscard]] constexpr std::uint8_t destination() const noexcept {
    return isPdu1() ? pduSpecific : GLOBAL_ADDRESS;
  }
  [[nodiscard]] constexpr std::uint32_t toCanId() const noexcept {
    return (static_cast<std::uint32_t>(priority & 0x7u) << 26) |
           (static_cast<std::uint32_t>(extendedDataPage) << 25) |
           (static_cast<std::uint32_t>(dataPage) << 24) |
           (static_cast<std::uint32_t>(pduFormat) << 16) |
           (static_cast<std::uint32_t>(pduSpecific) << 8) | sourceAddress;
  }
  static constexpr Id fromCanId(std::uint32_t canId) noexcept {
    Id id;
    id.priority = static_cast<std::uint8_t>((canId >> 26) & 0x7u);
    id.extendedDataPage = ((canId >> 25) & 1u) != 0;
    id.dataPage = ((canId >> 24) & 1u) != 0;
    id.pduFormat = static_cast<std::uint8_t>((canId >> 16) & 0xFFu);
    id.pduSpecific = static_cast<std::uint8_t>((canId >> 8) & 0xFFu);
    id.sourceAddress = static_cast<std::uint8_t>(canId & 0xFFu);
    return id;
  }
  /// PGN + priority + addresses -> Id (the destination is ignored for PDU2 PGNs).
  static constexpr Id fromPgn(std::uint32_t pgn, std::uint8_t priority, std::uint8_t sourceAddress,
                              std::uint8_t destination = GLOBAL_ADDRESS) noexcept {
    Id id = fromCanId((pgn & PGN_MASK) << 8);
    id.priority = priority;
    id.sourceAddress = sourceAddress;
    if (id.isPdu1()) id.pduSpecific = destination;
    return id;
  }
  friend constexpr bool operator==(const Id&, const Id&) = default;
};

/// PGN of a 29-bit CAN ID.
constexpr std::uint32_t pgnOf(std::uint32_t canId) noexcept { return Id::fromCanId(canId).pgn(); }

static_assert(pgnOf(0x0CEFF321u) == 0xEF00u);
static_assert(pgnOf(0x18FEF121u) == 0xFEF1u);
static_assert(Id::fromCanId(0x0CEFF321u).destination() == 0xF3u);
static_assert(Id::fromPgn(0xEF00u, 3, 0x21, 0xF3).toCanId() == 0x0CEFF321u);

}  // namespace openvcu::j1939
