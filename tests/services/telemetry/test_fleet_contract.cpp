// The MQTT contract between vcu-telemetry and `vcu fleet` (issue 25): what the real engine
// (services/telemetry/src/engine.*) writes is read back by shared/fleet's parsers and
// FleetView, topic names included; and the view's rules on their own (duplicates and old
// messages, bad payloads, the SOC signal, `vcu fleet get`'s values).
#include <doctest/doctest.h>

#include <set>

#include "engine.hpp"
#include "openvcu/fleet/fleet_view.hpp"
#include "shared/signals/signals_test_support.hpp"

namespace {

using namespace openvcu;

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START_NS = 1'000'000 * MS;
constexpr std::int64_t START_UNIX_MS = 1'764'259'200'000;
constexpr const char* VEHICLE = "hhea-07";

}  // namespace

TEST_CASE("fleet contract: the engine's state, faults, health and signals records are read back by FleetView") {
  signals::testing::ScopedInstance instance{"fleet-contract"};
  const signals::Catalog catalog = signals::testing::makeCatalog({"BMS.SOC", "BMS.Current"});
  auto table = signals::SignalTable::open(catalog, instance.name());
  REQUIRE(table.ok());
  config::TelemetryConfig settings;
  settings.signals = {{.name = "BMS.Current", .maxRateHz = 10, .deadband = 0},
                      {.name = "BMS.SOC", .maxRateHz = 10, .deadband = 0}};
  auto engine = telemetry::Engine::create(settings, catalog, *table);
  REQUIRE(engine);
  REQUIRE(table->writeBus(*catalog.indexOf("BMS.SOC"), 87.5, START_NS, 0xF3, signals::Quality::Valid));
  REQUIRE(table->writeBus(*catalog.indexOf("BMS.Current"), -12.25, START_NS, 0xF3, signals::Quality::Valid));
  engine->onDm1({.timestampNs = 0,
                 .service = {},
                 .instance = {},
                 .bus = {},
                 .node = "BMS",
                 .source = 0xF3,
                 .lamps = 0x04,
                 .dtcs = {{100, 1, 3, false}, {200, 2, 1, false}}});
  engine->onTransition(
      ipc::FsmTransition{.timestampNs = 0, .fromState = "Ready", .toState = "Driving", .cause = "drive"});
  engine->onFault(ipc::FaultEvent{.timestampNs = 0,
                                  .name = "Contactor",
                                  .source = "vcu-fsm",
                                  .severity = ipc::FaultSeverity::Critical,
                                  .active = true,
                                  .text = "welded"});
  engine->sample(START_NS);
  telemetry::TickInputs inputs;
  inputs.clocks = {.monoNs = START_NS, .unixMs = START_UNIX_MS};
  const auto records = engine->tick(41, inputs);

  fleet::FleetView sut;
  REQUIRE(sut.apply(fleet::vehicleTopic(VEHICLE, fleet::Topic::Status), fleet::STATUS_ONLINE));
  std::set<fleet::Topic> seen;
  for (const std::string& record : records) {
    const auto newline = record.find('\n');
    REQUIRE(newline != std::string::npos);
    const auto topic = fleet::topicFromSuffix(record.substr(0, newline));
    REQUIRE_MESSAGE(topic.has_value(), record.substr(0, newline));
    seen.insert(*topic);
    const auto applied = sut.apply(fleet::vehicleTopic(VEHICLE, *topic), record.substr(newline + 1));
    REQUIRE_MESSAGE(applied.ok(), applied.error().message);
    CHECK(*applied);
  }
  CHECK(seen == std::set{fleet::Topic::State, fleet::Topic::Faults, fleet::Topic::Health, fleet::Topic::Signals});
  const fleet::VehicleView* vehicle = sut.find(VEHICLE);
  REQUIRE(vehicle != nullptr);
  CHECK(vehicle->online == true);
  REQUIRE(vehicle->state.has_value());
  CHECK(vehicle->state->state == "Driving");
  CHECK(vehicle->state->previous == "Ready");
  CHECK(vehicle->state->seq == 41);
  CHECK(fleet::activeFaultCount(*vehicle) == 3);  // one fault event, two DM1 DTCs
  CHECK(fleet::activeDtcCount(*vehicle) == 2);
  CHECK(fleet::worstFaultLevel(*vehicle) == fleet::FaultLevel::Critical);
  CHECK(fleet::fleetValue(*vehicle, "faults") ==
        "3 active, worst critical: vcu-fsm/Contactor welded; DM1 BMS 2 DTC(s) SPN 100 FMI 1 OC 3, SPN 200 FMI 2 OC 1");
  CHECK(fleet::fleetValue(*vehicle, "BMS.SOC") == "87.5");
  CHECK(fleet::fleetValue(*vehicle, "BMS.Current") == "-12.25");
  CHECK(fleet::socSignalOf(*vehicle) == "BMS.SOC");
  CHECK(vehicle->newestUnixMs == START_UNIX_MS);
  REQUIRE(vehicle->health.has_value());
  CHECK(fleet::fleetValue(*vehicle, "health")->ends_with("queue 0 pending, 0 dropped"));
}

TEST_CASE("fleet view: a repeated or older state is ignored, a newer one replaces it") {
  fleet::FleetView sut;
  const std::string topic = fleet::vehicleTopic(VEHICLE, fleet::Topic::State);
  REQUIRE(*sut.apply(topic, R"({"v":1,"seq":10,"t":2000,"state":"Driving","previous":"Ready"})"));
  CHECK_FALSE(*sut.apply(topic, R"({"v":1,"seq":10,"t":2000,"state":"Driving","previous":"Ready"})"));  // QoS 1 again
  CHECK_FALSE(*sut.apply(topic, R"({"v":1,"seq":9,"t":1000,"state":"Ready"})"));  // from a drained backlog
  CHECK(sut.find(VEHICLE)->state->state == "Driving");
  CHECK(*sut.apply(topic, R"({"v":1,"seq":2,"t":3000,"state":"Charging"})"));  // its queue was reset: later t
  CHECK(sut.find(VEHICLE)->state->state == "Charging");
}

TEST_CASE("fleet view: a payload that is not the format is an error naming the topic and leaves the view alone") {
  fleet::FleetView sut;
  const auto notJson = sut.apply("openvcu/hhea-07/state", "{");
  REQUIRE_FALSE(notJson.ok());
  CHECK(notJson.error().message == "openvcu/hhea-07/state: not JSON");
  const auto badVersion = sut.apply("openvcu/hhea-07/faults", R"({"v":2,"seq":1,"t":1,"active":[]})");
  REQUIRE_FALSE(badVersion.ok());
  CHECK(badVersion.error().message == "openvcu/hhea-07/faults: /v: version 2 (this reads 1)");
  const auto badSample =
      sut.apply("openvcu/hhea-07/signals", R"({"v":1,"seq":1,"t":1,"names":["A"],"samples":[[3,1,2.0]]})");
  REQUIRE_FALSE(badSample.ok());
  CHECK(badSample.error().message == "openvcu/hhea-07/signals: /samples/0: name index 3 beyond /names");
  const auto badStatus = sut.apply("openvcu/hhea-07/status", "maybe");
  REQUIRE_FALSE(badStatus.ok());
  CHECK(sut.vehicles().empty());
  // not a vehicle message: ignored without an error
  CHECK_FALSE(*sut.apply("openvcu/hhea-07/cmd/1", "{}"));
  CHECK_FALSE(*sut.apply("other/hhea-07/state", "{}"));
  CHECK(sut.vehicles().empty());
}

TEST_CASE("fleet topics: names built and parsed the same way") {
  CHECK(fleet::vehicleTopic("hhea-01", fleet::Topic::Signals) == "openvcu/hhea-01/signals");
  CHECK(fleet::fleetFilter(fleet::Topic::Status) == "openvcu/+/status");
  const auto parsed = fleet::parseTopic("openvcu/hhea-01/birth");
  REQUIRE(parsed.has_value());
  CHECK(parsed->vehicleId == "hhea-01");
  CHECK(parsed->topic == fleet::Topic::Birth);
  CHECK_FALSE(fleet::parseTopic("openvcu/a b/birth").has_value());
  CHECK_FALSE(fleet::parseTopic("openvcu/hhea-01/cmd/7/answer").has_value());
  CHECK(fleet::isRetained(fleet::Topic::Status));
  CHECK(fleet::isRetained(fleet::Topic::State));
  CHECK(fleet::isRetained(fleet::Topic::Faults));
  CHECK_FALSE(fleet::isRetained(fleet::Topic::Signals));
  CHECK(fleet::commandFilter("hhea-01") == "openvcu/hhea-01/cmd/+");
  CHECK(fleet::commandAnswerSuffix("c7") == "cmd/c7/answer");
}

TEST_CASE("fleet view: the SOC column takes the option, else the birth's signal ending in SOC") {
  fleet::FleetView sut;
  REQUIRE(*sut.apply(
      "openvcu/v1/birth",
      R"({"v":1,"vehicleId":"v1","signals":[{"name":"VIC.HS_I","unit":"A"},{"name":"VIC.HS_FastUpdSOC","unit":"%"}]})"));
  const fleet::VehicleView& vehicle = *sut.find("v1");
  CHECK(fleet::socSignalOf(vehicle) == "VIC.HS_FastUpdSOC");
  CHECK(fleet::socSignalOf(vehicle, "BMS.Other") == "BMS.Other");
  CHECK_FALSE(fleet::fleetValue(vehicle, "state").has_value());  // not told yet
  CHECK_FALSE(fleet::fleetValue(vehicle, "status").has_value());
}
