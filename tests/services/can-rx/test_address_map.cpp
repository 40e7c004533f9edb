// canrx::AddressMap: J1939-81 claims seen on a bus -> the VCU's address and moved nodes'
// home addresses (services/can-rx/src/address_map.hpp).
#include <doctest/doctest.h>

#include <array>
#include <cstdint>

#include "address_map.hpp"

using openvcu::canrx::AddressMap;

namespace {
constexpr std::uint64_t OWN_NAME = 0xA00C'8100'0020'0001ull;
constexpr std::uint64_t INVERTER = 0x8000'0000'0000'0071ull;
constexpr std::uint64_t OTHER = 0x0000'0000'0000'0099ull;

/// The Address Claimed payload of `name`, least significant byte first.
std::array<std::uint8_t, 8> claim(std::uint64_t name) {
  std::array<std::uint8_t, 8> payload{};
  for (std::size_t i = 0; i < 8; ++i) payload[i] = static_cast<std::uint8_t>(name >> (8 * i));
  return payload;
}
}  // namespace

TEST_CASE("a node that claims a new address is decoded by the address its NAME claimed first") {
  AddressMap sut(OWN_NAME, 0x21);
  CHECK(sut.homeAddress(0x90) == 0x90);  // nothing seen: every address is itself
  CHECK_FALSE(sut.onAddressClaimed(0x71, claim(INVERTER)));
  CHECK(sut.homeAddress(0x71) == 0x71);
  CHECK_FALSE(sut.onAddressClaimed(0x90, claim(INVERTER)));
  CHECK(sut.homeAddress(0x90) == 0x71);
  CHECK(sut.homeAddress(0x71) == 0x71);  // released: a newcomer there is itself
  CHECK_FALSE(sut.onAddressClaimed(0x91, claim(INVERTER)));
  CHECK(sut.homeAddress(0x91) == 0x71);
  CHECK(sut.homeAddress(0x90) == 0x90);
  CHECK(sut.knownNames() == 1);
}

TEST_CASE("an address taken over by another NAME is that NAME's and a Cannot Claim releases its address") {
  AddressMap sut(OWN_NAME, 0x21);
  sut.onAddressClaimed(0x71, claim(INVERTER));
  sut.onAddressClaimed(0x90, claim(INVERTER));  // inverter moved to 0x90
  sut.onAddressClaimed(0x90, claim(OTHER));     // OTHER won 0x90 (its home)
  CHECK(sut.homeAddress(0x90) == 0x90);
  sut.onAddressClaimed(0x92, claim(INVERTER));  // the inverter moved on
  CHECK(sut.homeAddress(0x92) == 0x71);
  sut.onAddressClaimed(0xFE, claim(INVERTER));  // ... and then could not claim at all
  CHECK(sut.homeAddress(0x92) == 0x92);
  CHECK(sut.homeAddress(0x90) == 0x90);
}

TEST_CASE("the VCU's own address follows its own claims while its home stays the configured address") {
  AddressMap sut(OWN_NAME, 0x21);
  CHECK(sut.ownAddress() == 0x21);
  CHECK_FALSE(sut.onAddressClaimed(0x21, claim(OWN_NAME)));  // claimed as configured: no change
  CHECK(sut.onAddressClaimed(0x80, claim(OWN_NAME)));        // lost 0x21, moved to 0x80
  CHECK(sut.ownAddress() == 0x80);
  CHECK(sut.homeAddress(0x80) == 0x21);  // its own frames from 0x80 are still its own messages
  CHECK(sut.onAddressClaimed(0xFE, claim(OWN_NAME)));  // Cannot Claim
  CHECK(sut.ownAddress() == 0xFE);
  CHECK(sut.homeAddress(0x80) == 0x80);
}

TEST_CASE("without an own NAME the VCU keeps its configured address and short payloads are ignored") {
  AddressMap sut(std::nullopt, 0x21);
  CHECK_FALSE(sut.onAddressClaimed(0x80, claim(OWN_NAME)));
  CHECK(sut.ownAddress() == 0x21);
  const std::array<std::uint8_t, 4> shortPayload{1, 2, 3, 4};
  CHECK_FALSE(sut.onAddressClaimed(0x95, shortPayload));
  CHECK(sut.homeAddress(0x95) == 0x95);
  CHECK(sut.knownNames() == 1);
}
