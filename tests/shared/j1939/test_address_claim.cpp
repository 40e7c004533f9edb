// Issue #24: J1939-81 address claim, every case on a set clock.
#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "openvcu/j1939/address_claim.hpp"

using namespace openvcu::j1939;

template <>
struct doctest::StringMaker<ClaimState> {
  static doctest::String convert(ClaimState state) {
    const std::string_view name = claimStateName(state);
    return {name.data(), static_cast<doctest::String::size_type>(name.size())};
  }
};
template <>
struct doctest::StringMaker<ClaimFrame> {
  static doctest::String convert(const ClaimFrame& frame) {
    char text[48];
    std::snprintf(text, sizeof text, "%08X %02X %02X %02X %02X %02X %02X %02X %02X", static_cast<unsigned>(frame.canId),
                  frame.data[0], frame.data[1], frame.data[2], frame.data[3], frame.data[4], frame.data[5],
                  frame.data[6], frame.data[7]);
    return text;
  }
};

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0_NS = 10'000 * MS;

constexpr std::uint8_t VCU_ADDRESS = 0x21;  // HHEA's VCU: transmits right after its claim
constexpr std::uint8_t RANGE_FIRST = 0x80;  // 128
constexpr std::uint8_t RANGE_SECOND = 0x81;
constexpr std::uint8_t RANGE_THIRD = 0x82;
constexpr std::uint8_t VIC_ADDRESS = 0xF3;
constexpr std::uint8_t OTHER_ADDRESS = 0x40;

// AAC, construction, skid steer loader, main controller, identity 0x100.
constexpr Name OUR_NAME = Name::fromValue(0xB002800000000100u);
constexpr Name OUR_NAME_FIXED = Name::fromValue(0x3002800000000100u);   // the same, not AAC
constexpr Name HIGHER_PRIORITY = Name::fromValue(0x1000000000000001u);  // lower value: wins
constexpr Name LOWER_PRIORITY = Name::fromValue(0xF000000000000001u);   // higher value: loses
constexpr Name THIRD_NODE = Name::fromValue(0x2000000000000002u);

constexpr AddressClaimerConfig VCU_CONFIG{OUR_NAME, VCU_ADDRESS, DEFAULT_CLAIM_RANGE_FIRST, DEFAULT_CLAIM_RANGE_LAST};

struct AddressChange {
  std::uint8_t oldAddress{};
  std::uint8_t newAddress{};
  ClaimState state{};
  friend bool operator==(const AddressChange&, const AddressChange&) = default;
};

class RecordingSink final : public ClaimSink {
 public:
  void send(const ClaimFrame& frame) noexcept override { frames.push_back(frame); }
  void addressChanged(std::uint8_t oldAddress, std::uint8_t newAddress, ClaimState state) noexcept override {
    changes.push_back({oldAddress, newAddress, state});
  }
  void addressLost(std::uint8_t address, const Name& claimant) noexcept override {
    losses.push_back({address, claimant});
    lossBeforeChange.push_back(changes.size());
  }
  void clear() {
    frames.clear();
    changes.clear();
    losses.clear();
    lossBeforeChange.clear();
  }
  std::vector<ClaimFrame> frames;
  std::vector<AddressChange> changes;
  std::vector<AddressClaimed> losses;         ///< {the address lost, the claimant's NAME}
  std::vector<std::size_t> lossBeforeChange;  ///< changes.size() when each loss was reported
};

ClaimFrame claimOf(std::uint8_t address, const Name& name = OUR_NAME) {
  return ClaimFrame{addressClaimedCanId(address), encodeName(name)};
}

}  // namespace

TEST_CASE("claimer claims its preferred address at start: Address Claimed to global at priority 6") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);

  sut.start(T0_NS, sink);

  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == ClaimFrame{0x18EEFF21u, {0x00, 0x01, 0x00, 0x00, 0x00, 0x80, 0x02, 0xB0}});
  CHECK(sink.changes == std::vector<AddressChange>{{NULL_ADDRESS, VCU_ADDRESS, ClaimState::Claiming}});
  CHECK(sut.state() == ClaimState::Claiming);
  CHECK(sut.address() == VCU_ADDRESS);
  CHECK(sut.counters().claimsSent == 1);
}

TEST_CASE("claimer on an address below 128 may transmit at once and is Claimed after 250 ms") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.start(T0_NS, sink);
  sink.clear();

  CHECK(sut.mayTransmit());
  CHECK(sut.nextDeadlineNs() == T0_NS + ADDRESS_CLAIM_WAIT_NS);
  sut.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS - 1, sink);
  CHECK(sut.state() == ClaimState::Claiming);
  CHECK(sink.changes.empty());

  sut.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS, sink);

  CHECK(sut.state() == ClaimState::Claimed);
  CHECK(sink.changes == std::vector<AddressChange>{{VCU_ADDRESS, VCU_ADDRESS, ClaimState::Claimed}});
  CHECK(sink.frames.empty());
  CHECK_FALSE(sut.nextDeadlineNs());
  CHECK(sut.mayTransmit());
}

TEST_CASE("claimer on an address of 128..247 may transmit only after 250 ms without contest") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME, RANGE_FIRST});
  sut.start(T0_NS, sink);

  CHECK_FALSE(sut.mayTransmit());
  sut.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS - 1, sink);
  CHECK_FALSE(sut.mayTransmit());
  sut.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS, sink);
  CHECK(sut.mayTransmit());
  CHECK(transmitsWithoutWait(127));
  CHECK_FALSE(transmitsWithoutWait(128));
  CHECK_FALSE(transmitsWithoutWait(247));
  CHECK(transmitsWithoutWait(248));
  CHECK(transmitsWithoutWait(253));
  CHECK_FALSE(transmitsWithoutWait(NULL_ADDRESS));
}

TEST_CASE("claimer ignores its own claim looped back by the bus") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.start(T0_NS, sink);
  sink.clear();

  sut.onAddressClaimed(VCU_ADDRESS, OUR_NAME, T0_NS + 1 * MS, sink);
  sut.onAddressClaimed(RANGE_FIRST, OUR_NAME, T0_NS + 2 * MS, sink);  // an older claim of ours

  CHECK(sink.frames.empty());
  CHECK(sink.changes.empty());
  CHECK(sut.counters().echoesIgnored == 2);
  CHECK(sut.table().empty());
  CHECK(sut.address() == VCU_ADDRESS);
}

TEST_CASE("claimer defends its address against a lower-priority NAME and the 250 ms window keeps running") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.start(T0_NS, sink);
  sink.clear();

  sut.onAddressClaimed(VCU_ADDRESS, LOWER_PRIORITY, T0_NS + 100 * MS, sink);

  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(VCU_ADDRESS)});
  CHECK(sink.changes.empty());
  CHECK(sut.state() == ClaimState::Claiming);
  CHECK(sut.counters().contestsWon == 1);
  CHECK(sut.counters().claimsSent == 2);
  CHECK_FALSE(sut.table().taken(VCU_ADDRESS));  // the loser has to move
  CHECK(sut.nextDeadlineNs() == T0_NS + ADDRESS_CLAIM_WAIT_NS);
}

TEST_CASE("claimer defends a Claimed address too and stays Claimed") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.start(T0_NS, sink);
  sut.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS, sink);
  sink.clear();

  sut.onAddressClaimed(VCU_ADDRESS, LOWER_PRIORITY, T0_NS + 5'000 * MS, sink);

  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(VCU_ADDRESS)});
  CHECK(sut.state() == ClaimState::Claimed);
  CHECK(sut.mayTransmit());
}

TEST_CASE("claimer capable of any address loses to a higher-priority NAME and claims the first free one of the range") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.onAddressClaimed(RANGE_FIRST, THIRD_NODE, T0_NS - 1 * MS, sink);  // 128 is known taken
  sut.start(T0_NS, sink);
  sink.clear();
  const std::int64_t lostNs = T0_NS + 100 * MS;

  sut.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, lostNs, sink);

  CHECK(sink.changes == std::vector<AddressChange>{{VCU_ADDRESS, RANGE_SECOND, ClaimState::Claiming}});
  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(RANGE_SECOND)});
  CHECK(sut.address() == RANGE_SECOND);
  CHECK(sut.counters().contestsLost == 1);
  CHECK(sut.counters().addressesSkipped == 1);
  REQUIRE(sut.table().nameAt(VCU_ADDRESS));
  CHECK(*sut.table().nameAt(VCU_ADDRESS) == HIGHER_PRIORITY);
  // A new claim on 128..247: a new 250 ms window before other traffic.
  CHECK_FALSE(sut.mayTransmit());
  CHECK(sut.nextDeadlineNs() == lostNs + ADDRESS_CLAIM_WAIT_NS);
  sut.poll(lostNs + ADDRESS_CLAIM_WAIT_NS, sink);
  CHECK(sut.state() == ClaimState::Claimed);
  CHECK(sut.mayTransmit());
}

TEST_CASE("claimer losing an address of the range tries the next one, wrapping at the range end") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME, RANGE_THIRD, RANGE_FIRST, RANGE_THIRD});
  sut.start(T0_NS, sink);
  sink.clear();

  sut.onAddressClaimed(RANGE_THIRD, HIGHER_PRIORITY, T0_NS + 10 * MS, sink);
  CHECK(sut.address() == RANGE_FIRST);
  sut.onAddressClaimed(RANGE_FIRST, THIRD_NODE, T0_NS + 20 * MS, sink);
  CHECK(sut.address() == RANGE_SECOND);

  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(RANGE_FIRST), claimOf(RANGE_SECOND)});
  CHECK(sut.counters().contestsLost == 2);
}

TEST_CASE("claimer with the whole range taken sends Cannot Claim") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME, VCU_ADDRESS, RANGE_FIRST, RANGE_SECOND});
  sut.onAddressClaimed(RANGE_FIRST, THIRD_NODE, T0_NS - 2 * MS, sink);
  sut.onAddressClaimed(RANGE_SECOND, LOWER_PRIORITY, T0_NS - 1 * MS, sink);  // taken is taken
  sut.start(T0_NS, sink);
  sink.clear();

  sut.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS + 10 * MS, sink);

  CHECK(sink.changes == std::vector<AddressChange>{{VCU_ADDRESS, NULL_ADDRESS, ClaimState::CannotClaim}});
  CHECK(sink.frames == std::vector<ClaimFrame>{cannotClaimFrame(OUR_NAME)});
  CHECK(sink.frames[0].canId == 0x18EEFFFEu);
  CHECK(sut.state() == ClaimState::CannotClaim);
  CHECK(sut.address() == NULL_ADDRESS);
  CHECK_FALSE(sut.mayTransmit());
  CHECK(sut.counters().addressesSkipped == 2);
  CHECK(sut.counters().cannotClaimSent == 1);
}

TEST_CASE("claimer not capable of another address sends Cannot Claim when it loses and stops") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME_FIXED, VCU_ADDRESS});
  sut.start(T0_NS, sink);
  sut.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS, sink);
  sink.clear();

  sut.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS + 1'000 * MS, sink);

  CHECK(sink.changes == std::vector<AddressChange>{{VCU_ADDRESS, NULL_ADDRESS, ClaimState::CannotClaim}});
  CHECK(sink.frames == std::vector<ClaimFrame>{cannotClaimFrame(OUR_NAME_FIXED)});
  CHECK_FALSE(sut.mayTransmit());
  CHECK_FALSE(sut.nextDeadlineNs());
  sink.clear();
  // Later claims, even a loser's on our old address, change nothing but the table.
  sut.onAddressClaimed(VCU_ADDRESS, LOWER_PRIORITY, T0_NS + 2'000 * MS, sink);
  CHECK(sink.frames.empty());
  CHECK(sut.state() == ClaimState::CannotClaim);
  CHECK(*sut.table().nameAt(VCU_ADDRESS) == LOWER_PRIORITY);
}

TEST_CASE("claimer whose preferred address is held by a known higher-priority NAME starts elsewhere") {
  RecordingSink sink;
  AddressClaimer capable(VCU_CONFIG);
  AddressClaimer fixed({OUR_NAME_FIXED, VCU_ADDRESS});
  capable.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS - 1 * MS, sink);
  fixed.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS - 1 * MS, sink);

  capable.start(T0_NS, sink);
  fixed.start(T0_NS, sink);

  CHECK(capable.address() == RANGE_FIRST);
  CHECK(fixed.state() == ClaimState::CannotClaim);
  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(RANGE_FIRST), cannotClaimFrame(OUR_NAME_FIXED)});
}

TEST_CASE("claimer claims its preferred address even when a known lower-priority NAME holds it") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.onAddressClaimed(VCU_ADDRESS, LOWER_PRIORITY, T0_NS - 1 * MS, sink);

  sut.start(T0_NS, sink);

  CHECK(sut.address() == VCU_ADDRESS);
  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(VCU_ADDRESS)});
}

TEST_CASE("claimer without a usable preferred address starts in the range, or with Cannot Claim") {
  RecordingSink sink;
  AddressClaimer capable({OUR_NAME, NULL_ADDRESS});
  AddressClaimer fixed({OUR_NAME_FIXED, GLOBAL_ADDRESS});
  AddressClaimer emptyRange({OUR_NAME, NULL_ADDRESS, RANGE_SECOND, RANGE_FIRST});

  capable.start(T0_NS, sink);
  fixed.start(T0_NS, sink);
  emptyRange.start(T0_NS, sink);

  CHECK(capable.address() == RANGE_FIRST);
  CHECK(fixed.state() == ClaimState::CannotClaim);
  CHECK(emptyRange.state() == ClaimState::CannotClaim);
  CHECK(capable.counters().addressesSkipped == 0);
}

TEST_CASE("claimer answers a Request for Address Claimed to global or to its address, not to others") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.start(T0_NS, sink);
  sink.clear();

  sut.onRequestForAddressClaimed(GLOBAL_ADDRESS, T0_NS + 500 * MS, sink);
  sut.onRequestForAddressClaimed(VCU_ADDRESS, T0_NS + 600 * MS, sink);
  sut.onRequestForAddressClaimed(OTHER_ADDRESS, T0_NS + 700 * MS, sink);

  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(VCU_ADDRESS), claimOf(VCU_ADDRESS)});
  CHECK(sut.counters().requestsAnswered == 2);
  // The 250 ms window ended before the first request: Claimed was reported first.
  CHECK(sink.changes == std::vector<AddressChange>{{VCU_ADDRESS, VCU_ADDRESS, ClaimState::Claimed}});
}

TEST_CASE("claimer ignores a Request for Address Claimed before start") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);

  sut.onRequestForAddressClaimed(GLOBAL_ADDRESS, T0_NS, sink);

  CHECK(sink.frames.empty());
  CHECK(sut.state() == ClaimState::Idle);
  CHECK(sut.address() == NULL_ADDRESS);
  CHECK_FALSE(sut.mayTransmit());
}

TEST_CASE("claimer without an address answers a global Request with Cannot Claim after its pseudo-random delay") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME_FIXED, VCU_ADDRESS});
  sut.start(T0_NS, sink);
  sut.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS + 10 * MS, sink);
  sink.clear();
  const std::int64_t requestNs = T0_NS + 1'000 * MS;
  const std::int64_t delayNs = cannotClaimDelayNs(OUR_NAME_FIXED);
  REQUIRE(delayNs > 0);  // this NAME's delay; 0 would answer at once

  sut.onRequestForAddressClaimed(VIC_ADDRESS, requestNs, sink);  // to an address: not ours
  sut.onRequestForAddressClaimed(GLOBAL_ADDRESS, requestNs, sink);
  sut.onRequestForAddressClaimed(GLOBAL_ADDRESS, requestNs + 1 * MS, sink);  // no second, no later one

  CHECK(sink.frames.empty());
  CHECK(sut.nextDeadlineNs() == requestNs + delayNs);
  sut.poll(requestNs + delayNs - 1, sink);
  CHECK(sink.frames.empty());
  sut.poll(requestNs + delayNs, sink);
  CHECK(sink.frames == std::vector<ClaimFrame>{cannotClaimFrame(OUR_NAME_FIXED)});
  CHECK_FALSE(sut.nextDeadlineNs());
  CHECK(sut.counters().cannotClaimSent == 2);  // when it lost, and this answer
  CHECK(sut.counters().requestsAnswered == 2);
}

TEST_CASE("Cannot Claim delays stay within 0..153 ms and differ between NAMEs") {
  std::set<std::int64_t> delays;
  for (std::uint32_t identity = 0; identity < 64; ++identity) {
    Name name = OUR_NAME;
    name.identityNumber = identity;
    const std::int64_t delayNs = cannotClaimDelayNs(name);
    CHECK(delayNs >= 0);
    CHECK(delayNs <= CANNOT_CLAIM_MAX_DELAY_NS);
    CHECK(delayNs % CANNOT_CLAIM_DELAY_STEP_NS == 0);
    delays.insert(delayNs);
  }
  CHECK(delays.size() > 32);  // 64 NAMEs: most of them apart
}

TEST_CASE("claimer records a claim for another address in its table and nothing else") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.start(T0_NS, sink);
  sink.clear();

  sut.onAddressClaimed(OTHER_ADDRESS, HIGHER_PRIORITY, T0_NS + 10 * MS, sink);
  sut.onAddressClaimed(VIC_ADDRESS, LOWER_PRIORITY, T0_NS + 20 * MS, sink);

  CHECK(sink.frames.empty());
  CHECK(sink.changes.empty());
  CHECK(sut.address() == VCU_ADDRESS);
  CHECK(sut.table().size() == 2);
  CHECK(sut.table().addressOf(HIGHER_PRIORITY) == OTHER_ADDRESS);
  CHECK(sut.counters().contestsWon + sut.counters().contestsLost == 0);
}

TEST_CASE("claimer drops a node that sends Cannot Claim from its table") {
  RecordingSink sink;
  AddressClaimer sut(VCU_CONFIG);
  sut.start(T0_NS, sink);
  sut.onAddressClaimed(OTHER_ADDRESS, LOWER_PRIORITY, T0_NS + 10 * MS, sink);
  sink.clear();

  sut.onAddressClaimed(NULL_ADDRESS, LOWER_PRIORITY, T0_NS + 20 * MS, sink);

  CHECK(sut.table().empty());
  CHECK(sink.frames.empty());
  CHECK(sut.address() == VCU_ADDRESS);
}

TEST_CASE("claimer started again claims its preferred address again and keeps its counters") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME_FIXED, VCU_ADDRESS});
  sut.start(T0_NS, sink);
  sut.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS + 10 * MS, sink);
  sut.onAddressClaimed(NULL_ADDRESS, HIGHER_PRIORITY, T0_NS + 20 * MS, sink);  // the winner left
  sink.clear();

  sut.start(T0_NS + 1'000 * MS, sink);

  CHECK(sut.state() == ClaimState::Claiming);
  CHECK(sink.changes == std::vector<AddressChange>{{NULL_ADDRESS, VCU_ADDRESS, ClaimState::Claiming}});
  CHECK(sink.frames == std::vector<ClaimFrame>{claimOf(VCU_ADDRESS, OUR_NAME_FIXED)});
  CHECK(sut.counters().claimsSent == 2);
}

TEST_CASE("parseAddressClaimed reads the source and NAME of PGN 60928 frames only") {
  const NamePayload bytes = encodeName(OUR_NAME);
  const std::array<std::uint8_t, 7> shortPayload{};

  const std::optional<AddressClaimed> maybeSut = parseAddressClaimed(0x18EEFF21u, true, bytes);

  REQUIRE(maybeSut);
  CHECK(*maybeSut == AddressClaimed{VCU_ADDRESS, OUR_NAME});
  CHECK(parseAddressClaimed(0x18EEFFFEu, true, bytes) == AddressClaimed{NULL_ADDRESS, OUR_NAME});
  CHECK(parseAddressClaimed(0x18EEF321u, true, bytes) == AddressClaimed{VCU_ADDRESS, OUR_NAME});  // to one address
  CHECK_FALSE(parseAddressClaimed(0x18EEFF21u, false, bytes));                                    // standard frame
  CHECK_FALSE(parseAddressClaimed(0x18EFFF21u, true, bytes));                                     // PGN 0xEF00
  CHECK_FALSE(parseAddressClaimed(0x19EEFF21u, true, bytes));  // data page 1: PGN 0x1EE00
  CHECK_FALSE(parseAddressClaimed(0x18EEFF21u, true, shortPayload));
}

TEST_CASE("claimer reports the address it lost and the claimant's NAME before it gives the address up") {
  RecordingSink sink;
  AddressClaimer fixed({OUR_NAME_FIXED, VCU_ADDRESS});
  fixed.start(T0_NS, sink);
  fixed.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS, sink);
  sink.clear();

  fixed.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS + 1'000 * MS, sink);

  CHECK(sink.losses == std::vector<AddressClaimed>{{VCU_ADDRESS, HIGHER_PRIORITY}});
  CHECK(sink.lossBeforeChange == std::vector<std::size_t>{0});
  CHECK(sink.changes == std::vector<AddressChange>{{VCU_ADDRESS, NULL_ADDRESS, ClaimState::CannotClaim}});

  RecordingSink capableSink;
  AddressClaimer capable(VCU_CONFIG);
  capable.start(T0_NS, capableSink);
  capable.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS, capableSink);
  capableSink.clear();
  capable.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS + 1'000 * MS, capableSink);
  CHECK(capableSink.losses == std::vector<AddressClaimed>{{VCU_ADDRESS, HIGHER_PRIORITY}});
  CHECK(capableSink.changes == std::vector<AddressChange>{{VCU_ADDRESS, RANGE_FIRST, ClaimState::Claiming}});
}

TEST_CASE("claimer reports a preferred address a known higher-priority NAME holds at start") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME_FIXED, VCU_ADDRESS});
  sut.onAddressClaimed(VCU_ADDRESS, HIGHER_PRIORITY, T0_NS - 1 * MS, sink);
  CHECK(sink.losses.empty());  // not ours yet: only the table

  sut.start(T0_NS, sink);

  CHECK(sink.losses == std::vector<AddressClaimed>{{VCU_ADDRESS, HIGHER_PRIORITY}});
  CHECK(sut.state() == ClaimState::CannotClaim);
}

TEST_CASE("claimer does not report a defended address or claims of addresses it does not hold") {
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME_FIXED, VCU_ADDRESS});
  sut.start(T0_NS, sink);

  sut.onAddressClaimed(VCU_ADDRESS, LOWER_PRIORITY, T0_NS + 1 * MS, sink);  // defended
  sut.onAddressClaimed(OTHER_ADDRESS, HIGHER_PRIORITY, T0_NS + 2 * MS, sink);
  sut.onAddressClaimed(VCU_ADDRESS, OUR_NAME_FIXED, T0_NS + 3 * MS, sink);  // our echo

  CHECK(sink.losses.empty());
  CHECK(sut.address() == VCU_ADDRESS);
}

TEST_CASE("claimer without an address stays without one however often a hostile node claims (no wandering)") {
  // A node that claims the VCU's address with a NAME one below the VCU's, again and again.
  constexpr Name HOSTILE = Name::fromValue(0x3002800000000100u - 1);
  RecordingSink sink;
  AddressClaimer sut({OUR_NAME_FIXED, VCU_ADDRESS});
  sut.start(T0_NS, sink);
  sut.poll(T0_NS + ADDRESS_CLAIM_WAIT_NS, sink);
  sut.onAddressClaimed(VCU_ADDRESS, HOSTILE, T0_NS + 1'000 * MS, sink);
  REQUIRE(sut.state() == ClaimState::CannotClaim);
  REQUIRE(sink.losses.size() == 1);
  sink.clear();

  constexpr int REPEATS = 20;
  for (int i = 0; i < REPEATS; ++i) {
    const std::int64_t at = T0_NS + (2'000 + 10 * i) * MS;
    sut.onAddressClaimed(VCU_ADDRESS, HOSTILE, at, sink);
    sut.onAddressClaimed(static_cast<std::uint8_t>(RANGE_FIRST + i), HOSTILE, at, sink);
    sut.poll(at + 5 * MS, sink);
  }

  CHECK(sink.frames.empty());
  CHECK(sink.changes.empty());
  CHECK(sink.losses.empty());
  CHECK(sut.state() == ClaimState::CannotClaim);
  CHECK(sut.address() == NULL_ADDRESS);
  CHECK_FALSE(sut.mayTransmit());
  CHECK(sut.counters().claimsSent == 1);  // the claim at start, never one from another address
  CHECK(sut.counters().cannotClaimSent == 1);
}
