#pragma once
// Encoding of the VCU's own diagnostic and identification messages (design note:
// docs/design/j1939-diagnostics.md); decodeDm1() in dm1.hpp reads what encodeDm1() writes.
//
// DM1 / DM2 (SAE J1939-73), lamps as in dm1.hpp:
//   no DTC      lamps + 00 00 00 00 FF FF            8 bytes ("SPN 0, FMI 0": none active)
//   one DTC     lamps + record + FF FF               8 bytes
//   n > 1 DTCs  lamps + n records                    2 + 4n bytes, sent by transport protocol
//   amber on, SPN 100 FMI 1 OC 3 -> 04 FF 64 00 01 03 FF FF
//
// Identification (SAE J1939-71 / J1939DA; every field is ASCII and ends with '*', an empty
// field is just its '*'):
//   SOFT  PGN 65242: byte 0 = number of fields (SPN 965), then each software identification
//         (SPN 234) and '*'.            {"openvcu", "1.2.0"} -> 02 'openvcu*1.2.0*'
//   ECUID PGN 64965: part number (SPN 2901) * serial number (2902) * location (2903) *
//         type (2904) * manufacturer name (4304) * hardware ID (6714) *
//   CI    PGN 65259: make (SPN 586) * model (587) * serial number (588) * unit number (233) *
// Messages of up to 8 bytes go as one frame, longer ones by transport protocol.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "openvcu/j1939/dm1.hpp"

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_SOFTWARE_IDENTIFICATION = 0xFEDA;   ///< SAE J1939-71 PGN 65242 SOFT
inline constexpr std::uint32_t PGN_ECU_IDENTIFICATION = 0xFDC5;        ///< SAE J1939-71 PGN 64965 ECUID
inline constexpr std::uint32_t PGN_COMPONENT_IDENTIFICATION = 0xFEEB;  ///< SAE J1939-71 PGN 65259 CI
inline constexpr char IDENTIFICATION_DELIMITER = '*';                  ///< ends every identification field, 0x2A (42)
inline constexpr std::size_t SOFT_MAX_FIELDS = 125;                    ///< SPN 965 operational range 0..125
inline constexpr std::size_t IDENTIFICATION_MAX_FIELD_LENGTH = 200;    ///< "variable, up to 200 bytes"
inline constexpr std::size_t DM1_SINGLE_FRAME_LENGTH = 8;              ///< DM1 with 0 or 1 DTC: one padded frame

/// The DM1/DM2 length for `dtcCount` DTCs: 8 for 0 or 1, else 2 + 4 x dtcCount.
[[nodiscard]] constexpr std::size_t dm1EncodedLength(std::size_t dtcCount) noexcept {
  return dtcCount <= 1 ? DM1_SINGLE_FRAME_LENGTH : DM1_LAMP_BYTES + DM1_DTC_BYTES * dtcCount;
}

/// Lamps and DTCs -> DM1 bytes in `out` (layout above); the length written, or 0 when `out`
/// is too small, more than DM1_MAX_DTCS (445) DTCs are given, or a DTC is out of range
/// (SPN > 524287, FMI > 31, occurrence count > 127). A DTC with SPN 0 and FMI 0 is written
/// as given (a reader takes it for "none").
/// @note thread-safe and real-time safe.
[[nodiscard]] std::size_t encodeDm1(const LampStates& lamps, std::span<const Dtc> dtcs,
                                    std::span<std::uint8_t> out) noexcept;
/// DM2 (previously active DTCs, PGN 65227) has DM1's layout: the same as encodeDm1().
[[nodiscard]] std::size_t encodeDm2(const LampStates& lamps, std::span<const Dtc> dtcs,
                                    std::span<std::uint8_t> out) noexcept;

/// true when `field` may be an identification field: at most 200 bytes and no '*'.
[[nodiscard]] bool validIdentificationField(std::string_view field) noexcept;

/// SOFT: the count byte, then each field and '*'. 0 when `out` is too small, more than
/// 125 fields are given or a field is not valid.
/// @note thread-safe and real-time safe.
[[nodiscard]] std::size_t encodeSoftwareIdentification(std::span<const std::string_view> fields,
                                                       std::span<std::uint8_t> out) noexcept;

/// The ECUID fields in message order (empty = not given, still delimited).
struct EcuIdentification {
  std::string_view partNumber{};
  std::string_view serialNumber{};
  std::string_view location{};
  std::string_view type{};
  std::string_view manufacturer{};
  std::string_view hardwareId{};
};

/// The CI fields in message order.
struct ComponentIdentification {
  std::string_view make{};
  std::string_view model{};
  std::string_view serialNumber{};
  std::string_view unitNumber{};
};

/// ECUID bytes; 0 when `out` is too small or a field is not valid.
/// @note thread-safe and real-time safe.
[[nodiscard]] std::size_t encodeEcuIdentification(const EcuIdentification& ecu, std::span<std::uint8_t> out) noexcept;
/// CI bytes; 0 when `out` is too small or a field is not valid.
/// @note thread-safe and real-time safe.
[[nodiscard]] std::size_t encodeComponentIdentification(const ComponentIdentification& component,
                                                        std::span<std::uint8_t> out) noexcept;

}  // namespace openvcu::j1939
