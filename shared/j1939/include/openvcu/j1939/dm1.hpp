#pragma once
// SAE J1939-73 DM1, active diagnostic trouble codes (PGN 65226): two lamp bytes, then one
// 4-byte record per active DTC. Up to one DTC fits a single frame; more go by transport
// protocol (BAM), up to (1785 - 2) / 4 = 445 DTCs (design note: docs/design/j1939-transport.md).
//
//   byte 0  bits 7-6 malfunction lamp | 5-4 red stop | 3-2 amber warning | 1-0 protect
//   byte 1  the same four lamps' flash states
//   per DTC, 4 bytes:
//     byte 0  SPN bits 7..0
//     byte 1  SPN bits 15..8
//     byte 2  bits 7-5 SPN bits 18..16 | bits 4-0 FMI
//     byte 3  bit 7 SPN conversion method (CM) | bits 6-0 occurrence count
//
//   04 FF 64 00 01 03 FF FF -> amber warning lamp on, nothing flashes,
//                              one DTC: SPN 100, FMI 1, occurrence count 3, CM 0
//   00 FF 00 00 00 00 FF FF -> all lamps off, no active DTC (SPN 0, FMI 0 means none)
//
// The same layout carries DM2 (previously active DTCs, PGN 65227); decodeDm1() reads both.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_DM1 = 0xFECA;  ///< SAE J1939-73 PGN 65226 DM1 active DTCs
inline constexpr std::uint32_t PGN_DM2 = 0xFECB;  ///< SAE J1939-73 PGN 65227 DM2 previously active DTCs
inline constexpr std::uint32_t PGN_DM3 = 0xFECC;  ///< SAE J1939-73 PGN 65228 DM3 clear previously active DTCs
inline constexpr std::uint32_t PGN_DM11 = 0xFED3; ///< SAE J1939-73 PGN 65235 DM11 clear active DTCs
inline constexpr std::size_t DM1_LAMP_BYTES = 2;  ///< lamp status and lamp flash
inline constexpr std::size_t DM1_DTC_BYTES = 4;   ///< one DTC record
inline constexpr std::size_t DM1_MIN_LENGTH = DM1_LAMP_BYTES + DM1_DTC_BYTES;  ///< 6
inline constexpr std::size_t DM1_MAX_LENGTH = 1785;  ///< the J1939-21 transport protocol limit
inline constexpr std::size_t DM1_MAX_DTCS = (DM1_MAX_LENGTH - DM1_LAMP_BYTES) / DM1_DTC_BYTES;  ///< 445
inline constexpr std::uint32_t DTC_MAX_SPN = 0x7FFFF;  ///< SPN has 19 bits, 524287
inline constexpr std::uint8_t DTC_MAX_FMI = 31;        ///< FMI has 5 bits
inline constexpr std::uint8_t DTC_MAX_OCCURRENCE_COUNT = 127;  ///< 127 = not available

/// One diagnostic trouble code.
struct Dtc {
  std::uint32_t spn{};              ///< suspect parameter number, 0..524287
  std::uint8_t fmi{};               ///< failure mode identifier, 0..31
  std::uint8_t occurrenceCount{};   ///< 0..126; 127 = not available
  /// CM bit: false = the current layout (J1939-73 conversion method version 4); true = one
  /// of the older methods 1..3, whose SPN bits were ordered differently. The SPN is still
  /// read with the current layout, so for CM = 1 it is raw and may not name the real SPN.
  bool spnConversionMethod{};
  friend constexpr bool operator==(const Dtc&, const Dtc&) = default;
};

/// A lamp's 2-bit status.
enum class LampStatus : std::uint8_t { Off = 0, On = 1, Error = 2, NotAvailable = 3 };
/// A lamp's 2-bit flash state.
enum class LampFlash : std::uint8_t { Slow = 0, Fast = 1, Reserved = 2, NotFlashing = 3 };

struct LampStates {
  LampStatus protect{LampStatus::NotAvailable};
  LampStatus amberWarning{LampStatus::NotAvailable};
  LampStatus redStop{LampStatus::NotAvailable};
  LampStatus malfunction{LampStatus::NotAvailable};
  LampFlash protectFlash{LampFlash::NotFlashing};
  LampFlash amberWarningFlash{LampFlash::NotFlashing};
  LampFlash redStopFlash{LampFlash::NotFlashing};
  LampFlash malfunctionFlash{LampFlash::NotFlashing};
  friend constexpr bool operator==(const LampStates&, const LampStates&) = default;
};

/// "Off", "On", "Error", "NotAvailable".
[[nodiscard]] std::string_view lampStatusName(LampStatus status) noexcept;
/// "Slow", "Fast", "Reserved", "NotFlashing".
[[nodiscard]] std::string_view lampFlashName(LampFlash flash) noexcept;

/// A decoded DM1 with room for every DTC a DM1 can carry (about 3.6 KB, no allocation).
struct Dm1 {
  LampStates lamps;
  std::array<Dtc, DM1_MAX_DTCS> dtcs{};
  std::size_t dtcCount{};

  [[nodiscard]] std::span<const Dtc> activeDtcs() const noexcept { return {dtcs.data(), dtcCount}; }
  /// true when a DTC with this SPN and FMI is active.
  [[nodiscard]] bool contains(std::uint32_t spn, std::uint8_t fmi) const noexcept;
};

/// DM1 (or DM2) bytes -> lamps and active DTCs, in message order. Empty when fewer than 6
/// bytes (lamps and one record) or more than 1785 arrive: a truncated DM1 must not read as
/// "all DTCs cleared". Records of SPN 0 with FMI 0 (the "no active DTC" pattern) and
/// FF FF FF FF padding are skipped; trailing bytes short of a record are ignored.
/// 04 FF 64 00 01 03 FF FF -> amber on, {SPN 100, FMI 1, OC 3}.
/// @note thread-safe and real-time safe.
[[nodiscard]] std::optional<Dm1> decodeDm1(std::span<const std::uint8_t> data) noexcept;

/// Reports DTCs active in `after` but not in `before` (appeared) and active in `before`
/// but not in `after` (disappeared), identified by SPN and FMI; occurrence count and CM
/// changes are not differences. Each (SPN, FMI) is reported once even if a message repeats
/// it. Calls `onAppeared(const Dtc&)` in `after`'s order, then `onDisappeared(const Dtc&)`
/// in `before`'s order.
/// @note thread-safe and real-time safe: no allocation, O(n x m) comparisons (a DM1 has
///       few DTCs; 445 x 445 is the worst case).
template <typename OnAppeared, typename OnDisappeared>
void diffDtcs(const Dm1& before, const Dm1& after, OnAppeared&& onAppeared,
              OnDisappeared&& onDisappeared) noexcept {
  const auto sameCode = [](const Dtc& a, const Dtc& b) { return a.spn == b.spn && a.fmi == b.fmi; };
  const auto reportMissing = [&sameCode](std::span<const Dtc> from, std::span<const Dtc> in,
                                         auto&& report) {
    for (std::size_t i = 0; i < from.size(); ++i) {
      bool seen = false;
      for (std::size_t j = 0; j < i && !seen; ++j) seen = sameCode(from[j], from[i]);
      if (seen) continue;
      bool found = false;
      for (const Dtc& other : in) {
        if (sameCode(other, from[i])) {
          found = true;
          break;
        }
      }
      if (!found) report(from[i]);
    }
  };
  reportMissing(after.activeDtcs(), before.activeDtcs(), onAppeared);
  reportMissing(before.activeDtcs(), after.activeDtcs(), onDisappeared);
}

}  // namespace openvcu::j1939
