// Issue #24: the J1939-81 NAME, its 64-bit value, its 8 bytes and its priority rule.
#include <doctest/doctest.h>

#include <array>
#include <cstdint>

#include "openvcu/j1939/name.hpp"

using namespace openvcu::j1939;

namespace {

// The HHEA VCU's NAME fields with the AAC bit set (config/hhea/vehicle.json has them
// without it, a fixed address): construction (3), skid steer loader (1), function 128
// "main controller", identity 1.
constexpr Name HHEA_VCU{true, 3, 0, 1, false, 0x80, 0, 0, 0, 1};
constexpr std::uint64_t HHEA_VCU_VALUE = 0xB002800000000001u;
constexpr NamePayload HHEA_VCU_BYTES{0x01, 0x00, 0x00, 0x00, 0x00, 0x80, 0x02, 0xB0};

}  // namespace

TEST_CASE("NAME fields land on the J1939-81 bit positions") {
  CHECK(HHEA_VCU.toValue() == HHEA_VCU_VALUE);
  CHECK(Name{true}.toValue() == 0x8000000000000000u);
  CHECK(Name{false, 7}.toValue() == 0x7000000000000000u);
  CHECK(Name{false, 0, 15}.toValue() == 0x0F00000000000000u);
  CHECK(Name{false, 0, 0, 127}.toValue() == 0x00FE000000000000u);
  CHECK(Name{false, 0, 0, 0, true}.toValue() == 0x0001000000000000u);
  CHECK(Name{false, 0, 0, 0, false, 0xFF}.toValue() == 0x0000FF0000000000u);
  CHECK(Name{false, 0, 0, 0, false, 0, 31}.toValue() == 0x000000F800000000u);
  CHECK(Name{false, 0, 0, 0, false, 0, 0, 7}.toValue() == 0x0000000700000000u);
  CHECK(Name{false, 0, 0, 0, false, 0, 0, 0, 2047}.toValue() == 0x00000000FFE00000u);
  CHECK(Name{false, 0, 0, 0, false, 0, 0, 0, 0, 0x1FFFFF}.toValue() == 0x00000000001FFFFFu);
}

TEST_CASE("NAME value round-trips through its fields for every bit") {
  for (unsigned bit = 0; bit < 64; ++bit) {
    const std::uint64_t value = std::uint64_t{1} << bit;
    CHECK(Name::fromValue(value).toValue() == value);
  }
  CHECK(Name::fromValue(~std::uint64_t{0}).toValue() == ~std::uint64_t{0});
  CHECK(Name::fromValue(~std::uint64_t{0}).fits());
}

TEST_CASE("NAME encodes least significant byte first and decodes back") {
  CHECK(encodeName(HHEA_VCU) == HHEA_VCU_BYTES);

  const std::optional<Name> maybeSut = decodeName(HHEA_VCU_BYTES);

  REQUIRE(maybeSut);
  CHECK(maybeSut->toValue() == HHEA_VCU_VALUE);
  CHECK(maybeSut->function == 0x80);
  CHECK(maybeSut->industryGroup == 3);
  CHECK(maybeSut->arbitraryAddressCapable);
}

TEST_CASE("NAME decode refuses a payload that is not 8 bytes") {
  const std::array<std::uint8_t, 9> tooLong{};
  CHECK_FALSE(decodeName(std::span<const std::uint8_t>{HHEA_VCU_BYTES.data(), 7}));
  CHECK_FALSE(decodeName(tooLong));
  CHECK_FALSE(decodeName({}));
}

TEST_CASE("NAME fields wider than their bits do not fit and are cut when sent") {
  Name sut = HHEA_VCU;
  sut.identityNumber = NAME_MAX_IDENTITY_NUMBER + 1;  // 2^21

  CHECK_FALSE(sut.fits());
  CHECK(sut.toValue() == (HHEA_VCU_VALUE & ~std::uint64_t{0x1FFFFF}));
  sut = HHEA_VCU;
  sut.manufacturerCode = NAME_MAX_MANUFACTURER_CODE + 1;
  CHECK_FALSE(sut.fits());
  sut = HHEA_VCU;
  sut.industryGroup = 8;
  CHECK_FALSE(sut.fits());
}

TEST_CASE("the numerically lower NAME has priority, whatever field makes the difference") {
  Name higherIdentity = HHEA_VCU;
  higherIdentity.identityNumber = 2;
  Name notArbitrary = HHEA_VCU;
  notArbitrary.arbitraryAddressCapable = false;

  CHECK(hasPriorityOver(HHEA_VCU, higherIdentity));
  CHECK_FALSE(hasPriorityOver(higherIdentity, HHEA_VCU));
  CHECK(hasPriorityOver(notArbitrary, HHEA_VCU));  // the AAC bit is the most significant
  CHECK_FALSE(hasPriorityOver(HHEA_VCU, HHEA_VCU));
}
