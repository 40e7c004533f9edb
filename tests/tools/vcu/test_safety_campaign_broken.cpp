// `vcu safety campaign` fails when a safety mechanism is switched off. Each case runs the whole
// headless HHEA stack in the sandbox (safety_campaign_stack.hpp) on a copy of config/hhea in
// which one mechanism is disabled through configuration only, injects the fault the mechanism
// exists for and expects exit 1, the hazard's FAIL line and the missed item by name:
//   - the FSM's receive timeout (fsm.json's transitions to Battery Timeout on the age of
//     HVESSS1, "ageGt": "3s") removed: the battery's silence in Ready never reaches Battery
//     Timeout;
//   - the dead-man on the FSM's writes (schedule.json "writers": [], the list vcu-can-tx and
//     vcu-gpio watch) off: a hung vcu-fsm leaves the contactors closed and nobody raises
//     writer_lost.fsm;
//   - vcu-watchdog (under supervisord beside vcu-fsm, as config/supervisor/openvcu.conf runs
//     them) with a policy that does not list fsm: no service_silent.fsm, no restart. With fsm
//     listed the same campaign passes.
// The intact runs of the first two hazards are test_safety_campaign_stack.cpp's.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "safety_campaign_stack.hpp"

namespace {

const std::string WATCHDOG = WATCHDOG_BINARY;

/// An item missing from a failed run is looked for during twice the FTTI: the battery's and the
/// dead-man's hazards have an FTTI of 4000 ms, which the intact mechanisms meet with margin
/// (test_safety_campaign_stack.cpp: Battery Timeout about 3.0 s, the dead-man about 2.2 s).
const std::string WINDOW_TEXT = "not seen within 8000 ms";
/// The watchdog's hazard: silent 2500 ms (safety.json) after the last beat, which lies up to
/// 1000 ms before the hang, seen at the next 100 ms read; supervisord restarts at its next
/// once-a-second tick; the new vcu-fsm loads the configuration and beats (about 1 s on a
/// loaded machine): up to about 5.6 s. Measured on the 2-core machine under load: silent after
/// 1.8-2.0 s, the new vcu-fsm beating after 2.9-4.0 s (an FTTI of 4000 ms was missed once).
const std::string WATCHDOG_WINDOW_TEXT = "not seen within 12000 ms";
/// Reach the state, settle, the window, clear, return home: well above the 30 s default.
constexpr auto CAMPAIGN_TIMEOUT = 90s;

/// A one-hazard safety case: the battery (VIC) goes silent in Ready.
nlohmann::json batterySilentCase() {
  return nlohmann::json::parse(R"({"hazards": [
    {"id": "T-BAT-SILENT", "severity": "PL d",
     "description": "the battery stops sending", "safetyGoal": "open the HV path",
     "during": ["Ready"],
     "safeState": {"fsmStates": ["Battery Timeout"],
                   "bus": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 0}]},
     "detection": [{"kind": "receiveTimeout", "message": "HVESSS1_PGN61590"}],
     "fttiMs": 4000,
     "faults": [{"inject": "silence", "node": "VIC"}]}]})");
}

/// A one-hazard safety case: vcu-fsm hangs while Driving, vcu-can-tx's dead-man acts.
nlohmann::json fsmHangCase() {
  return nlohmann::json::parse(R"({"hazards": [
    {"id": "T-FSM-HANG", "severity": "PL d",
     "description": "vcu-fsm hangs while driving", "safetyGoal": "open the HV path, disable the drive",
     "during": ["Driving"],
     "safeState": {"bus": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 0},
                           {"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupB_Contactors", "value": 0}]},
     "detection": [{"kind": "dtc", "fault": "writer_lost.fsm"}],
     "fttiMs": 4000,
     "faults": [{"inject": "stop", "service": "fsm"}]}]})");
}

/// A one-hazard safety case: vcu-fsm hangs while Driving, vcu-watchdog detects it and has it
/// restarted.
nlohmann::json fsmWatchdogCase() {
  return nlohmann::json::parse(R"({"hazards": [
    {"id": "T-FSM-WATCHDOG", "severity": "PL d",
     "description": "vcu-fsm hangs while driving", "safetyGoal": "restart vcu-fsm",
     "during": ["Driving"],
     "safeState": {"restarted": ["fsm"]},
     "detection": [{"kind": "serviceWatchdog", "service": "fsm"}],
     "fttiMs": 6000,
     "faults": [{"inject": "stop", "service": "fsm"}]}]})");
}

/// `vcu safety campaign --safety SAFETY --repeat 1` against the stack.
harness::CommandResult runCampaign(CampaignStack& stack, const nlohmann::json& safetyCase) {
  const fs::path safety = stack.writeSafety(safetyCase);
  return stack.sut.run(
      {VCU, "safety", "campaign", "--safety", safety.string(), "--repeat", "1", "--config", stack.config.string()},
      CAMPAIGN_TIMEOUT);
}

/// fsm.json without its transitions to Battery Timeout on the age of HVESSS1; returns how many
/// were removed.
std::size_t removeBatteryTimeouts(const fs::path& folder) {
  std::size_t removed = 0;
  editJson(folder / "fsm.json", [&](nlohmann::json& machine) {
    for (auto& state : machine["states"]) {
      if (!state.contains("transitions")) continue;
      auto& transitions = state["transitions"];
      const auto before = transitions.size();
      transitions.erase(
          std::remove_if(transitions.begin(), transitions.end(),
                         [](const nlohmann::json& transition) {
                           const auto& condition = transition.value("condition", nlohmann::json::object());
                           return transition.value("nextState", "") == "Battery Timeout" &&
                                  condition.value("key", "") == "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts" &&
                                  condition.contains("ageGt");
                         }),
          transitions.end());
      removed += before - transitions.size();
    }
  });
  return removed;
}

/// supervisord running vcu-fsm and vcu-watchdog on the stack's configuration (autorestart, as
/// config/supervisor/openvcu.conf), logs in the configuration's folder.
struct Supervised {
  fs::path folder;
  fs::path watchdogLog() const { return folder / "watchdog.log"; }

  void start(CampaignStack& stack) {
    folder = stack.config.parent_path();
    const fs::path conf = folder / "supervisord.conf";
    std::ofstream out(conf);
    out << "[supervisord]\nnodaemon=true\nlogfile=" << (folder / "supervisord.log").string()
        << "\npidfile=" << (folder / "supervisord.pid").string() << "\nchildlogdir=" << folder.string() << "\n"
        << (::geteuid() == 0 ? "user=root\n" : "")
        << "[unix_http_server]\nfile=" << (folder / "supervisor.sock").string()
        << "\n[rpcinterface:supervisor]\nsupervisor.rpcinterface_factory = "
           "supervisor.rpcinterface:make_main_rpcinterface\n";
    for (const auto& [name, binary] :
         {std::pair<std::string, std::string>{"fsm", FSM}, std::pair<std::string, std::string>{"watchdog", WATCHDOG}}) {
      const fs::path log = folder / (name + ".log");
      fs::remove(log);  // a log of an earlier case in the same sandbox
      out << "[program:" << name << "]\ncommand=" << binary << " --config " << stack.config.string()
          << "\nautorestart=true\nstartsecs=1\nstopsignal=TERM\nstopwaitsecs=5\nstdout_logfile=" << log.string()
          << "\nredirect_stderr=true\n";
    }
    out.close();
    REQUIRE_STATUS(stack.sut.start({.name = "supervisord", .argv = {"supervisord", "-n", "-c", conf.string()}}));
  }
  [[nodiscard]] std::string watchdogOutput() const {
    std::ifstream in(watchdogLog());
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
};

}  // namespace

TEST_CASE("without the FSM's receive timeout on HVESSS1 the battery's silence fails the campaign on Battery Timeout") {
  SKIP_UNLESS_ISOLATED();
  std::size_t removed = 0;
  CampaignStack stack([&](const fs::path& folder) { removed = removeBatteryTimeouts(folder); });
  // Ready, Connecting Driving, Driving, Connecting Charging, Charging, Charge Required
  REQUIRE(removed == 6);

  const auto result = runCampaign(stack, batterySilentCase());
  MESSAGE(result.out);
  CHECK_MESSAGE(result.exitCode() == 1, result.describe());
  CHECK(contains(result.out, "T-BAT-SILENT #1 FAIL"));
  CHECK(contains(result.out, "miss #1: fsm Battery Timeout " + WINDOW_TEXT));
  // the other mechanisms still act: can-rx's receive timeout, the contactors (open in Ready)
  CHECK_FALSE(contains(result.out, "miss #1: fault rx_timeout"));
  CHECK_FALSE(contains(result.out, "miss #1: bus "));
  CHECK(contains(result.out, "campaign FAILED: 0 passed, 1 failed"));
}

TEST_CASE(
    "without the dead-man on the FSM's writes a hung vcu-fsm fails the campaign on writer_lost.fsm and the "
    "contactors") {
  SKIP_UNLESS_ISOLATED();
  CampaignStack stack([](const fs::path& folder) {
    // an empty list is what the schedule loader accepts as "no writer watched" (safeValues need the key)
    editJson(folder / "schedule.json", [](nlohmann::json& schedule) {
      REQUIRE(schedule["writers"].size() == 1);
      schedule["writers"] = nlohmann::json::array();
    });
  });

  const auto result = runCampaign(stack, fsmHangCase());
  MESSAGE(result.out);
  CHECK_MESSAGE(result.exitCode() == 1, result.describe());
  CHECK(contains(result.out, "T-FSM-HANG #1 FAIL"));
  CHECK(contains(result.out, "miss #1: fault writer_lost.fsm " + WINDOW_TEXT));
  CHECK(contains(result.out, "miss #1: bus PDU_Rx_1.Close_GroupA_Contactors=0 " + WINDOW_TEXT));
  CHECK(contains(result.out, "miss #1: bus PDU_Rx_1.Close_GroupB_Contactors=0 " + WINDOW_TEXT));
  CHECK(contains(result.out, "campaign FAILED: 0 passed, 1 failed"));
}

TEST_CASE("vcu-watchdog under supervisord reports a hung vcu-fsm and has it restarted within the FTTI") {
  SKIP_UNLESS_ISOLATED();
  Supervised supervised;
  CampaignStack stack({}, [&](CampaignStack& self) { supervised.start(self); });

  const auto result = runCampaign(stack, fsmWatchdogCase());
  MESSAGE(result.out);
  CHECK_MESSAGE(result.exitCode() == 0, result.describe());
  CHECK(contains(result.out, "T-FSM-WATCHDOG #1 PASS"));
  CHECK(contains(result.out, "campaign passed: 1 passed, 0 failed"));
  const std::string log = supervised.watchdogOutput();
  CHECK_MESSAGE(contains(log, "watching can-rx, can-tx, fsm, gpio"), log);
  CHECK_MESSAGE(contains(log, "killed vcu-fsm"), log);
}

TEST_CASE("a vcu-watchdog whose policy leaves fsm out fails the campaign on service_silent.fsm and the restart") {
  SKIP_UNLESS_ISOLATED();
  Supervised supervised;
  CampaignStack stack(
      [](const fs::path& folder) {
        editJson(folder / "safety.json", [](nlohmann::json& safety) {
          auto& services = safety["watchdog"]["services"];
          const auto before = services.size();
          services.erase(std::remove(services.begin(), services.end(), "fsm"), services.end());
          REQUIRE(services.size() + 1 == before);
        });
      },
      [&](CampaignStack& self) { supervised.start(self); });

  const auto result = runCampaign(stack, fsmWatchdogCase());
  MESSAGE(result.out);
  CHECK_MESSAGE(result.exitCode() == 1, result.describe());
  CHECK(contains(result.out, "T-FSM-WATCHDOG #1 FAIL"));
  CHECK(contains(result.out, "miss #1: fault service_silent.fsm " + WATCHDOG_WINDOW_TEXT));
  CHECK(contains(result.out, "miss #1: restarted fsm " + WATCHDOG_WINDOW_TEXT));
  CHECK(contains(result.out, "campaign FAILED: 0 passed, 1 failed"));
  // the watchdog ran, watching the others
  const std::string log = supervised.watchdogOutput();
  CHECK_MESSAGE(contains(log, "watching can-rx, can-tx, gpio:"), log);
  CHECK_FALSE_MESSAGE(contains(log, "killed vcu-fsm"), log);
}
