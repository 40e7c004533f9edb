#include "openvcu/j1939/dm1.hpp"

namespace openvcu::j1939 {
namespace {

constexpr std::uint8_t TWO_BITS = 0x3;
constexpr unsigned PROTECT_SHIFT = 0;
constexpr unsigned AMBER_WARNING_SHIFT = 2;
constexpr unsigned RED_STOP_SHIFT = 4;
constexpr unsigned MALFUNCTION_SHIFT = 6;
constexpr std::uint8_t FMI_MASK = 0x1F;
constexpr unsigned SPN_HIGH_SHIFT = 5;  // byte 2 bits 7-5 are SPN bits 18..16
constexpr std::uint8_t CONVERSION_METHOD_BIT = 0x80;
constexpr std::uint8_t OCCURRENCE_COUNT_MASK = 0x7F;
constexpr std::uint8_t PADDING = 0xFF;

constexpr LampStatus statusAt(std::uint8_t byte, unsigned shift) noexcept {
  return static_cast<LampStatus>((byte >> shift) & TWO_BITS);
}

constexpr LampFlash flashAt(std::uint8_t byte, unsigned shift) noexcept {
  return static_cast<LampFlash>((byte >> shift) & TWO_BITS);
}

constexpr Dtc dtcFrom(std::span<const std::uint8_t, DM1_DTC_BYTES> record) noexcept {
  Dtc dtc;
  dtc.spn = static_cast<std::uint32_t>(record[0]) | (static_cast<std::uint32_t>(record[1]) << 8) |
            (static_cast<std::uint32_t>(record[2] >> SPN_HIGH_SHIFT) << 16);
  dtc.fmi = static_cast<std::uint8_t>(record[2] & FMI_MASK);
  dtc.spnConversionMethod = (record[3] & CONVERSION_METHOD_BIT) != 0;
  dtc.occurrenceCount = static_cast<std::uint8_t>(record[3] & OCCURRENCE_COUNT_MASK);
  return dtc;
}

constexpr bool isPadding(std::span<const std::uint8_t, DM1_DTC_BYTES> record) noexcept {
  return record[0] == PADDING && record[1] == PADDING && record[2] == PADDING &&
         record[3] == PADDING;
}

constexpr std::array<std::uint8_t, DM1_DTC_BYTES> SPN_100_RECORD{0x64, 0x00, 0x01, 0x03};
static_assert(dtcFrom(SPN_100_RECORD) == Dtc{100, 1, 3, false});
constexpr std::array<std::uint8_t, DM1_DTC_BYTES> HIGHEST_SPN_RECORD{0xFF, 0xFF, 0xFE, 0x7E};
static_assert(dtcFrom(HIGHEST_SPN_RECORD) == Dtc{DTC_MAX_SPN, 30, 126, false});

}  // namespace

std::string_view lampStatusName(LampStatus status) noexcept {
  switch (status) {
    case LampStatus::Off: return "Off";
    case LampStatus::On: return "On";
    case LampStatus::Error: return "Error";
    case LampStatus::NotAvailable: return "NotAvailable";
  }
  return "Unknown";
}

std::string_view lampFlashName(LampFlash flash) noexcept {
  switch (flash) {
    case LampFlash::Slow: return "Slow";
    case LampFlash::Fast: return "Fast";
    case LampFlash::Reserved: return "Reserved";
    case LampFlash::NotFlashing: return "NotFlashing";
  }
  return "Unknown";
}

bool Dm1::contains(std::uint32_t spn, std::uint8_t fmi) const noexcept {
  for (const Dtc& dtc : activeDtcs()) {
    if (dtc.spn == spn && dtc.fmi == fmi) return true;
  }
  return false;
}

std::optional<Dm1> decodeDm1(std::span<const std::uint8_t> data) noexcept {
  if (data.size() < DM1_MIN_LENGTH || data.size() > DM1_MAX_LENGTH) return std::nullopt;
  std::optional<Dm1> maybeDm1{std::in_place};
  Dm1& dm1 = *maybeDm1;
  const std::uint8_t status = data[0];
  const std::uint8_t flash = data[1];
  dm1.lamps.protect = statusAt(status, PROTECT_SHIFT);
  dm1.lamps.amberWarning = statusAt(status, AMBER_WARNING_SHIFT);
  dm1.lamps.redStop = statusAt(status, RED_STOP_SHIFT);
  dm1.lamps.malfunction = statusAt(status, MALFUNCTION_SHIFT);
  dm1.lamps.protectFlash = flashAt(flash, PROTECT_SHIFT);
  dm1.lamps.amberWarningFlash = flashAt(flash, AMBER_WARNING_SHIFT);
  dm1.lamps.redStopFlash = flashAt(flash, RED_STOP_SHIFT);
  dm1.lamps.malfunctionFlash = flashAt(flash, MALFUNCTION_SHIFT);

  // (1785 - 2) / 4 records at most: DM1_MAX_DTCS always has room.
  for (std::size_t offset = DM1_LAMP_BYTES; offset + DM1_DTC_BYTES <= data.size();
       offset += DM1_DTC_BYTES) {
    const auto record = data.subspan(offset).first<DM1_DTC_BYTES>();
    if (isPadding(record)) continue;
    const Dtc dtc = dtcFrom(record);
    if (dtc.spn == 0 && dtc.fmi == 0) continue;  // J1939-73: no active DTC
    dm1.dtcs[dm1.dtcCount++] = dtc;
  }
  return maybeDm1;
}

}  // namespace openvcu::j1939
