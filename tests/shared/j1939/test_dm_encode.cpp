// DM1/DM2 and identification encoding (dm_encode.hpp), byte by byte; DM1 read back with
// decodeDm1(). Issue 24.
#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/j1939/dm_encode.hpp"

using namespace openvcu::j1939;

namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::uint32_t SPN_OIL_PRESSURE = 100;
constexpr std::uint32_t SPN_PROPRIETARY = 520192;  // 0x7F000, the first proprietary SPN
constexpr std::uint8_t FMI_LOW = 1;
constexpr std::uint8_t FMI_BAD_DEVICE = 12;
constexpr std::uint8_t FMI_CONDITION_EXISTS = 31;

LampStates amberOn() {
  LampStates lamps;
  lamps.protect = lamps.redStop = lamps.malfunction = LampStatus::Off;
  lamps.amberWarning = LampStatus::On;
  return lamps;
}

LampStates allOff() {
  LampStates lamps;
  lamps.protect = lamps.amberWarning = lamps.redStop = lamps.malfunction = LampStatus::Off;
  return lamps;
}

Bytes encoded(const LampStates& lamps, std::span<const Dtc> dtcs) {
  std::array<std::uint8_t, DM1_MAX_LENGTH> buffer{};
  const std::size_t length = encodeDm1(lamps, dtcs, buffer);
  return Bytes(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(length));
}

Bytes text(std::string_view s) {
  return Bytes(s.begin(), s.end());
}

}  // namespace

TEST_CASE("DM1 without an active DTC is lamps then 00 00 00 00 FF FF") {
  CHECK(encoded(allOff(), {}) == Bytes{0x00, 0xFF, 0x00, 0x00, 0x00, 0x00, 0xFF, 0xFF});
}

TEST_CASE("DM1 with one DTC is one frame padded with FF") {
  const std::array dtcs{Dtc{SPN_OIL_PRESSURE, FMI_LOW, 3, false}};
  CHECK(encoded(amberOn(), dtcs) == Bytes{0x04, 0xFF, 0x64, 0x00, 0x01, 0x03, 0xFF, 0xFF});
}

TEST_CASE("DM1 with five DTCs is 2 + 4 x 5 bytes, records in order, without padding") {
  const std::array dtcs{Dtc{SPN_OIL_PRESSURE, FMI_LOW, 1, false}, Dtc{SPN_PROPRIETARY, FMI_BAD_DEVICE, 2, false},
                        Dtc{SPN_PROPRIETARY + 1, FMI_CONDITION_EXISTS, 126, false}, Dtc{DTC_MAX_SPN, 0, 127, false},
                        Dtc{0x12345, 7, 5, true}};
  LampStates lamps = amberOn();
  lamps.redStop = LampStatus::On;
  lamps.redStopFlash = LampFlash::Fast;
  const Bytes expected{0x14, 0xDF,               // red (5-4 = 01) + amber (3-2 = 01); red flashes fast (01)
                       0x64, 0x00, 0x01, 0x01,   // SPN 100 FMI 1 OC 1
                       0x00, 0xF0, 0xEC, 0x02,   // SPN 0x7F000: bits 18..16 = 7 -> 0xE0 | FMI 12
                       0x01, 0xF0, 0xFF, 0x7E,   // SPN 0x7F001 FMI 31 OC 126
                       0xFF, 0xFF, 0xE0, 0x7F,   // SPN 0x7FFFF FMI 0 OC 127
                       0x45, 0x23, 0x27, 0x85};  // SPN 0x12345 FMI 7, CM 1, OC 5
  CHECK(dm1EncodedLength(dtcs.size()) == 22);
  CHECK(encoded(lamps, dtcs) == expected);
}

TEST_CASE("an encoded DM1 reads back as the same lamps and DTCs") {
  const std::array dtcs{Dtc{SPN_OIL_PRESSURE, FMI_LOW, 1, false}, Dtc{SPN_PROPRIETARY, FMI_BAD_DEVICE, 9, false},
                        Dtc{DTC_MAX_SPN, FMI_CONDITION_EXISTS, 126, false}};
  LampStates lamps = amberOn();
  lamps.protectFlash = LampFlash::Slow;
  for (std::size_t count = 0; count <= dtcs.size(); ++count) {
    CAPTURE(count);
    const std::span<const Dtc> given(dtcs.data(), count);
    const Bytes bytes = encoded(lamps, given);
    const auto decoded = decodeDm1(bytes);
    REQUIRE(decoded);
    CHECK(decoded->lamps == lamps);
    REQUIRE(decoded->dtcCount == count);
    for (std::size_t i = 0; i < count; ++i) CHECK(decoded->dtcs[i] == given[i]);
  }
}

TEST_CASE("DM1 encoding refuses a short buffer, too many DTCs and out-of-range fields") {
  const std::array one{Dtc{SPN_OIL_PRESSURE, FMI_LOW, 1, false}};
  std::array<std::uint8_t, 7> small{};
  CHECK(encodeDm1(amberOn(), one, small) == 0);
  std::array<std::uint8_t, DM1_MAX_LENGTH> buffer{};
  const std::array badSpn{Dtc{DTC_MAX_SPN + 1, FMI_LOW, 1, false}};
  const std::array badFmi{Dtc{SPN_OIL_PRESSURE, 32, 1, false}};
  const std::array badCount{Dtc{SPN_OIL_PRESSURE, FMI_LOW, 128, false}};
  CHECK(encodeDm1(amberOn(), badSpn, buffer) == 0);
  CHECK(encodeDm1(amberOn(), badFmi, buffer) == 0);
  CHECK(encodeDm1(amberOn(), badCount, buffer) == 0);
  std::vector<Dtc> tooMany(DM1_MAX_DTCS + 1, Dtc{SPN_OIL_PRESSURE, FMI_LOW, 1, false});
  std::vector<std::uint8_t> large(4096);
  CHECK(encodeDm1(amberOn(), tooMany, large) == 0);
  tooMany.pop_back();
  CHECK(encodeDm1(amberOn(), tooMany, large) == DM1_MAX_LENGTH - 3);  // 2 + 4 x 445 = 1782
}

TEST_CASE("DM2 has the DM1 layout") {
  const std::array one{Dtc{SPN_OIL_PRESSURE, FMI_LOW, 3, false}};
  std::array<std::uint8_t, 8> dm2{};
  REQUIRE(encodeDm2(amberOn(), one, dm2) == 8);
  CHECK(Bytes(dm2.begin(), dm2.end()) == encoded(amberOn(), one));
}

TEST_CASE("software identification is the field count, then each field ended by '*'") {
  const std::array<std::string_view, 2> fields{"openvcu", "1.2.0"};
  std::array<std::uint8_t, 32> out{};
  const std::size_t length = encodeSoftwareIdentification(fields, out);
  Bytes expected{0x02};
  const Bytes rest = text("openvcu*1.2.0*");
  expected.insert(expected.end(), rest.begin(), rest.end());
  CHECK(Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(length)) == expected);

  CHECK(encodeSoftwareIdentification(std::span<const std::string_view>{}, out) == 1);
  CHECK(out[0] == 0);
  const std::array<std::string_view, 1> starred{"a*b"};
  CHECK(encodeSoftwareIdentification(starred, out) == 0);
  std::array<std::uint8_t, 8> small{};
  CHECK(encodeSoftwareIdentification(fields, small) == 0);
  const std::vector<std::string_view> tooMany(SOFT_MAX_FIELDS + 1, "x");
  std::array<std::uint8_t, 512> large{};
  CHECK(encodeSoftwareIdentification(tooMany, large) == 0);
}

TEST_CASE("ECU identification has six '*'-ended fields in J1939 order, empty ones kept") {
  const EcuIdentification ecu{"PN-1", "SN-2", "cab", "VCU", "", "HW-3"};
  std::array<std::uint8_t, 64> out{};
  const std::size_t length = encodeEcuIdentification(ecu, out);
  CHECK(Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(length)) == text("PN-1*SN-2*cab*VCU**HW-3*"));
  CHECK(encodeEcuIdentification(EcuIdentification{}, out) == 6);
  CHECK(encodeEcuIdentification(EcuIdentification{.type = "a*"}, out) == 0);
  std::array<std::uint8_t, 10> small{};
  CHECK(encodeEcuIdentification(ecu, small) == 0);
}

TEST_CASE("component identification is make, model, serial number, unit number, each ended by '*'") {
  const ComponentIdentification component{"LUT", "HHEA", "0001", "loader 1"};
  std::array<std::uint8_t, 64> out{};
  const std::size_t length = encodeComponentIdentification(component, out);
  CHECK(Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(length)) == text("LUT*HHEA*0001*loader 1*"));
  const std::string longField(IDENTIFICATION_MAX_FIELD_LENGTH + 1, 'x');
  std::array<std::uint8_t, 512> large{};
  CHECK(encodeComponentIdentification(ComponentIdentification{.model = longField}, large) == 0);
}
