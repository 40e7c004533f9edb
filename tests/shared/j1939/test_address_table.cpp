// Issue #24: the NAME <-> address table of the other nodes on a bus.
#include "openvcu/j1939/address_table.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <vector>

using namespace openvcu::j1939;

namespace {

constexpr Name NODE_A = Name::fromValue(0xA000000000000001u);
constexpr Name NODE_B = Name::fromValue(0xA000000000000002u);
constexpr std::uint8_t FIRST_ADDRESS = 0x80;
constexpr std::uint8_t SECOND_ADDRESS = 0x81;
constexpr std::int64_t T0_NS = 1'000'000'000;
constexpr std::int64_t T1_NS = 2'000'000'000;

}  // namespace

TEST_CASE("address table records a claim both ways") {
  AddressTable sut;

  CHECK(sut.onClaim(FIRST_ADDRESS, NODE_A, T0_NS));

  CHECK(sut.size() == 1);
  REQUIRE(sut.nameAt(FIRST_ADDRESS));
  CHECK(*sut.nameAt(FIRST_ADDRESS) == NODE_A);
  CHECK(sut.addressOf(NODE_A) == FIRST_ADDRESS);
  CHECK_FALSE(sut.addressOf(NODE_B));
  CHECK_FALSE(sut.nameAt(SECOND_ADDRESS));
}

TEST_CASE("address table moves a NAME seen at a new address and frees the old one") {
  AddressTable sut;
  sut.onClaim(FIRST_ADDRESS, NODE_A, T0_NS);

  sut.onClaim(SECOND_ADDRESS, NODE_A, T1_NS);

  CHECK(sut.size() == 1);
  CHECK_FALSE(sut.taken(FIRST_ADDRESS));
  CHECK(sut.addressOf(NODE_A) == SECOND_ADDRESS);
}

TEST_CASE("address table gives an address to the latest claimer; the one before is gone") {
  AddressTable sut;
  sut.onClaim(FIRST_ADDRESS, NODE_A, T0_NS);

  sut.onClaim(FIRST_ADDRESS, NODE_B, T1_NS);

  CHECK(sut.size() == 1);
  CHECK(*sut.nameAt(FIRST_ADDRESS) == NODE_B);
  CHECK_FALSE(sut.addressOf(NODE_A));
}

TEST_CASE("address table removes a NAME that sends Cannot Claim") {
  AddressTable sut;
  sut.onClaim(FIRST_ADDRESS, NODE_A, T0_NS);
  sut.onClaim(SECOND_ADDRESS, NODE_B, T0_NS);

  CHECK(sut.onClaim(NULL_ADDRESS, NODE_A, T1_NS));

  CHECK(sut.size() == 1);
  CHECK_FALSE(sut.taken(FIRST_ADDRESS));
  CHECK_FALSE(sut.addressOf(NODE_A));
  CHECK(sut.addressOf(NODE_B) == SECOND_ADDRESS);
}

TEST_CASE("address table refuses a claim from the global address") {
  AddressTable sut;

  CHECK_FALSE(sut.onClaim(GLOBAL_ADDRESS, NODE_A, T0_NS));

  CHECK(sut.empty());
}

TEST_CASE("address table iterates over known entries only, in address order") {
  AddressTable sut;
  sut.onClaim(SECOND_ADDRESS, NODE_B, T1_NS);
  sut.onClaim(0x00, NODE_A, T0_NS);

  std::vector<AddressEntry> seen;
  for (const AddressEntry entry : sut) seen.push_back(entry);

  REQUIRE(seen.size() == 2);
  CHECK(seen[0].address == 0x00);
  CHECK(seen[0].name == NODE_A);
  CHECK(seen[0].claimedNs == T0_NS);
  CHECK(seen[1].address == SECOND_ADDRESS);
  CHECK(seen[1].name == NODE_B);
  CHECK(seen[1].claimedNs == T1_NS);
}

TEST_CASE("address table clear and remove forget entries") {
  AddressTable sut;
  sut.onClaim(FIRST_ADDRESS, NODE_A, T0_NS);
  sut.onClaim(SECOND_ADDRESS, NODE_B, T0_NS);

  sut.remove(FIRST_ADDRESS);
  sut.remove(FIRST_ADDRESS);  // twice: nothing more

  CHECK(sut.size() == 1);
  sut.clear();
  CHECK(sut.empty());
  CHECK(sut.begin() == sut.end());
}
