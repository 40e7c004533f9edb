// safety.json against its vehicle (checkSafety in shared/safety/safety_case.hpp), and the
// vehicle.json key "safety" that names it: the shipped HHEA and tractor cases pass, copies
// with one damaged member are refused at the JSON path of that member.
#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/safety/safety_case.hpp"

namespace {

using namespace openvcu;
namespace fs = std::filesystem;

const fs::path CONFIG_ROOT = fs::path(OPENVCU_SOURCE_DIR) / "config";

/// A vehicle loaded with its catalog and FSM state names, as `vcu check` has them.
struct LoadedVehicle {
  config::VehicleConfig config;
  signals::Catalog catalog;
  std::vector<std::string> states;
};

LoadedVehicle loadVehicle(const fs::path& vehicleJson) {
  auto config = config::loadVehicleConfig(vehicleJson.string());
  REQUIRE_MESSAGE(config, (config ? "" : config.error().toString()));
  auto catalog = config::buildCatalog(*config);
  REQUIRE(catalog);
  auto machine = fsm::loadMachine(config->fsmFile, *config, *catalog);
  REQUIRE(machine);
  LoadedVehicle loaded{std::move(*config), std::move(*catalog), {}};
  for (const fsm::State& state : machine->states) loaded.states.push_back(state.name);
  return loaded;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A copy of a shipped vehicle folder in a fresh temporary folder, removed afterwards.
class VehicleCopy {
 public:
  explicit VehicleCopy(const std::string& vehicle) {
    m_dir = fs::temp_directory_path() /
            ("openvcu-safety-test-" + std::to_string(::getpid()) + "-" + std::to_string(s_counter++));
    fs::create_directories(m_dir);
    for (const auto& entry : fs::directory_iterator(CONFIG_ROOT / vehicle)) {
      if (entry.is_regular_file()) fs::copy_file(entry.path(), m_dir / entry.path().filename());
    }
  }
  ~VehicleCopy() { fs::remove_all(m_dir); }
  VehicleCopy(const VehicleCopy&) = delete;
  VehicleCopy& operator=(const VehicleCopy&) = delete;

  /// Replaces the first `from` in `file` by `to` (the test fails when it is absent).
  void replace(const std::string& file, const std::string& from, const std::string& to) {
    std::string text = readFile(m_dir / file);
    const auto at = text.find(from);
    REQUIRE_MESSAGE(at != std::string::npos, from);
    text.replace(at, from.size(), to);
    std::ofstream(m_dir / file) << text;
  }
  [[nodiscard]] fs::path path(const std::string& file) const { return m_dir / file; }

 private:
  fs::path m_dir;
  static inline int s_counter = 0;
};

/// The diagnostics of the copy's safety.json against the copy's vehicle, one per line.
std::string checkCopy(const VehicleCopy& copy) {
  const LoadedVehicle vehicle = loadVehicle(copy.path("vehicle.json"));
  REQUIRE_FALSE(vehicle.config.safetyFile.empty());
  auto safetyCase = safety::loadSafety(vehicle.config.safetyFile);
  REQUIRE_MESSAGE(safetyCase, (safetyCase ? "" : safetyCase.error().toString()));
  std::string text;
  for (const Error& diagnostic : safety::checkSafety(*safetyCase, vehicle.config, vehicle.catalog, &vehicle.states)) {
    text += diagnostic.toString() + "\n";
  }
  return text;
}

bool contains(const std::string& text, std::string_view part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("vehicle.json's \"safety\" names the safety case, resolved beside it") {
  const LoadedVehicle hhea = loadVehicle(CONFIG_ROOT / "hhea/vehicle.json");
  CHECK(hhea.config.safetyFile == (CONFIG_ROOT / "hhea/safety.json").lexically_normal().string());
}

TEST_CASE("a vehicle.json naming a safety file that does not exist is refused at /safety") {
  VehicleCopy copy("hhea");
  fs::remove(copy.path("safety.json"));
  auto loaded = config::loadVehicleConfig(copy.path("vehicle.json").string());
  REQUIRE_FALSE(loaded);
  CHECK(contains(loaded.error().toString(), "vehicle.json: /safety: file '"));
}

TEST_CASE("a vehicle without \"safety\" has no safety case") {
  VehicleCopy copy("hhea");
  copy.replace("vehicle.json", ",\n  \"safety\": \"safety.json\"", "");
  auto loaded = config::loadVehicleConfig(copy.path("vehicle.json").string());
  REQUIRE(loaded);
  CHECK(loaded->safetyFile.empty());
}

TEST_CASE("the shipped HHEA and tractor safety cases load and pass every check against their vehicles") {
  for (const char* vehicle : {"hhea", "tractor"}) {
    CAPTURE(vehicle);
    const LoadedVehicle loaded = loadVehicle(CONFIG_ROOT / vehicle / "vehicle.json");
    auto safetyCase = safety::loadSafety(loaded.config.safetyFile);
    REQUIRE_MESSAGE(safetyCase, (safetyCase ? "" : safetyCase.error().toString()));
    std::string diagnostics;
    for (const Error& diagnostic : safety::checkSafety(*safetyCase, loaded.config, loaded.catalog, &loaded.states)) {
      diagnostics += diagnostic.toString() + "\n";
    }
    CHECK_MESSAGE(diagnostics.empty(), diagnostics);
    REQUIRE(safetyCase->watchdog);
    CHECK(safetyCase->watchdog->services == std::vector<std::string>{"can-rx", "can-tx", "fsm", "gpio"});
  }
}

TEST_CASE("the HHEA case covers every fault state of its FSM, each watched service and the J1939 address") {
  const LoadedVehicle hhea = loadVehicle(CONFIG_ROOT / "hhea/vehicle.json");
  auto sut = safety::loadSafety(hhea.config.safetyFile);
  REQUIRE(sut);
  std::set<std::string> safeStates;
  std::set<std::string> restarted;
  std::set<safety::DetectionKind> kinds;
  for (const safety::Hazard& hazard : sut->hazards) {
    safeStates.insert(hazard.safeState.fsmStates.begin(), hazard.safeState.fsmStates.end());
    restarted.insert(hazard.safeState.restarted.begin(), hazard.safeState.restarted.end());
    for (const safety::Detection& detection : hazard.detection) kinds.insert(detection.kind);
    CHECK_MESSAGE(!hazard.faults.empty(), hazard.id);
  }
  for (const char* state : {"Battery Fault", "Battery Timeout", "PDU Fault", "Contactor Fault", "HVLP Inverter Fault",
                            "Editron Inverter Fault", "OBC Fault", "Crash"}) {
    CHECK_MESSAGE(safeStates.count(state) == 1, state);
  }
  for (const std::string& service : sut->watchdog->services) CHECK_MESSAGE(restarted.count(service) == 1, service);
  CHECK(kinds.count(safety::DetectionKind::AddressLoss) == 1);
  CHECK(kinds.count(safety::DetectionKind::ReceiveTimeout) == 1);
  CHECK(kinds.count(safety::DetectionKind::GpioInput) == 1);
}

TEST_CASE("safety.json naming an FSM state, GPIO line, signal, message, node or bus the vehicle lacks is refused") {
  VehicleCopy copy("hhea");
  copy.replace("safety.json", R"("fsmStates": ["Battery Fault"])", R"("fsmStates": ["Battery Fualt"])");
  copy.replace("safety.json", R"("during": ["Driving"])", R"("during": ["Flying"])");
  copy.replace("safety.json", R"({"line": "Cl15", "level": 0})", R"({"line": "ContactorFault", "level": 0})");
  copy.replace("safety.json", R"({"signal": "Vehicle_Control_Unit.VCU.VCU_DCDC_Command", "value": 0})",
               R"({"signal": "Vehicle_Control_Unit.VCU.VCU_DCDC_Comand", "value": 0})");
  copy.replace("safety.json", R"({"kind": "gpioInput", "line": "ContactorFault"})",
               R"({"kind": "gpioInput", "line": "Cl15"})");
  copy.replace("safety.json", R"({"inject": "silence", "node": "VIC"})", R"({"inject": "silence", "node": "BMS"})");
  copy.replace("safety.json", R"({"kind": "addressLoss", "bus": "vehicle", "withinMs": 1000})",
               R"({"kind": "addressLoss", "bus": "chassis", "withinMs": 1000})");
  copy.replace("safety.json", R"({"inject": "busOff", "bus": "vehicle"})",
               R"({"inject": "silence", "message": "HVESSS1_PGN4336"})");
  const std::string diagnostics = checkCopy(copy);
  CHECK(contains(diagnostics, "safety.json: /hazards/0/during/0: no FSM state 'Flying' in "));
  CHECK(contains(diagnostics, "safety.json: /hazards/0/safeState/fsmStates/0: no FSM state 'Battery Fualt' in "));
  CHECK(contains(diagnostics, "did you mean 'Battery Fault'?"));
  CHECK(contains(diagnostics,
                 "safety.json: /hazards/0/safeState/bus/0/signal: no signal "
                 "'Vehicle_Control_Unit.VCU.VCU_DCDC_Comand' in the DBC or the internal signals; did you "
                 "mean 'Vehicle_Control_Unit.VCU.VCU_DCDC_Command'?"));
  CHECK(contains(diagnostics, "/hazards/1/faults/0/node: no node 'BMS' in the DBC's BU_ list"));
  CHECK(contains(diagnostics, "/hazards/3/detection/0/line: GPIO line 'Cl15' is an output; expected an input"));
  CHECK(contains(diagnostics, "safeState/gpio/0/line: GPIO line 'ContactorFault' is an input; expected an output"));
  CHECK(contains(diagnostics, "/detection/0/bus: no bus 'chassis' in "));
  CHECK(contains(diagnostics, "/faults/0/message: no message 'HVESSS1_PGN4336' in the DBC"));
}

TEST_CASE("a watched service the watchdog does not watch or restart, or a silence bound beyond the FTTI, is refused") {
  VehicleCopy copy("hhea");
  copy.replace("safety.json", R"("services": ["can-rx", "can-tx", "fsm", "gpio"])",
               R"("services": ["can-rx", "can-tx", "gpio"])");
  copy.replace("safety.json", R"("silentAfterMs": 2500)", R"("silentAfterMs": 6500)");
  const std::string diagnostics = checkCopy(copy);
  CHECK(contains(diagnostics,
                 "/detection/0/service: service 'fsm' is not in /watchdog/services: nothing detects "
                 "its silence"));
  CHECK(
      contains(diagnostics, "/safeState/restarted/0: service 'fsm' is not in /watchdog/services: nothing restarts it"));
  CHECK(contains(diagnostics,
                 "/detection/0/service: the watchdog counts a service silent after 6500 ms "
                 "(/watchdog/silentAfterMs): not inside this hazard's FTTI of 6000 ms"));
}

TEST_CASE("a vehicle without a J1939 address claim on the bus has no address to lose") {
  VehicleCopy copy("tractor");
  copy.replace("safety.json", R"({"kind": "serviceWatchdog", "service": "gpio", "withinMs": 3000})",
               R"({"kind": "addressLoss", "bus": "vehicle"})");
  CHECK(contains(checkCopy(copy), "/detection/0/bus: bus 'vehicle' has no J1939 address claim"));
}

TEST_CASE("a hazard without a fault to inject is a warning, not an error") {
  VehicleCopy copy("hhea");
  copy.replace("safety.json", R"("faults": [{"inject": "gpioStuck", "line": "ContactorFault", "level": 1}],)", "");
  auto safetyCase = safety::loadSafety(copy.path("safety.json").string());
  REQUIRE(safetyCase);
  const LoadedVehicle vehicle = loadVehicle(copy.path("vehicle.json"));
  const auto diagnostics = safety::checkSafety(*safetyCase, vehicle.config, vehicle.catalog, &vehicle.states);
  REQUIRE(diagnostics.size() == 1);
  CHECK(diagnostics[0].severity == Severity::Warning);
  CHECK(contains(diagnostics[0].toString(), "/hazards/3: warning: hazard 'HHEA-CONTACTOR-FAULT' lists no fault"));
}

TEST_CASE("a simulated fault the simulation file does not define, or silent.<NODE> of no node, is refused") {
  VehicleCopy copy("tractor");
  copy.replace("safety.json", R"({"inject": "simFault", "name": "bms_fault"})",
               R"({"inject": "simFault", "name": "bms_faults"})");
  copy.replace("safety.json", R"({"inject": "simFault", "name": "pump_fault"})",
               R"({"inject": "simFault", "name": "silent.Pump"})");
  const std::string diagnostics = checkCopy(copy);
  CHECK_MESSAGE(contains(diagnostics, "/faults/0/name: no fault 'bms_faults' in "), diagnostics);
  CHECK(contains(diagnostics, "did you mean 'bms_fault'?"));
  CHECK(contains(diagnostics, "/faults/0/name: no node 'Pump' in the DBC's BU_ list"));
}
