// The display logic the HMI and vcu-web share (openvcu::display): value text and status, the
// FSM rules behind the operator switches, service health, command acknowledgements and the
// log ring (issue 10).
// The plot's ring and decimation are tested with shared/trace (tests/shared/trace).
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "dashboard_test_catalog.hpp"
#include "openvcu/display/commands.hpp"
#include "openvcu/display/fsm_rules.hpp"
#include "openvcu/display/health.hpp"
#include "openvcu/display/log_buffer.hpp"
#include "openvcu/display/values.hpp"

using namespace openvcu;
using namespace openvcu::display;

namespace {

constexpr std::int64_t SECOND_NS = 1'000'000'000;
constexpr std::int64_t STALE_AFTER_NS = 2 * SECOND_NS;

signals::Catalog smallCatalog() {
  return openvcu::testing::dashboardCatalog();
}

signals::SlotSnapshot busSlot(double value, std::int64_t timestampNs, signals::Quality quality) {
  signals::SlotSnapshot slot;
  slot.bus = {.value = value, .timestampNs = timestampNs, .source = 0xF3, .quality = quality, .updates = 1};
  return slot;
}

}  // namespace

TEST_CASE("a fresh valid bus value is Ready, an old one Stale, a never written one NotConnected") {
  const std::int64_t now = 100 * SECOND_NS;
  CHECK(classify(busSlot(1, now - SECOND_NS, signals::Quality::Valid), now, STALE_AFTER_NS) == ValueStatus::Ready);
  CHECK(classify(busSlot(1, now - 3 * SECOND_NS, signals::Quality::Valid), now, STALE_AFTER_NS) == ValueStatus::Stale);
  CHECK(classify(busSlot(1, now, signals::Quality::Stale), now, STALE_AFTER_NS) == ValueStatus::Stale);
  CHECK(classify(busSlot(1, now, signals::Quality::OutOfRange), now, STALE_AFTER_NS) == ValueStatus::Stale);
  CHECK(classify(signals::SlotSnapshot{}, now, STALE_AFTER_NS) == ValueStatus::NotConnected);
}

TEST_CASE("a commanded value without a bus value is Ready and shown and the bus value wins when there is one") {
  signals::SignalInfo internal;
  internal.key = "internal.operator.Start";
  internal.kind = signals::SignalKind::Internal;
  internal.direction = signals::SignalDirection::Internal;
  signals::SlotSnapshot slot;
  slot.command = {.value = 1, .timestampNs = 5, .writer = 3, .updates = 1};
  CHECK(classify(slot, 10 * SECOND_NS, STALE_AFTER_NS) == ValueStatus::Ready);
  REQUIRE(shownValue(internal, slot));
  CHECK(*shownValue(internal, slot) == 1);
  slot.bus = {.value = 7, .timestampNs = 10 * SECOND_NS, .quality = signals::Quality::Valid, .updates = 2};
  CHECK(*shownValue(internal, slot) == 7);
  CHECK_FALSE(shownValue(internal, signals::SlotSnapshot{}));
}

TEST_CASE("a received signal shows only what came from the bus, never a command (#20)") {
  signals::SignalInfo received;
  received.key = "BMS.Status.SOC";
  received.kind = signals::SignalKind::Bus;
  received.direction = signals::SignalDirection::Received;
  signals::SlotSnapshot slot;
  slot.command = {.value = 1, .timestampNs = 5, .writer = 240, .updates = 1};

  CHECK_FALSE(shownValue(received, slot));
  slot.bus = {.value = 7, .timestampNs = 6, .quality = signals::Quality::Valid, .updates = 1};
  CHECK(shownValue(received, slot) == std::optional<double>(7));
}

TEST_CASE("values are formatted with the unit, or as their value text") {
  const signals::Catalog catalog = smallCatalog();
  CHECK(formatValue(catalog[0], 87.456, "%.1f") == "87.5 %");
  CHECK(formatValue(catalog[1], 1, "%.1f") == "On");
  CHECK(formatValue(catalog[1], 2, "") == "2");
  CHECK(formatValue(catalog[0], 50, "%s") == "50 %");  // an unsafe format falls back to %g
  CHECK(formatValue(catalog[0], 50, "%n") == "50 %");
}

TEST_CASE("value texts colour rows: Normal green, Fault and Error red, others neutral") {
  CHECK(toneOf("Normal") == TextTone::Good);
  CHECK(toneOf("Fault") == TextTone::Bad);
  CHECK(toneOf("Communication Error") == TextTone::Bad);
  CHECK(toneOf("Awaiting HV Req") == TextTone::Neutral);
  CHECK(toneOf("No fault (Normal)") == TextTone::Good);  // #10: Editron's st_mot_fault 0
}

TEST_CASE("bus signals go stale with age and internal signals (written on change) only by quality") {
  const signals::Catalog catalog = smallCatalog();
  CHECK(staleAfterFor(catalog[0], STALE_AFTER_NS) == STALE_AFTER_NS);  // a DBC signal
  CHECK(staleAfterFor(catalog[1], STALE_AFTER_NS) == 0);               // internal.relay.Cl15
  const std::int64_t now = 100 * SECOND_NS;
  CHECK(classify(busSlot(1, now - 50 * SECOND_NS, signals::Quality::Valid), now,
                 staleAfterFor(catalog[1], STALE_AFTER_NS)) == ValueStatus::Ready);
}

TEST_CASE("row labels keep the node of bus keys and the group of internal keys") {
  CHECK(shortLabel("HVLP_SA71.HS2_Status_Feedback.InverterStatus") == "HVLP_SA71 InverterStatus");
  CHECK(shortLabel("internal.relay.Cl15") == "relay Cl15");
  CHECK(shortLabel("plain") == "plain");
}

TEST_CASE("the FSM rules name states by index and know which switches each state reads") {
  const auto sut = FsmRules::parse(R"({"initialState": "Standby", "states": [
      {"name": "Standby", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": "Start"}, "nextState": "Ready"}]},
      {"name": "Ready", "transitions": [{"condition": {"any": [{"internal.operator.ConnectDriving": 1}, {"key": "internal.operator.ACCharging", "eq": 1}]}, "nextState": "Standby"}]}]})",
                                   "fsm.json");
  REQUIRE_MESSAGE(sut, sut.error().toString());
  CHECK(sut->stateName(0) == "Standby");
  CHECK(sut->stateName(7) == "state 7");
  CHECK(sut->stateReads(0, "internal.operator.StartStop"));
  CHECK_FALSE(sut->stateReads(0, "internal.operator.ConnectDriving"));
  CHECK(sut->stateReads(1, "internal.operator.ConnectDriving"));
  CHECK(sut->stateReads(1, "internal.operator.ACCharging"));
  CHECK_FALSE(sut->stateReads(5, "internal.operator.StartStop"));
}

TEST_CASE("the HHEA state machine offers Start in Standby and not Connect Driving") {
  const auto sut = FsmRules::load(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/fsm.json");
  REQUIRE_MESSAGE(sut, sut.error().toString());
  CHECK(sut->stateName(0) == "Standby");
  CHECK(sut->stateReads(0, "internal.operator.StartStop"));
  CHECK_FALSE(sut->stateReads(0, "internal.operator.ConnectDriving"));
}

TEST_CASE("an FSM file without states is refused with the reason") {
  const auto sut = FsmRules::parse(R"({"initialState": "x"})", "fsm.json");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().find("states") != std::string::npos);
}

TEST_CASE(
    "service health: expected services start NotConnected, beat Ready, late Stale, silent NotConnected, restarts "
    "counted") {
  HealthTracker sut({"vcu-fsm"}, STALE_AFTER_NS);
  REQUIRE(sut.services().size() == 1);
  CHECK(sut.statusOf(sut.services()[0], 0) == ValueStatus::NotConnected);
  ipc::Heartbeat beat{
      .service = "vcu-fsm", .instance = {}, .pid = 100, .uptimeMs = 10, .counters = {}, .status = "ready"};
  CHECK_FALSE(sut.onHeartbeat(beat, 10 * SECOND_NS));
  const ServiceHealth& fsm = sut.services()[0];
  CHECK(sut.statusOf(fsm, 11 * SECOND_NS) == ValueStatus::Ready);
  CHECK(sut.statusOf(fsm, 13 * SECOND_NS) == ValueStatus::Stale);
  CHECK(sut.statusOf(fsm, 17 * SECOND_NS) == ValueStatus::NotConnected);
  beat.pid = 101;
  sut.onHeartbeat(beat, 18 * SECOND_NS);
  CHECK(sut.services()[0].restarts == 1);
  CHECK(sut.statusOf(sut.services()[0], 18 * SECOND_NS) == ValueStatus::Ready);
  beat.service = "vcu-other";
  CHECK(sut.onHeartbeat(beat, 18 * SECOND_NS));
  CHECK(sut.services().size() == 2);
}

TEST_CASE("a service that beat and then fell silent is silent, a fault service_silent.<name>, until it beats again") {
  HealthTracker sut({"vcu-fsm", "vcu-gpio"}, STALE_AFTER_NS);
  const ipc::Heartbeat beat{
      .service = "vcu-fsm", .instance = {}, .pid = 100, .uptimeMs = 10, .counters = {}, .status = "ready"};
  sut.onHeartbeat(beat, 10 * SECOND_NS);
  const ServiceHealth* fsm = sut.find("vcu-fsm");
  const ServiceHealth* gpio = sut.find("vcu-gpio");
  REQUIRE(fsm);
  REQUIRE(gpio);
  CHECK(sut.livenessOf(*fsm, 11 * SECOND_NS) == Liveness::Beating);
  CHECK_FALSE(sut.silentFor(*fsm, 11 * SECOND_NS));
  CHECK(sut.silentFaults(11 * SECOND_NS, 1000 * SECOND_NS).empty());
  CHECK(sut.livenessOf(*gpio, 11 * SECOND_NS) == Liveness::NotHeard);  // never beat: not silent, no fault

  constexpr std::int64_t LATER = 14 * SECOND_NS;
  CHECK(sut.livenessOf(*fsm, LATER) == Liveness::Silent);
  REQUIRE(sut.silentFor(*fsm, LATER));
  CHECK(*sut.silentFor(*fsm, LATER) == 4 * SECOND_NS);
  const auto faults = sut.silentFaults(LATER, 1000 * SECOND_NS);
  REQUIRE(faults.size() == 1);
  CHECK(faults[0].name == "service_silent.fsm");
  CHECK(faults[0].source == SILENT_FAULT_SOURCE);
  CHECK(faults[0].severity == ipc::FaultSeverity::Critical);
  CHECK(faults[0].timestampNs == 996 * SECOND_NS);  // the last beat, on the real-time clock
  CHECK(faults[0].text.find("vcu-fsm stopped beating") != std::string::npos);
  CHECK(namesFault(faults, "service_silent.fsm"));
  CHECK(sut.services().size() == 2);  // the silent row stays listed

  sut.onHeartbeat(beat, 15 * SECOND_NS);
  CHECK(sut.livenessOf(*sut.find("vcu-fsm"), 15 * SECOND_NS) == Liveness::Beating);
  CHECK(sut.silentFaults(15 * SECOND_NS, 1000 * SECOND_NS).empty());
}

TEST_CASE("a service whose last heartbeat said stopping is stopped, not silent, and still a fault") {
  HealthTracker sut({}, STALE_AFTER_NS);
  sut.onHeartbeat(
      {.service = "vcu-gpio", .instance = {}, .pid = 7, .uptimeMs = 1, .counters = {}, .status = "stopping (SIGTERM)"},
      SECOND_NS);
  const ServiceHealth* gpio = sut.find("vcu-gpio");
  REQUIRE(gpio);
  CHECK(sut.livenessOf(*gpio, 5 * SECOND_NS) == Liveness::Stopped);
  const auto faults = sut.silentFaults(5 * SECOND_NS, 5 * SECOND_NS);
  REQUIRE(faults.size() == 1);
  CHECK(faults[0].name == "service_silent.gpio");
}

TEST_CASE("a beat in the table's heartbeat slot keeps a service beating and lists one LCM never told of") {
  HealthTracker sut({"vcu-fsm"}, STALE_AFTER_NS);
  CHECK_FALSE(sut.onSlotBeat("vcu-fsm", 10 * SECOND_NS));
  CHECK(sut.onSlotBeat("vcu-can-rx", 2 * SECOND_NS));  // a new row: beat once, silent since
  CHECK(sut.livenessOf(*sut.find("vcu-fsm"), 11 * SECOND_NS) == Liveness::Beating);
  CHECK(sut.livenessOf(*sut.find("vcu-can-rx"), 11 * SECOND_NS) == Liveness::Silent);
  sut.onSlotBeat("vcu-fsm", 5 * SECOND_NS);  // an older slot time never moves the last beat back
  CHECK(sut.find("vcu-fsm")->lastBeatMonoNs == 10 * SECOND_NS);
  CHECK(silentFaultName("vcu-can-rx") == "service_silent.can-rx");
  CHECK(silentFaultName("fixture") == "service_silent.fixture");
}

TEST_CASE("a command is answered by its own ack only, refused with the reason, or times out") {
  CommandTracker sut("vcu-hmi", 41, 2 * SECOND_NS);
  ipc::CommandRequest first;
  sut.prepare(first, 0);
  ipc::CommandRequest second;
  sut.prepare(second, 0);
  CHECK(first.requestId == 41);
  CHECK(second.requestId == 42);
  CHECK(first.issuer == "vcu-hmi");
  CHECK_FALSE(sut.onAck(
      {.requestId = 41, .issuer = "vcu", .responder = "vcu-fsm", .accepted = true, .reason = {}, .owner = true}));
  const auto refused = sut.onAck({.requestId = 41,
                                  .issuer = "vcu-hmi",
                                  .responder = "vcu-fsm",
                                  .accepted = false,
                                  .reason = "not permitted in state Standby"});
  REQUIRE(refused);
  CHECK(refused->second.state == CommandOutcome::State::Refused);
  CHECK(refused->second.text == "refused by vcu-fsm: not permitted in state Standby");
  CHECK(sut.expire(SECOND_NS).empty());
  const auto expired = sut.expire(3 * SECOND_NS);
  REQUIRE(expired.size() == 1);
  CHECK(expired[0].first == 42);
  CHECK(expired[0].second.state == CommandOutcome::State::TimedOut);
  CHECK(sut.pending() == 0);
}

TEST_CASE("the log ring keeps the newest records and filters by service and level") {
  LogBuffer sut(3);
  CHECK_FALSE(sut.add({.timestampNs = 1, .service = "vcu-fsm", .level = ipc::LogLevel::Info, .text = "a"}));
  sut.add({.timestampNs = 2, .service = "vcu-can-rx", .level = ipc::LogLevel::Warning, .text = "b"});
  sut.add({.timestampNs = 3, .service = "vcu-fsm", .level = ipc::LogLevel::Error, .text = "c"});
  CHECK(sut.add({.timestampNs = 4, .service = "vcu-fsm", .level = ipc::LogLevel::Debug, .text = "d"}));
  CHECK(sut.size() == 3);
  CHECK(sut.select("", ipc::LogLevel::Trace).size() == 3);
  CHECK(sut.select("vcu-fsm", ipc::LogLevel::Trace).size() == 2);
  const auto errors = sut.select("", ipc::LogLevel::Warning);
  REQUIRE(errors.size() == 2);
  CHECK(sut.exportText(errors) ==
        "1970-01-01T00:00:00.000Z warning vcu-can-rx: b\n1970-01-01T00:00:00.000Z error vcu-fsm: c\n");
}
