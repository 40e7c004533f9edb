// Issue 22: simulation.json's "model" key and the generic model's rules, follow, integrate
// and faults, loaded on tests/data/ecu-sim (a small non-HHEA vehicle): a good file compiles
// to resolved signals and values; each kind of mistake is refused with its JSON path.

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "openvcu/config/simulation.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string GENERIC = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/ecu-sim/vehicle.json";
const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";

Result<config::SimConfig> loadText(const std::string& text, const std::string& vehiclePath = GENERIC) {
  auto vehicle = config::loadVehicleConfig(vehiclePath);
  REQUIRE_MESSAGE(vehicle, (vehicle ? "" : vehicle.error().toString()));
  const fs::path file = fs::temp_directory_path() / ("openvcu-sim-rules-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << text;
  auto result = config::loadSimConfig(file.string(), *vehicle);
  fs::remove(file);
  return result;
}

/// The first error's JSON path, or "ok".
std::string firstErrorPath(const std::string& text) {
  const auto result = loadText(text);
  return result ? "ok" : result.error().location.jsonPath;
}

std::string firstErrorText(const std::string& text) {
  const auto result = loadText(text);
  return result ? "ok" : result.error().toString();
}

}  // namespace

TEST_CASE("#22 the test vehicle's simulation file compiles its rules, follow, integrate and faults") {
  auto vehicle = config::loadVehicleConfig(GENERIC);
  REQUIRE_MESSAGE(vehicle, (vehicle ? "" : vehicle.error().toString()));
  const auto sut = config::loadSimConfig(vehicle->simulationFile, *vehicle);
  REQUIRE_MESSAGE(sut, (sut ? "" : sut.error().toString()));
  CHECK(sut->model == config::SimModel::Generic);
  const config::SimRules& rules = sut->rules;
  REQUIRE(rules.rules.size() == 2);
  CHECK(rules.rules[0].afterNs == 500'000'000);
  REQUIRE(rules.rules[0].set.size() == 1);
  CHECK(rules.rules[0].set[0].value == 2);  // VAL_ "Closed"
  const config::SimSignal& contactor = rules.signals[rules.rules[0].set[0].signal];
  CHECK(contactor.key == "BMS.BMS_Status.ContactorState");
  CHECK(contactor.kind == config::SimSignal::Kind::Node);
  const config::SimConditionNode& when = rules.nodes[rules.rules[0].when];
  CHECK(when.kind == config::SimNodeKind::Compare);
  CHECK(when.value == 1);  // VAL_ "Close"
  CHECK(rules.signals[when.signal].kind == config::SimSignal::Kind::Vcu);
  REQUIRE(rules.follow.size() == 1);
  CHECK(rules.follow[0].timeConstantNs == 500'000'000);
  CHECK(rules.signals[rules.follow[0].target].key == "VCU.INV_Command.SpeedRequest");
  REQUIRE(rules.integrate.size() == 1);
  CHECK(rules.integrate[0].factor == -0.5);
  CHECK(rules.integrate[0].minimum == 10);
  CHECK(rules.integrate[0].maximum == 90);
  REQUIRE(rules.faults.size() == 1);
  CHECK(rules.faults[0].name == "isolation");
  CHECK(rules.faults[0].set.size() == 2);
}

TEST_CASE("#22 {\"model\": \"generic\"} alone is valid, and without the key (or without a file) the model is generic") {
  const auto alone = loadText(R"({"model": "generic"})");
  REQUIRE(alone);
  CHECK(alone->model == config::SimModel::Generic);
  CHECK(alone->rules.rules.empty());
  const auto absent = loadText(R"({"tick": "20ms"})");
  REQUIRE(absent);
  CHECK(absent->model == config::SimModel::Generic);
  auto vehicle = config::loadVehicleConfig(GENERIC);
  REQUIRE(vehicle);
  const auto noFile = config::loadSimConfig("", *vehicle);
  REQUIRE(noFile);
  CHECK(noFile->model == config::SimModel::Generic);
  CHECK(noFile->safety.empty());
}

TEST_CASE("#22 the HHEA file says model hhea, and each model refuses the other's keys") {
  auto vehicle = config::loadVehicleConfig(HHEA);
  REQUIRE(vehicle);
  const auto hhea = config::loadSimConfig(vehicle->simulationFile, *vehicle);
  REQUIRE_MESSAGE(hhea, (hhea ? "" : hhea.error().toString()));
  CHECK(hhea->model == config::SimModel::Hhea);
  CHECK(firstErrorPath(R"({"battery": {"initialSoc": 50}})") == "/battery");
  CHECK(firstErrorPath(R"({"model": "hhea", "rules": []})") == "/rules");
  CHECK(firstErrorPath(R"({"model": "tractor"})") == "/model");
}

TEST_CASE("#22 an unknown signal is refused with its JSON path and a did-you-mean") {
  const std::string text = firstErrorText(R"({"rules": [{"when": {"key": "VCU.BMS_Command.ContactorReqest", "eq": 1},
      "set": {"BMS.BMS_Status.ContactorState": 2}}]})");
  CHECK_MESSAGE(text.find("/rules/0/when/key: no bus signal 'VCU.BMS_Command.ContactorReqest'") != std::string::npos, text);
  CHECK_MESSAGE(text.find("did you mean 'VCU.BMS_Command.ContactorRequest'?") != std::string::npos, text);
}

TEST_CASE("#22 each kind of mistake in the generic keys is refused with its JSON path") {
  // a VCU signal cannot be set: the simulator plays the other nodes
  CHECK(firstErrorPath(R"({"rules": [{"set": {"VCU.BMS_Command.ContactorRequest": 1}}]})") ==
        "/rules/0/set/VCU.BMS_Command.ContactorRequest");
  // a value name not in the value table
  CHECK(firstErrorPath(R"({"rules": [{"set": {"BMS.BMS_Status.ContactorState": "Shut"}}]})") ==
        "/rules/0/set/BMS.BMS_Status.ContactorState");
  // a value outside the DBC range
  CHECK(firstErrorPath(R"({"faults": {"low": {"set": {"BMS.BMS_Status.SOC": 150}}}})") ==
        "/faults/low/set/BMS.BMS_Status.SOC");
  // an unknown key, a bad duration, a missing set
  CHECK(firstErrorPath(R"({"rules": [{"set": {}, "colour": 1}]})") == "/rules/0/colour");
  CHECK(firstErrorPath(R"({"rules": [{"set": {}, "after": "soon"}]})") == "/rules/0/after");
  CHECK(firstErrorPath(R"({"rules": [{"when": {}}]})") == "/rules/0/set");
  // conditions: an operator without key, quality (fsm.json only), in with an empty list
  CHECK(firstErrorPath(R"({"rules": [{"when": {"eq": 1}, "set": {}}]})") == "/rules/0/when");
  CHECK(firstErrorPath(R"({"rules": [{"when": {"key": "INV.INV_Status.State", "quality": "valid"}, "set": {}}]})") ==
        "/rules/0/when");
  CHECK(firstErrorPath(R"({"rules": [{"when": {"any": [{"key": "INV.INV_Status.State", "in": []}]}, "set": {}}]})") ==
        "/rules/0/when/any/0/in");
  // follow: no time constant, a target that is neither a key nor a number
  CHECK(firstErrorPath(R"({"follow": [{"signal": "INV.INV_Status.MotorSpeed", "target": 0}]})") ==
        "/follow/0/timeConstant");
  CHECK(firstErrorPath(R"({"follow": [{"signal": "INV.INV_Status.MotorSpeed", "target": true, "timeConstant": "1s"}]})") ==
        "/follow/0/target");
  // integrate: min above max, a rate of the wrong kind
  CHECK(firstErrorPath(R"({"integrate": [{"signal": "BMS.BMS_Status.SOC", "rate": 1, "min": 50, "max": 40}]})") ==
        "/integrate/0/min");
  CHECK(firstErrorPath(R"({"integrate": [{"signal": "BMS.BMS_Status.SOC", "rate": "fast"}]})") == "/integrate/0/rate");
  // fault names: silent.<NODE> is built in
  CHECK(firstErrorPath(R"({"faults": {"silent.BMS": {"set": {}}}})") == "/faults/silent.BMS");
  // sim.safety.ok without pairs to check
  CHECK(firstErrorPath(R"({"rules": [{"when": {"sim.safety.ok": 1}, "set": {}}]})") == "/rules/0/when/sim.safety.ok");
}
