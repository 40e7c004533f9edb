// cantx::Network on the HHEA configuration (vehicle.json, diagnostics.json, fsm.json) with a
// recording TxPort and a set clock: J1939-81 address claim, the VCU's DM1/DM2/DM3/DM11,
// identification answers and TP sending (issue 24).

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <string>
#include <vector>

#include "network.hpp"
#include "openvcu/config/diagnostics.hpp"
#include "openvcu/fsm/engine.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/address_claim.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/dm_encode.hpp"
#include "vehicle_fixture.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START = 5'000 * MS;
const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
constexpr std::uint64_t OUR_NAME = 0x3002800000000001u;              // config/hhea/vehicle.json: fixed address
constexpr std::uint64_t AAC_BIT = std::uint64_t{1} << 63;            // arbitrary address capable
constexpr std::uint64_t HIGHER_PRIORITY_NAME = 0x0000000000000010u;  // lower value wins
constexpr std::uint64_t LOWER_PRIORITY_NAME = 0xFFFFFFFFFFFFFFF0u;
constexpr std::uint8_t TOOL = 0xF9;  // a service tool's address
constexpr std::uint32_t CLAIM_FROM_21 = 0x18EEFF21;
constexpr std::uint32_t DM1_FROM_21 = 0x18FECA21;     // priority 6, PGN 65226
constexpr std::uint32_t DM2_FROM_21 = 0x18FECB21;     // priority 6, PGN 65227
constexpr std::uint32_t BAM_CM_FROM_21 = 0x1CECFF21;  // TP.CM, priority 7, to global
constexpr std::uint32_t BAM_DT_FROM_21 = 0x1CEBFF21;  // TP.DT, priority 7, to global
constexpr std::uint32_t ACK_FROM_21 = 0x18E8FF21;
constexpr std::uint32_t SCHEDULED = 0x0CFF0021;  // a proprietary frame from the preferred address
constexpr std::uint32_t CRASH_SPN = 520199;
constexpr std::uint8_t CRASH_FMI = 31;
constexpr std::uint32_t KEEP_ALIVE_SPN = 520300;  // the signal DTC the tests add
constexpr std::uint8_t KEEP_ALIVE_FMI = 31;

struct Sent {
  std::size_t bus;
  can::Frame frame;
};

struct Recorder final : cantx::TxPort {
  std::vector<Sent> frames;
  can::SendStatus send(std::size_t bus, const can::Frame& frame) noexcept override {
    frames.push_back({bus, frame});
    return can::SendStatus::Sent;
  }
  [[nodiscard]] std::vector<can::Frame> withId(std::uint32_t id) const {
    std::vector<can::Frame> matching;
    for (const Sent& sent : frames) {
      if (sent.frame.id == id) matching.push_back(sent.frame);
    }
    return matching;
  }
};

std::vector<std::uint8_t> bytes(const can::Frame& frame) {
  return {frame.data.begin(), frame.data.begin() + frame.length};
}

std::vector<std::uint8_t> nameBytes(std::uint64_t name) {
  std::vector<std::uint8_t> out;
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(name >> (8 * i)));
  return out;
}

can::Frame extended(std::uint32_t id, std::vector<std::uint8_t> data) {
  can::Frame frame;
  frame.id = id;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), frame.data.begin());
  return frame;
}

can::Frame claimFrame(std::uint8_t address, std::uint64_t name) {
  return extended(0x18EEFF00u | address, nameBytes(name));
}

/// The payload of a TP session: the TP.DT packets with `dtId`, in order, cut to `size`.
std::vector<std::uint8_t> reassemble(const std::vector<can::Frame>& packets, std::size_t size) {
  std::vector<std::uint8_t> payload;
  for (const can::Frame& packet : packets)
    payload.insert(payload.end(), packet.data.begin() + 1, packet.data.begin() + 8);
  payload.resize(std::min(size, payload.size()));
  return payload;
}

struct Fixture : openvcu::testing::VehicleTable {
  std::vector<std::string> fsmStates;
  config::DiagnosticsConfig diagnostics;
  Recorder port;
  std::unique_ptr<cantx::Network> sut;
  std::size_t bus{};
  std::int64_t now{START};

  Fixture() : VehicleTable(HHEA, "txnet-" + std::to_string(::getpid())) {
    auto machineResult = fsm::loadMachine(vehicle.fsmFile, vehicle, catalog);
    REQUIRE_MESSAGE(machineResult, (machineResult ? "" : machineResult.error().toString()));
    for (const fsm::State& state : machineResult->states) fsmStates.push_back(state.name);
    auto diagnosticsResult = config::loadDiagnosticsConfig(vehicle, catalog, &fsmStates);
    REQUIRE_MESSAGE(diagnosticsResult, (diagnosticsResult ? "" : diagnosticsResult.error().toString()));
    diagnostics = std::move(*diagnosticsResult);
    bool found = false;
    for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
      if (vehicle.buses[b].j1939) {
        bus = b;
        found = true;
      }
    }
    REQUIRE(found);
  }

  /// A second DTC raised by an internal signal (HHEA's diagnostics.json has only FSM states).
  void addSignalDtc() {
    config::DtcConfig dtc;
    dtc.name = "keep alive";
    dtc.path = "/dtcs/9";
    dtc.source = config::DtcSource::Signal;
    dtc.signal = "internal.tx.keepAlive";
    dtc.compare = config::DtcCompare::Ne;
    dtc.value = 0;
    dtc.definition.spn = KEEP_ALIVE_SPN;
    dtc.definition.fmi = KEEP_ALIVE_FMI;
    dtc.definition.lamps.amberWarning = true;
    diagnostics.dtcs.push_back(dtc);
  }

  void create() {
    auto created = cantx::Network::create(vehicle, diagnostics, fsmStates, catalog, *table, port, "1.2.3");
    REQUIRE_MESSAGE(created, (created ? "" : created.error().toString()));
    sut = std::move(*created);
  }
  void start() {
    create();
    sut->start(now);
  }
  signals::SignalIndex key(const std::string& name) {
    const auto index = catalog.indexOf(name);
    REQUIRE_MESSAGE(index, name);
    return *index;
  }
  /// internal.fsm.state as vcu-fsm writes it: the state's index, a command of the FSM writer.
  void enterState(const std::string& state) {
    const auto found = std::find(fsmStates.begin(), fsmStates.end(), state);
    REQUIRE_MESSAGE(found != fsmStates.end(), state);
    REQUIRE(table->writeCommand(key("internal.fsm.state"), static_cast<double>(found - fsmStates.begin()), now,
                                fsm::FSM_WRITER));
  }
  void runAt(std::int64_t at) {
    now = at;
    sut->run(now);
  }
  /// Runs at each deadline up to `until`, as the transmit thread does.
  void runUntil(std::int64_t until) {
    for (;;) {
      const std::int64_t next = std::max(sut->nextDeadlineNs(), now);
      if (next > until) break;
      runAt(next);
    }
    now = until;
  }
  can::SendStatus sendScheduled(std::uint32_t id) { return sut->send(bus, extended(id, {1, 2, 3, 4, 5, 6, 7, 8})); }
  bool request(std::uint32_t pgn, std::uint8_t requester, bool global) {
    return sut->answerRequest(bus, j1939::Request{pgn, requester, global}, now);
  }
};

}  // namespace

TEST_CASE("network: start claims the preferred address with the NAME LSB first and passes scheduled frames") {
  Fixture f;
  f.start();
  const auto claims = f.port.withId(CLAIM_FROM_21);
  REQUIRE(claims.size() == 1);
  CHECK(bytes(claims[0]) == nameBytes(OUR_NAME));
  CHECK(f.port.frames[0].bus == f.bus);
  f.port.frames.clear();
  CHECK(f.sendScheduled(SCHEDULED) == can::SendStatus::Sent);
  REQUIRE(f.port.frames.size() == 1);
  CHECK(f.port.frames[0].frame.id == SCHEDULED);
  CHECK(bytes(f.port.frames[0].frame) == std::vector<std::uint8_t>{1, 2, 3, 4, 5, 6, 7, 8});
}

TEST_CASE("network: a higher-priority NAME takes 0x21 and the VCU moves into 128..247 with its frames") {
  Fixture f;
  f.vehicle.buses[f.bus].j1939->name.arbitraryAddressCapable = true;  // may move
  f.start();
  f.runAt(START + 300 * MS);
  f.port.frames.clear();
  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now);
  REQUIRE(f.port.frames.size() == 1);
  const can::Frame claim = f.port.frames[0].frame;
  CHECK((claim.id & 0xFFFFFF00u) == 0x18EEFF00u);
  const std::uint8_t moved = static_cast<std::uint8_t>(claim.id & 0xFFu);
  CHECK(moved >= 128);
  CHECK(moved <= 247);
  CHECK(bytes(claim) == nameBytes(OUR_NAME | AAC_BIT));
  CHECK(f.sut->counters().contestsLost.load() == 1);
  // 128..247: 250 ms before other traffic
  CHECK(f.sendScheduled(SCHEDULED) == can::SendStatus::Down);
  f.runUntil(f.now + 300 * MS);
  f.port.frames.clear();
  CHECK(f.sendScheduled(SCHEDULED) == can::SendStatus::Sent);
  CHECK(f.sendScheduled(0x0CFF0030) == can::SendStatus::Sent);
  REQUIRE(f.port.frames.size() == 2);
  CHECK(f.port.frames[0].frame.id == (0x0CFF0000u | moved));
  CHECK(f.port.frames[1].frame.id == 0x0CFF0030u);
  const auto view = f.sut->snapshot();
  REQUIRE(view.size() == 1);
  CHECK(view[0].address == moved);
}

TEST_CASE("network: a lower-priority NAME claiming 0x21 is answered with our claim and changes nothing") {
  Fixture f;
  f.start();
  f.runAt(START + 300 * MS);
  f.port.frames.clear();
  f.sut->onFrame(f.bus, claimFrame(0x21, LOWER_PRIORITY_NAME), f.now);
  const auto claims = f.port.withId(CLAIM_FROM_21);
  REQUIRE(claims.size() == 1);
  CHECK(bytes(claims[0]) == nameBytes(OUR_NAME));
  CHECK(f.sut->counters().contestsWon.load() == 1);
  f.port.frames.clear();
  CHECK(f.sendScheduled(SCHEDULED) == can::SendStatus::Sent);
  REQUIRE(f.port.frames.size() == 1);
  CHECK(f.port.frames[0].frame.id == SCHEDULED);
}

TEST_CASE(
    "network: a NAME that is not arbitrary-address capable sends Cannot Claim when it loses and holds its frames") {
  Fixture f;
  f.vehicle.buses[f.bus].j1939->name.arbitraryAddressCapable = false;
  f.start();
  f.runAt(START + 300 * MS);
  f.port.frames.clear();
  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now);
  f.runUntil(f.now + 200 * MS);
  const auto cannot = f.port.withId(0x18EEFFFEu);
  REQUIRE(cannot.size() == 1);
  CHECK(bytes(cannot[0]) == nameBytes(OUR_NAME & ~AAC_BIT));
  CHECK(f.sut->counters().cannotClaim.load() == 1);
  f.port.frames.clear();
  CHECK(f.sendScheduled(SCHEDULED) == can::SendStatus::Down);
  CHECK(f.port.frames.empty());
  CHECK(f.sut->counters().framesHeldByClaim.load() == 1);
  const auto view = f.sut->snapshot();
  REQUIRE(view.size() == 1);
  CHECK(view[0].claimState == ipc::ClaimState::CannotClaim);
  const auto dm1Before = f.sut->counters().dm1Sent.load();
  f.runUntil(f.now + 2000 * MS);
  CHECK(f.port.frames.empty());  // no DM1 either
  CHECK(f.sut->counters().dm1Sent.load() == dm1Before);
}

TEST_CASE("network: an FSM fault state raises its DTC in a DM1 once per second") {
  Fixture f;
  f.enterState("Crash");
  f.start();
  f.runAt(START);
  auto dm1s = f.port.withId(DM1_FROM_21);
  REQUIRE(dm1s.size() == 1);
  const auto dm1 = j1939::decodeDm1(bytes(dm1s[0]));
  REQUIRE(dm1);
  CHECK(dm1->dtcCount == 1);
  CHECK(dm1->contains(CRASH_SPN, CRASH_FMI));
  CHECK(dm1->dtcs[0].occurrenceCount == 1);
  CHECK(dm1->lamps.redStop == j1939::LampStatus::On);
  CHECK(dm1->lamps.redStopFlash == j1939::LampFlash::Fast);
  f.runUntil(START + 999 * MS);
  CHECK(f.port.withId(DM1_FROM_21).size() == 1);
  f.runUntil(START + 1000 * MS);
  CHECK(f.port.withId(DM1_FROM_21).size() == 2);
  f.runUntil(START + 3000 * MS);
  CHECK(f.port.withId(DM1_FROM_21).size() == 4);
  CHECK(f.sut->counters().dm1Sent.load() == 4);
}

TEST_CASE("network: two active DTCs go out by BAM with TP.DT packets 50 ms apart") {
  Fixture f;
  f.addSignalDtc();
  f.enterState("Crash");
  REQUIRE(f.table->writeCommand(f.key("internal.tx.keepAlive"), 1, f.now, 3));
  f.start();
  f.runAt(START);
  const auto announce = f.port.withId(BAM_CM_FROM_21);
  REQUIRE(announce.size() == 1);
  // 20 = BAM, 10 bytes (2 lamp bytes + 2 DTCs), 2 packets, FF, PGN 65226
  CHECK(bytes(announce[0]) == std::vector<std::uint8_t>{0x20, 10, 0, 2, 0xFF, 0xCA, 0xFE, 0x00});
  CHECK(f.port.withId(BAM_DT_FROM_21).empty());
  f.runUntil(START + 49 * MS);
  CHECK(f.port.withId(BAM_DT_FROM_21).empty());
  f.runUntil(START + 50 * MS);
  CHECK(f.port.withId(BAM_DT_FROM_21).size() == 1);
  f.runUntil(START + 99 * MS);
  CHECK(f.port.withId(BAM_DT_FROM_21).size() == 1);
  f.runUntil(START + 100 * MS);
  const auto packets = f.port.withId(BAM_DT_FROM_21);
  REQUIRE(packets.size() == 2);
  CHECK(packets[0].data[0] == 1);
  CHECK(packets[1].data[0] == 2);
  const auto dm1 = j1939::decodeDm1(reassemble(packets, 10));
  REQUIRE(dm1);
  CHECK(dm1->dtcCount == 2);
  CHECK(dm1->contains(CRASH_SPN, CRASH_FMI));
  CHECK(dm1->contains(KEEP_ALIVE_SPN, KEEP_ALIVE_FMI));
  CHECK(f.port.withId(DM1_FROM_21).empty());
  CHECK(f.sut->counters().tpCompleted.load() == 1);
}

TEST_CASE("network: a cleared fault is in DM2 with count 1 and an accepted DM3 clears it with a positive ACK") {
  Fixture f;
  f.diagnostics.dm3 = config::ClearPolicy::Accept;  // HHEA's diagnostics.json refuses clears
  f.enterState("Crash");
  f.start();
  f.runAt(START);
  auto saved = f.sut->takeCountsToSave();
  REQUIRE(saved);
  const auto crash =
      std::find_if(saved->begin(), saved->end(), [](const j1939::Dtc& dtc) { return dtc.spn == CRASH_SPN; });
  REQUIRE(crash != saved->end());
  CHECK(crash->occurrenceCount == 1);
  CHECK_FALSE(f.sut->takeCountsToSave());
  f.port.frames.clear();
  f.enterState(f.fsmStates.front());
  f.runUntil(START + 1000 * MS);  // the on-change DM1 at START counts for this period
  const auto onChange = f.port.withId(DM1_FROM_21);
  REQUIRE(onChange.size() == 1);
  const auto cleared = j1939::decodeDm1(bytes(onChange[0]));
  CHECK((!cleared || cleared->dtcCount == 0));
  const auto view = f.sut->snapshot();
  REQUIRE(view.size() == 1);
  REQUIRE(view[0].dtcs.size() == 1);
  CHECK(view[0].dtcs[0] == ipc::J1939Dtc{"crash", CRASH_SPN, CRASH_FMI, 1, false});
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_DM2, TOOL, true));
  auto dm2s = f.port.withId(DM2_FROM_21);
  REQUIRE(dm2s.size() == 1);
  auto dm2 = j1939::decodeDm1(bytes(dm2s[0]));
  REQUIRE(dm2);
  REQUIRE(dm2->dtcCount == 1);
  CHECK(dm2->dtcs[0].spn == CRASH_SPN);
  CHECK(dm2->dtcs[0].fmi == CRASH_FMI);
  CHECK(dm2->dtcs[0].occurrenceCount == 1);

  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_DM3, TOOL, false));
  const auto acks = f.port.withId(ACK_FROM_21);
  REQUIRE(acks.size() == 1);
  CHECK(acks[0].data[0] == 0);  // positive
  CHECK(acks[0].data[4] == TOOL);
  CHECK(acks[0].data[5] == 0xCC);  // PGN 65228 LSB first
  CHECK(acks[0].data[6] == 0xFE);
  CHECK(f.sut->counters().clearsAccepted.load() == 1);
  f.runAt(f.now + 1 * MS);
  saved = f.sut->takeCountsToSave();
  REQUIRE(saved);
  for (const j1939::Dtc& dtc : *saved) CHECK(dtc.occurrenceCount == 0);
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_DM2, TOOL, true));
  dm2s = f.port.withId(DM2_FROM_21);
  REQUIRE(dm2s.size() == 1);
  dm2 = j1939::decodeDm1(bytes(dm2s[0]));
  CHECK((!dm2 || dm2->dtcCount == 0));
}

TEST_CASE("network: DM11 refused by configuration is answered with Access denied and clears nothing") {
  Fixture f;
  f.diagnostics.dm11 = config::ClearPolicy::Refuse;
  f.enterState("Crash");
  f.start();
  f.runAt(START);
  (void)f.sut->takeCountsToSave();
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_DM11, TOOL, true));
  const auto acks = f.port.withId(ACK_FROM_21);
  REQUIRE(acks.size() == 1);
  CHECK(acks[0].data[0] == 2);  // access denied
  CHECK(f.sut->counters().clearsRefused.load() == 1);
  f.runAt(f.now + 1 * MS);
  CHECK_FALSE(f.sut->takeCountsToSave());
  const auto view = f.sut->snapshot();
  REQUIRE(view.size() == 1);
  REQUIRE(view[0].dtcs.size() == 1);
  CHECK(view[0].dtcs[0].active);
}

TEST_CASE("network: a global SOFT request is answered by BAM with the configured fields and the version") {
  Fixture f;
  f.start();
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_SOFTWARE_IDENTIFICATION, TOOL, true));
  const auto announce = f.port.withId(BAM_CM_FROM_21);
  REQUIRE(announce.size() == 1);
  CHECK(announce[0].data[0] == 0x20);
  CHECK(announce[0].data[5] == 0xDA);
  CHECK(announce[0].data[6] == 0xFE);
  const std::size_t size = announce[0].data[1] | (announce[0].data[2] << 8);
  f.runUntil(START + 1000 * MS);
  const auto payload = reassemble(f.port.withId(BAM_DT_FROM_21), size);
  const std::string expected = "openvcu*openvcu 1.2.3*";
  REQUIRE(payload.size() == expected.size() + 1);
  CHECK(payload[0] == 2);  // number of fields
  CHECK(std::string(payload.begin() + 1, payload.end()) == expected);
}

TEST_CASE("network: a destination-specific ECUID request goes by RTS/CTS to the requester") {
  Fixture f;
  f.start();
  f.runAt(START + 300 * MS);
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_ECU_IDENTIFICATION, TOOL, false));
  const auto rts = f.port.withId(0x1CECF921u);
  REQUIRE(rts.size() == 1);
  CHECK(rts[0].data[0] == 0x10);
  CHECK(rts[0].data[5] == 0xC5);
  CHECK(rts[0].data[6] == 0xFD);
  const std::size_t size = rts[0].data[1] | (rts[0].data[2] << 8);
  const std::uint8_t packets = rts[0].data[3];
  const std::uint8_t window = rts[0].data[4];
  REQUIRE(window >= 1);
  CHECK(f.port.withId(BAM_CM_FROM_21).empty());
  for (std::uint8_t next = 1; next <= packets; next = static_cast<std::uint8_t>(next + window)) {
    const auto count = static_cast<std::uint8_t>(std::min<int>(window, packets - next + 1));
    f.sut->onFrame(f.bus, extended(0x1CEC21F9u, {0x11, count, next, 0xFF, 0xFF, 0xC5, 0xFD, 0x00}), f.now);
    f.runUntil(f.now + 100 * MS);
    CHECK(f.port.withId(0x1CEBF921u).size() == static_cast<std::size_t>(next + count - 1));
  }
  const auto data = f.port.withId(0x1CEBF921u);
  REQUIRE(data.size() == packets);
  const auto payload = reassemble(data, size);
  CHECK(std::string(payload.begin(), payload.end()) ==
        "OPENVCU-HHEA*0001*cab*VCU*University of Minnesota*Raspberry Pi*");
  CHECK(f.sut->counters().tpCompleted.load() == 0);
  f.sut->onFrame(f.bus,
                 extended(0x1CEC21F9u, {0x13, static_cast<std::uint8_t>(size), static_cast<std::uint8_t>(size >> 8),
                                        packets, 0xFF, 0xC5, 0xFD, 0x00}),
                 f.now);
  CHECK(f.sut->counters().tpCompleted.load() == 1);
  CHECK(f.sut->counters().tpFailed.load() == 0);
}

TEST_CASE("network: a Request for Address Claimed gets our claim and an unknown PGN is left to the scheduler") {
  Fixture f;
  f.start();
  f.runAt(START + 300 * MS);
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_ADDRESS_CLAIMED, TOOL, true));
  const auto claims = f.port.withId(CLAIM_FROM_21);
  REQUIRE(claims.size() == 1);
  CHECK(bytes(claims[0]) == nameBytes(OUR_NAME));
  f.port.frames.clear();
  CHECK_FALSE(f.request(0xFEE6, TOOL, true));
  CHECK(f.port.frames.empty());
}

TEST_CASE("network: the snapshot shows the claim and the nodes seen and the DTCs with names and counts and the lamps") {
  Fixture f;
  f.start();
  f.sut->onFrame(f.bus, claimFrame(0x30, LOWER_PRIORITY_NAME), f.now);
  f.enterState("Crash");
  f.runUntil(START + 300 * MS);
  const auto view = f.sut->snapshot();
  REQUIRE(view.size() == 1);
  CHECK(view[0].claimState == ipc::ClaimState::Claimed);
  CHECK(view[0].address == 0x21);
  CHECK(view[0].name == OUR_NAME);
  CHECK(view[0].bus == f.vehicle.buses[f.bus].name);
  REQUIRE(view[0].nodes.size() == 1);
  CHECK(view[0].nodes[0] == ipc::J1939Node{0x30, LOWER_PRIORITY_NAME});
  REQUIRE(view[0].dtcs.size() == 1);
  CHECK(view[0].dtcs[0] == ipc::J1939Dtc{"crash", CRASH_SPN, CRASH_FMI, 1, true});
  CHECK((view[0].lamps & 0x30) == 0x10);  // red stop on
  CHECK(f.sut->takeChanged());
}

TEST_CASE("network: restored occurrence counts continue when the fault comes back") {
  Fixture f;
  const j1939::Dtc restored[] = {{CRASH_SPN, CRASH_FMI, 4, false}};
  f.create();
  f.sut->restoreCounts(restored);
  f.enterState("Crash");
  f.sut->start(f.now);
  f.runAt(START);
  const auto dm1s = f.port.withId(DM1_FROM_21);
  REQUIRE(dm1s.size() == 1);
  const auto dm1 = j1939::decodeDm1(bytes(dm1s[0]));
  REQUIRE(dm1);
  REQUIRE(dm1->dtcCount == 1);
  CHECK(dm1->dtcs[0].occurrenceCount == 5);
  const auto saved = f.sut->takeCountsToSave();
  REQUIRE(saved);
  const auto crash =
      std::find_if(saved->begin(), saved->end(), [](const j1939::Dtc& dtc) { return dtc.spn == CRASH_SPN; });
  REQUIRE(crash != saved->end());
  CHECK(crash->occurrenceCount == 5);
}

TEST_CASE("network: a destination-specific request for a one-frame PDU2 answer is answered to global") {
  Fixture f;
  f.enterState("Crash");
  f.start();
  f.runAt(START);
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_DM1, TOOL, false));
  const auto dm1s = f.port.withId(DM1_FROM_21);  // PDU2 has no destination address
  REQUIRE(dm1s.size() == 1);
  const auto dm1 = j1939::decodeDm1(bytes(dm1s[0]));
  REQUIRE(dm1);
  CHECK(dm1->contains(CRASH_SPN, CRASH_FMI));
  CHECK(f.port.frames.size() == 1);
}

TEST_CASE("network: answers after a lost contest leave from the new address") {
  Fixture f;
  f.vehicle.buses[f.bus].j1939->name.arbitraryAddressCapable = true;  // may move
  f.start();
  f.runAt(START + 300 * MS);
  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now);
  const std::uint8_t moved = static_cast<std::uint8_t>(f.port.frames.back().frame.id & 0xFFu);
  REQUIRE(moved != 0x21);
  f.runUntil(f.now + 300 * MS);
  f.port.frames.clear();
  CHECK(f.request(j1939::PGN_SOFTWARE_IDENTIFICATION, TOOL, true));
  CHECK(f.port.withId(BAM_CM_FROM_21).empty());
  CHECK(f.port.withId(0x1CECFF00u | moved).size() == 1);
}

TEST_CASE("network: Cannot Claim ends a transport session in progress") {
  Fixture f;
  f.vehicle.buses[f.bus].j1939->name.arbitraryAddressCapable = false;
  f.start();
  f.runAt(START + 300 * MS);
  CHECK(f.request(j1939::PGN_ECU_IDENTIFICATION, TOOL, false));
  REQUIRE(f.port.withId(0x1CECF921u).size() == 1);
  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now);
  f.runUntil(f.now + 200 * MS);
  CHECK(f.sut->counters().tpFailed.load() == 1);
  CHECK(f.sut->counters().tpCompleted.load() == 0);
  const auto view = f.sut->snapshot();
  REQUIRE(view.size() == 1);
  CHECK(view[0].address == j1939::NULL_ADDRESS);
}

TEST_CASE("network: the log names the address change after a lost contest") {
  Fixture f;
  f.vehicle.buses[f.bus].j1939->name.arbitraryAddressCapable = true;  // may move
  f.start();
  f.runAt(START + 300 * MS);
  (void)f.sut->takeLog();
  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now);
  const auto lines = f.sut->takeLog();
  REQUIRE(lines.size() == 1);
  CHECK(lines[0].find("0x21 -> 0x") != std::string::npos);
  CHECK(lines[0].find(f.vehicle.buses[f.bus].name) != std::string::npos);
  CHECK(f.sut->takeLog().empty());
}

TEST_CASE("network: a scheduled message longer than 8 bytes leaves a classic bus by the transport protocol") {
  Fixture f;
  f.start();
  f.port.frames.clear();
  std::vector<std::uint8_t> payload(20);
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<std::uint8_t>(0xA0 + i);
  f.sut->setNow(f.now);
  // PDU2 0xFF40 (proprietary B) from the preferred address: BAM to global, 3 packets
  CHECK(f.sut->send(f.bus, extended(0x18FF4021, payload)) == can::SendStatus::Sent);
  REQUIRE(f.port.withId(BAM_CM_FROM_21).size() == 1);
  CHECK(bytes(f.port.withId(BAM_CM_FROM_21)[0]) == std::vector<std::uint8_t>{0x20, 20, 0, 3, 0xFF, 0x40, 0xFF, 0x00});
  f.runUntil(f.now + 200 * MS);
  CHECK(reassemble(f.port.withId(BAM_DT_FROM_21), payload.size()) == payload);
  // a long message of another source address cannot go by TP from the VCU's address
  f.port.frames.clear();
  (void)f.sut->send(f.bus, extended(0x18FF40E5, payload));
  REQUIRE(f.port.frames.size() == 1);
  CHECK(f.port.frames[0].frame.id == 0x18FF40E5u);  // handed on as it is: the link refuses it
}

TEST_CASE("network: a lost address is reported once with the bus, the address and the claimant's NAME") {
  Fixture f;
  f.start();
  f.runAt(START + 300 * MS);
  CHECK(f.sut->takeAddressLosses().empty());
  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now);

  const auto losses = f.sut->takeAddressLosses();
  REQUIRE(losses.size() == 1);
  const cantx::AddressLoss& loss = losses[0];
  CHECK(loss.bus == f.vehicle.buses[f.bus].name);
  CHECK(loss.lostAddress == 0x21);
  CHECK(loss.claimant == HIGHER_PRIORITY_NAME);
  CHECK(loss.ourName == OUR_NAME);
  CHECK(loss.newAddress == j1939::NULL_ADDRESS);
  CHECK(loss.critical());
  CHECK(loss.describe() ==
        "bus 'vehicle': address 0x21 (33) taken by NAME 0x0000000000000010, which has priority over this VCU's NAME "
        "0x3002800000000001; the VCU sent Cannot Claim and sends nothing more on this bus (J1939-81) until "
        "vcu-can-tx restarts");
  CHECK(f.sut->counters().addressesLost.load() == 1);
  CHECK(f.sut->takeAddressLosses().empty());

  // The claim again: nothing more is lost, nothing is sent, the VCU stays without an address.
  f.port.frames.clear();
  for (int i = 0; i < 3; ++i) f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME - 1), f.now + i * MS);
  f.runUntil(f.now + 500 * MS);
  CHECK(f.sut->takeAddressLosses().empty());
  CHECK(f.port.frames.empty());
  CHECK(f.sut->snapshot()[0].claimState == ipc::ClaimState::CannotClaim);
}

TEST_CASE("network: a VCU that moved does not send its J1939-76 pairs from the new address") {
  constexpr std::uint32_t S1_ES = 0x0CEFF321;      // HHEA's ignition SDM, from 0x21 to 0xF3
  constexpr std::uint32_t S1_ES_SHM = 0x0C0EF321;  // its SHM (PGN 0x0E00)
  Fixture f;
  f.vehicle.buses[f.bus].j1939->name.arbitraryAddressCapable = true;  // warned by vcu check
  f.create();
  const std::vector<std::uint32_t> sdms{S1_ES};
  f.sut->holdSafetyMessages(sdms);
  f.sut->start(f.now);
  f.runAt(START + 300 * MS);
  CHECK(f.sendScheduled(S1_ES_SHM) == can::SendStatus::Sent);  // from 0x21: as configured
  CHECK(f.sendScheduled(S1_ES) == can::SendStatus::Sent);

  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now);
  f.runUntil(f.now + 300 * MS);
  f.port.frames.clear();

  CHECK(f.sendScheduled(S1_ES_SHM) == can::SendStatus::Down);
  CHECK(f.sendScheduled(S1_ES) == can::SendStatus::Down);
  CHECK(f.sendScheduled(SCHEDULED) == can::SendStatus::Sent);  // other traffic follows the address
  REQUIRE(f.port.frames.size() == 1);
  const std::uint8_t moved = static_cast<std::uint8_t>(f.port.frames[0].frame.id & 0xFFu);
  CHECK(moved >= 128);
  CHECK(f.sut->counters().safetyFramesHeld.load() == 2);
  const auto losses = f.sut->takeAddressLosses();
  REQUIRE(losses.size() == 1);
  CHECK(losses[0].newAddress == moved);
  CHECK(losses[0].safetyPairsHeld);
  CHECK(losses[0].critical());
  CHECK(losses[0].describe().find("the VCU moved to 0x80 (128); its J1939-76 safety pairs are not sent from there") !=
        std::string::npos);
}

TEST_CASE("network: a VCU without safety pairs that moved is a warning, not critical") {
  Fixture f;
  f.vehicle.buses[f.bus].j1939->name.arbitraryAddressCapable = true;
  f.start();
  f.sut->onFrame(f.bus, claimFrame(0x21, HIGHER_PRIORITY_NAME), f.now + MS);
  const auto losses = f.sut->takeAddressLosses();
  REQUIRE(losses.size() == 1);
  CHECK(losses[0].newAddress == 0x80);
  CHECK_FALSE(losses[0].safetyPairsHeld);
  CHECK_FALSE(losses[0].critical());
}
