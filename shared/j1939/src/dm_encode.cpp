#include "openvcu/j1939/dm_encode.hpp"

#include <algorithm>
#include <initializer_list>

namespace openvcu::j1939 {
namespace {

constexpr unsigned PROTECT_SHIFT = 0;
constexpr unsigned AMBER_WARNING_SHIFT = 2;
constexpr unsigned RED_STOP_SHIFT = 4;
constexpr unsigned MALFUNCTION_SHIFT = 6;
constexpr unsigned SPN_HIGH_SHIFT = 5;  // byte 2 bits 7-5 are SPN bits 18..16
constexpr std::uint8_t CONVERSION_METHOD_BIT = 0x80;
constexpr std::uint8_t PADDING = 0xFF;

constexpr std::uint8_t bits(auto value, unsigned shift) noexcept {
  return static_cast<std::uint8_t>((static_cast<unsigned>(value) & 0x3U) << shift);
}

constexpr bool validDtc(const Dtc& dtc) noexcept {
  return dtc.spn <= DTC_MAX_SPN && dtc.fmi <= DTC_MAX_FMI && dtc.occurrenceCount <= DTC_MAX_OCCURRENCE_COUNT;
}

void writeRecord(const Dtc& dtc, std::uint8_t* record) noexcept {
  record[0] = static_cast<std::uint8_t>(dtc.spn & 0xFF);
  record[1] = static_cast<std::uint8_t>((dtc.spn >> 8) & 0xFF);
  record[2] = static_cast<std::uint8_t>(((dtc.spn >> 16) << SPN_HIGH_SHIFT) | dtc.fmi);
  record[3] = static_cast<std::uint8_t>((dtc.spnConversionMethod ? CONVERSION_METHOD_BIT : 0) | dtc.occurrenceCount);
}

/// Appends each field and its '*' at out[offset..]; the new offset, or 0 on failure.
std::size_t appendFields(std::initializer_list<std::string_view> fields, std::span<std::uint8_t> out,
                         std::size_t offset) noexcept {
  for (const std::string_view field : fields) {
    if (!validIdentificationField(field) || out.size() - offset < field.size() + 1) return 0;
    std::copy(field.begin(), field.end(), out.begin() + static_cast<std::ptrdiff_t>(offset));
    offset += field.size();
    out[offset++] = static_cast<std::uint8_t>(IDENTIFICATION_DELIMITER);
  }
  return offset;
}

}  // namespace

std::size_t encodeDm1(const LampStates& lamps, std::span<const Dtc> dtcs, std::span<std::uint8_t> out) noexcept {
  const std::size_t length = dm1EncodedLength(dtcs.size());
  if (dtcs.size() > DM1_MAX_DTCS || out.size() < length) return 0;
  if (!std::all_of(dtcs.begin(), dtcs.end(), validDtc)) return 0;
  out[0] = bits(lamps.protect, PROTECT_SHIFT) | bits(lamps.amberWarning, AMBER_WARNING_SHIFT) |
           bits(lamps.redStop, RED_STOP_SHIFT) | bits(lamps.malfunction, MALFUNCTION_SHIFT);
  out[1] = bits(lamps.protectFlash, PROTECT_SHIFT) | bits(lamps.amberWarningFlash, AMBER_WARNING_SHIFT) |
           bits(lamps.redStopFlash, RED_STOP_SHIFT) | bits(lamps.malfunctionFlash, MALFUNCTION_SHIFT);
  if (dtcs.empty()) {
    writeRecord(Dtc{}, &out[DM1_LAMP_BYTES]);  // J1939-73: SPN 0, FMI 0, OC 0 = no active DTC
  } else {
    for (std::size_t i = 0; i < dtcs.size(); ++i) writeRecord(dtcs[i], &out[DM1_LAMP_BYTES + DM1_DTC_BYTES * i]);
  }
  // 0 or 1 DTC: bytes 6 and 7 pad the single frame
  for (std::size_t i = DM1_MIN_LENGTH; i < length && dtcs.size() <= 1; ++i) out[i] = PADDING;
  return length;
}

std::size_t encodeDm2(const LampStates& lamps, std::span<const Dtc> dtcs, std::span<std::uint8_t> out) noexcept {
  return encodeDm1(lamps, dtcs, out);
}

bool validIdentificationField(std::string_view field) noexcept {
  return field.size() <= IDENTIFICATION_MAX_FIELD_LENGTH &&
         field.find(IDENTIFICATION_DELIMITER) == std::string_view::npos;
}

std::size_t encodeSoftwareIdentification(std::span<const std::string_view> fields,
                                         std::span<std::uint8_t> out) noexcept {
  if (fields.size() > SOFT_MAX_FIELDS || out.empty()) return 0;
  out[0] = static_cast<std::uint8_t>(fields.size());
  std::size_t offset = 1;
  for (const std::string_view field : fields) {
    offset = appendFields({field}, out, offset);
    if (offset == 0) return 0;
  }
  return offset;
}

std::size_t encodeEcuIdentification(const EcuIdentification& ecu, std::span<std::uint8_t> out) noexcept {
  return appendFields({ecu.partNumber, ecu.serialNumber, ecu.location, ecu.type, ecu.manufacturer, ecu.hardwareId}, out,
                      0);
}

std::size_t encodeComponentIdentification(const ComponentIdentification& component,
                                          std::span<std::uint8_t> out) noexcept {
  return appendFields({component.make, component.model, component.serialNumber, component.unitNumber}, out, 0);
}

}  // namespace openvcu::j1939
