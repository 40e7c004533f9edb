// The schedule file and the overlay: defaults from the DBC, every refusal with its JSON
// path and reason, the overlay applied all-or-nothing and written atomically.

#include <doctest/doctest.h>
#include "vehicle_fixture.hpp"
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "openvcu/config/catalog.hpp"
#include "openvcu/schedule/schedule_config.hpp"

using namespace openvcu;

namespace {

const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";

struct Fixture : openvcu::testing::VehicleTable {
  std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("openvcu-txconfig-" + std::to_string(::getpid()));

  Fixture() : VehicleTable(HHEA) {
    std::filesystem::create_directories(folder);
  }
  ~Fixture() {
    std::error_code ignored;
    std::filesystem::remove_all(folder, ignored);
  }
  std::string write(const std::string& name, const std::string& text) {
    const auto path = (folder / name).string();
    std::ofstream(path) << text;
    return path;
  }
  Result<schedule::Schedule> load(const std::string& json) {
    vehicle.scheduleFile = write("schedule.json", json);
    return schedule::loadSchedule(vehicle, catalog);
  }
  std::string error(const std::string& json) {
    auto result = load(json);
    REQUIRE_MESSAGE(!result, json);
    return result.error().toString();
  }
  const schedule::ScheduledMessage& entry(const schedule::Schedule& schedule, const std::string& name) {
    auto found = schedule::findScheduled(schedule, vehicle, name);
    REQUIRE_MESSAGE(found, name);
    return schedule.messages[*found];
  }
};

}  // namespace

TEST_CASE("without a file: every message the node transmits, at its DBC cycle, safety headers left out") {
  Fixture f;
  f.vehicle.scheduleFile.clear();
  auto schedule = schedule::loadSchedule(f.vehicle, f.catalog);
  REQUIRE_MESSAGE(schedule, (schedule ? "" : schedule.error().toString()));
  CHECK(schedule->messages.size() == 36);  // 38 VCU messages minus the two SHM definitions
  CHECK(f.entry(*schedule, "S1_ES_PGN61427").cycleNs == 20'000'000);
  CHECK(f.entry(*schedule, "CMD_SYS_1").cycleNs == 10'000'000);
  CHECK(f.entry(*schedule, "TD_PGN65254").cycleNs == 0);  // on request only
  CHECK(!f.entry(*schedule, "S1_ES_PGN61427").safetyDeltaNs);
  CHECK(!schedule::findScheduled(*schedule, f.vehicle, "SHM_VCU_to_VIC"));
  CHECK(schedule->overlay == f.vehicle.directory + "/schedule.overlay.json");
}

TEST_CASE("the HHEA schedule: keep-alive group, five safety pairs, HVLP computed fields, writer and safe values") {
  Fixture f;
  auto schedule = schedule::loadSchedule(f.vehicle, f.catalog);
  REQUIRE_MESSAGE(schedule, (schedule ? "" : schedule.error().toString()));
  const auto& s1 = f.entry(*schedule, "S1_ES_PGN61427");
  REQUIRE(s1.safetyDeltaNs);
  CHECK(*s1.safetyDeltaNs == 292'000);
  REQUIRE(s1.group);
  CHECK(schedule->groups[*s1.group].name == "keepAlive");
  CHECK(f.entry(*schedule, "HC3_Battery_Demands_4").computed.size() == 2);
  CHECK(f.entry(*schedule, "HC3_Battery_Demands_4").computed[0].algorithm == schedule::FieldAlgorithm::Counter);
  CHECK(f.entry(*schedule, "PDU_Rx_1").onChange);
  REQUIRE(schedule->writers.size() == 1);
  CHECK(schedule->writers[0].service == "fsm");
  CHECK(schedule->safeValues.size() == 15);
  CHECK(schedule->overlay.ends_with("config/hhea/schedule.overlay.json"));
}

TEST_CASE("settings: cycle, offset, values, destination substitution") {
  Fixture f;
  auto schedule = f.load(R"({"include": ["RQST_ES_PGN59904", "CMD_SYS_0"],
    "messages": {"CMD_SYS_0": {"cycleMs": 50, "offsetMs": 5, "values": {"cmd_sys_request": 1}},
                 "RQST_ES_PGN59904": {"destination": "0x40"}}})");
  REQUIRE_MESSAGE(schedule, (schedule ? "" : schedule.error().toString()));
  REQUIRE(schedule->messages.size() == 2);
  const auto& sys0 = f.entry(*schedule, "CMD_SYS_0");
  CHECK(sys0.cycleNs == 50'000'000);
  CHECK(sys0.offsetNs == 5'000'000);
  REQUIRE(sys0.defaults[0]);
  CHECK(*sys0.defaults[0] == 1);
  CHECK(f.entry(*schedule, "RQST_ES_PGN59904").canId == 0x18EA4021);  // DA 0xF3 -> 0x40
}

TEST_CASE("refusals name the JSON path and the reason") {
  Fixture f;
  CHECK(f.error(R"({"mesages": {}})").find("/mesages") != std::string::npos);
  CHECK(f.error(R"({"messages": {"S1_ES_PGN6142": {}}})")
            .ends_with("/messages/S1_ES_PGN6142: unknown message 'S1_ES_PGN6142' (did you mean 'S1_ES_PGN61427'?)"));
  CHECK(f.error(R"({"messages": {"S1_ES_PGN61427": {"safety": {"deltaUs": 20000}}}})")
            .ends_with("/messages/S1_ES_PGN61427/safety/deltaUs: must be shorter than the cycle (20000 us)"));
  CHECK(f.error(R"({"messages": {"SHM_VCU_to_VIC": {}}})").find("safety header") != std::string::npos);
  CHECK(f.error(R"({"messages": {"HC1_Demands": {"computed": [{"signal": "SEQ_Command1", "algorithm": "crc9"}]}}})")
            .find("/messages/HC1_Demands/computed/0/algorithm: unknown algorithm 'crc9'") != std::string::npos);
  CHECK(f.error(R"({"messages": {"HC1_Demands": {"computed": [{"signal": "Torque_Request", "algorithm": "sum8"}]}}})")
            .find("unsigned integer signal") != std::string::npos);
  CHECK(f.error(R"({"messages": {"HC1_Demands": {"values": {"ControlWrd": 6}}}})")
            .ends_with("/messages/HC1_Demands/values/ControlWrd: unknown signal 'ControlWrd' in message 'HC1_Demands' "
                       "(did you mean 'ControlWord'?)"));
  CHECK(f.error(R"({"messages": {"HC1_Demands": {"values": {"ControlWord": 70000}}}})")
            .find("outside the range") != std::string::npos);
  CHECK(f.error(R"({"messages": {"HC1_Demands": {"group": "keepAlive"}}})")
            .find("unknown send group 'keepAlive'") != std::string::npos);
  CHECK(f.error(R"({"groups": {"g": {"signal": "internal.tx.keepAliv"}}})")
            .find("(did you mean 'internal.tx.keepAlive'?)") != std::string::npos);
  CHECK(f.error(R"({"writers": [{"service": "fsm", "timeoutMs": 500}]})")
            .ends_with("/writers/0/timeoutMs: must be above 1000 (the heartbeat period) and at most 600000 ms"));
  CHECK(f.error(R"({"writers": [{"service": "fms", "timeoutMs": 3000}]})")
            .find("unknown service 'fms'") != std::string::npos);
  CHECK(f.error(R"({"safeValues": {"Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors": 0}})")
            .find("list the writers") != std::string::npos);
  CHECK(f.error(R"({"messages": {"CCVS1_PGN65265": {"destination": "0x10"}}})").find("PDU2") != std::string::npos);
  CHECK(f.error(R"({"exclude": ["CMD_SYS_0"], "messages": {"CMD_SYS_0": {}}})").find("excluded") != std::string::npos);
  CHECK(f.error(R"({"realtimePriority": 120})").find("/realtimePriority") != std::string::npos);
  CHECK(f.error("{\"messages\": {\n}").find("schedule.json") != std::string::npos);  // syntax: file, line
}

TEST_CASE("issue 27: sdmSpinUs defaults to 500 us, takes 0..10000 whole microseconds, refuses anything else") {
  Fixture f;
  auto defaults = f.load("{}");
  REQUIRE(defaults);
  CHECK(defaults->sdmSpinNs == schedule::DEFAULT_SDM_SPIN_US * 1000);
  auto off = f.load(R"({"sdmSpinUs": 0})");
  REQUIRE(off);
  CHECK(off->sdmSpinNs == 0);
  auto longest = f.load(R"({"sdmSpinUs": 10000})");
  REQUIRE(longest);
  CHECK(longest->sdmSpinNs == 10'000'000);
  const std::string expected =
      "/sdmSpinUs: must be a whole number of microseconds from 0 (the transmit thread always sleeps) to 10000";
  CHECK(f.error(R"({"sdmSpinUs": 10001})").find(expected) != std::string::npos);
  CHECK(f.error(R"({"sdmSpinUs": -1})").find(expected) != std::string::npos);
  CHECK(f.error(R"({"sdmSpinUs": 2.5})").find(expected) != std::string::npos);
  CHECK(f.error(R"({"sdmSpinUs": "500"})").find("/sdmSpinUs") != std::string::npos);
}

TEST_CASE("the overlay: applied over the schedule all or nothing, saved atomically, read back") {
  Fixture f;
  auto schedule = f.load(R"({"overlay": "runtime.json"})");
  REQUIRE(schedule);
  CHECK(schedule->overlay == (f.folder / "runtime.json").string());
  auto missing = schedule::loadOverlay(schedule->overlay);
  REQUIRE(missing);
  CHECK(missing->empty());

  schedule::Overlay overlay;
  overlay.messages.push_back({"CCVS1_PGN65265", 50.0, false});
  overlay.defaults.emplace_back("Vehicle_Control_Unit.CCVS1_PGN65265.Wheel_Based_Veh_Spd", 12.5);
  overlay.overrides.emplace_back("Vehicle_Control_Unit.HC1_Demands.ControlWord", 6);
  REQUIRE(schedule::saveOverlay(schedule->overlay, overlay));
  for (const auto& item : std::filesystem::directory_iterator(f.folder)) {
    CHECK(item.path().filename().string().find(".tmp") == std::string::npos);  // no temporary left
  }
  auto loaded = schedule::loadOverlay(schedule->overlay);
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
  auto applied = schedule::applyOverlay(*schedule, *loaded, f.vehicle, f.catalog);
  REQUIRE_MESSAGE(applied, (applied ? "" : applied.error().toString()));
  const auto& ccvs = f.entry(*applied, "CCVS1_PGN65265");
  CHECK(ccvs.cycleNs == 50'000'000);
  CHECK(!ccvs.enabled);
  REQUIRE(ccvs.defaults[4]);  // Wheel_Based_Veh_Spd
  CHECK(*ccvs.defaults[4] == 12.5);

  // one bad entry refuses the whole overlay, naming it
  loaded->defaults.emplace_back("Vehicle_Control_Unit.HC1_Demands.ControlWord", 1e9);
  auto refused = schedule::applyOverlay(*schedule, *loaded, f.vehicle, f.catalog);
  REQUIRE(!refused);
  CHECK(refused.error().message.find("/defaults/Vehicle_Control_Unit.HC1_Demands.ControlWord: value") !=
        std::string::npos);
  CHECK(f.entry(*schedule, "CCVS1_PGN65265").cycleNs == 100'000'000);  // the original is untouched

  f.write("runtime.json", R"({"format": 1, "messages": {"CCVS1_PGN65265": {"cycle": 5}}})");
  auto unknownKey = schedule::loadOverlay(schedule->overlay);
  REQUIRE(!unknownKey);
  CHECK(unknownKey.error().toString().find("/messages/CCVS1_PGN65265") != std::string::npos);
}

TEST_CASE("checkCycle: whole ms 1..3600000 and longer than the safety delta") {
  schedule::ScheduledMessage message;
  message.safetyDeltaNs = 2'000'000;
  CHECK(schedule::checkCycle(message, 0.5));
  CHECK(schedule::checkCycle(message, 2.0));
  CHECK(schedule::checkCycle(message, 2.5));  // #19: whole milliseconds only
  CHECK(!schedule::checkCycle(message, 3.0));
  CHECK(schedule::checkCycle(message, 4e6));
}

TEST_CASE("runtimeMessage: any DBC message on a bus joins at a checked cycle, and the overlay keeps it across restarts") {
  Fixture f;
  auto schedule = f.load(R"({"overlay": "runtime.json"})");
  REQUIRE(schedule);
  auto added = schedule::runtimeMessage(*schedule, f.vehicle, f.catalog, "HVESSD2_PGN61585", 100);
  REQUIRE_MESSAGE(added, (added ? "" : added.error().toString()));
  CHECK(added->added);
  CHECK(added->cycleNs == 100'000'000);
  CHECK(added->canId == 0x18F091F3);  // the VIC's own ID: the bench stands in for it
  CHECK(added->keys.size() == added->defaults.size());
  CHECK(!added->group);
  auto refusal = [&](const std::string& name, double cycleMs) {
    auto result = schedule::runtimeMessage(*schedule, f.vehicle, f.catalog, name, cycleMs);
    REQUIRE_MESSAGE(!result, name);
    return result.error().message;
  };
  CHECK(refusal("HVESSD2_PGN61586", 100).find("did you mean 'HVESSD2_PGN61585'") != std::string::npos);
  CHECK(refusal("CCVS1_PGN65265", 100).find("already in the transmit schedule") != std::string::npos);
  CHECK(refusal("SHM_VCU_to_VIC", 100).find("safety header") != std::string::npos);
  CHECK(refusal("HVESSD2_PGN61585", 0).find("whole number of ms from 1 to 3600000") != std::string::npos);

  schedule::Overlay overlay;
  overlay.messages.push_back({"HVESSD2_PGN61585", 100.0, std::nullopt, true});
  overlay.defaults.emplace_back("VIC.HVESSD2_PGN61585.HS_FastUpdSOC", 55);
  REQUIRE(schedule::saveOverlay(schedule->overlay, overlay));
  auto loaded = schedule::loadOverlay(schedule->overlay);
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
  REQUIRE(loaded->messages.size() == 1);
  CHECK(loaded->messages[0].added);
  auto applied = schedule::applyOverlay(*schedule, *loaded, f.vehicle, f.catalog);
  REQUIRE_MESSAGE(applied, (applied ? "" : applied.error().toString()));
  CHECK(applied->messages.size() == schedule->messages.size() + 1);
  const auto& hvessd2 = f.entry(*applied, "HVESSD2_PGN61585");
  CHECK(hvessd2.added);
  CHECK(hvessd2.cycleNs == 100'000'000);
  CHECK(std::count(hvessd2.defaults.begin(), hvessd2.defaults.end(), std::optional<double>(55.0)) == 1);

  // an added message without its cycle, or one the schedule already has, refuses the overlay
  f.write("runtime.json", R"({"format": 1, "messages": {"HVESSD2_PGN61585": {"added": true}}})");
  auto noCycle = schedule::loadOverlay(schedule->overlay);
  REQUIRE(!noCycle);
  CHECK(noCycle.error().toString().find("/messages/HVESSD2_PGN61585/cycleMs") != std::string::npos);
  f.write("runtime.json", R"({"format": 1, "messages": {"CCVS1_PGN65265": {"added": true, "cycleMs": 50}}})");
  auto twice = schedule::loadOverlay(schedule->overlay);
  REQUIRE(twice);
  auto refused = schedule::applyOverlay(*schedule, *twice, f.vehicle, f.catalog);
  REQUIRE(!refused);
  CHECK(refused.error().message.find("/messages/CCVS1_PGN65265: 'CCVS1_PGN65265' is already") != std::string::npos);
}

TEST_CASE("issue 18: an SDM and another message of equal PGN, SA and DA are warned about, naming both") {
  Fixture f;
  auto schedule = schedule::loadSchedule(f.vehicle, f.catalog);
  REQUIRE_MESSAGE(schedule, (schedule ? "" : schedule.error().toString()));
  const auto warnings = schedule::safetyIdentityWarnings(*schedule, f.vehicle);
  REQUIRE(warnings.size() == 1);
  CHECK_MESSAGE(warnings[0].starts_with("S1_ES_PGN61427 (0x0CEFF321, J1939-76 SDM) and PropA_C4_PGN61184 (0x18EFF321) "
                                        "have the same PGN 0xEF00, source 0x21 and destination 0xF3 on bus vehicle"),
                warnings[0]);
  // the pairs that include one message: PropA_C4 has one, CMD_SYS_1 none
  const auto propA = schedule::findScheduled(*schedule, f.vehicle, "PropA_C4_PGN61184");
  const auto sys1 = schedule::findScheduled(*schedule, f.vehicle, "CMD_SYS_1");
  REQUIRE(propA);
  REQUIRE(sys1);
  CHECK(schedule::safetyIdentityWarnings(*schedule, f.vehicle, *propA).size() == 1);
  CHECK(schedule::safetyIdentityWarnings(*schedule, f.vehicle, *sys1).empty());
}

TEST_CASE("issue 18: equal PGN, SA and DA without an SDM, or the SDM alone, is not warned about") {
  Fixture f;
  f.vehicle.scheduleFile.clear();  // defaults: S1_ES and PropA_C4 both plain messages
  auto plain = schedule::loadSchedule(f.vehicle, f.catalog);
  REQUIRE(plain);
  CHECK(schedule::safetyIdentityWarnings(*plain, f.vehicle).empty());
  auto alone = f.load(R"({"exclude": ["PropA_C4_PGN61184"],
                          "messages": {"S1_ES_PGN61427": {"safety": {"deltaUs": 292}}}})");
  REQUIRE_MESSAGE(alone, (alone ? "" : alone.error().toString()));
  CHECK(schedule::safetyIdentityWarnings(*alone, f.vehicle).empty());
}
