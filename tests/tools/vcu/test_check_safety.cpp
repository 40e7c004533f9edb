// `vcu check` and safety.json: the shipped vehicles' safety cases counted and passed, broken
// ones refused with the file and the JSON path; copies of config/hhea made by the test.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;
namespace fs = std::filesystem;

namespace {

const fs::path CONFIG_ROOT = fs::path(OPENVCU_SOURCE_DIR) / "config";

/// A copy of config/<vehicle> in the scratch folder under `name`, with the first `from` in
/// `file` replaced by `to` when given; returns the copy's vehicle.json.
std::string vehicleCopy(const std::string& vehicle, const std::string& name, const std::string& file = {},
                        const std::string& from = {}, const std::string& to = {}) {
  const fs::path folder = scratchFolder() / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(CONFIG_ROOT / vehicle)) {
    if (entry.is_regular_file()) fs::copy_file(entry.path(), folder / entry.path().filename());
  }
  if (!file.empty()) {
    std::ifstream in(folder / file);
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const auto at = text.find(from);
    REQUIRE_MESSAGE(at != std::string::npos, from);
    text.replace(at, from.size(), to);
    writeScratchFile(name + "/" + file, text);
  }
  return (folder / "vehicle.json").string();
}

}  // namespace

TEST_CASE("vcu check checks the shipped safety cases and counts safety.json") {
  const RunResult hhea = runVcu({"check", "--config", (CONFIG_ROOT / "hhea/vehicle.json").string()});
  CHECK_MESSAGE(hhea.exitCode == EXIT_OK, hhea.err);
  CHECK(contains(hhea.out, "safety.json: 0 errors, 0 warnings\n"));
  CHECK(contains(hhea.out, "vehicle 'hhea': 12 files, 0 errors"));
  const RunResult tractor = runVcu({"check", "--config", (CONFIG_ROOT / "tractor/vehicle.json").string()});
  CHECK_MESSAGE(tractor.exitCode == EXIT_OK, tractor.err);
  CHECK(contains(tractor.out, "safety.json: 0 errors, 0 warnings\n"));
}

TEST_CASE("vcu check refuses a safety.json naming an FSM state the machine lacks, at its JSON path") {
  const std::string vehicle = vehicleCopy("hhea", "check_safety_state", "safety.json",
                                          R"("fsmStates": ["Battery Timeout"])", R"("fsmStates": ["Battery Timout"])");
  const RunResult result = runVcu({"check", "--config", vehicle});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(result.err,
                         "check_safety_state/safety.json: /hazards/1/safeState/fsmStates/0: error: no FSM "
                         "state 'Battery Timout' in "),
                result.err);
  CHECK(contains(result.err, "did you mean 'Battery Timeout'?"));
  CHECK(contains(result.out, "safety.json: 1 error"));
  CHECK(contains(result.out, "12 files, 1 error"));
}

TEST_CASE("vcu check refuses a safety.json its loader refuses, with the JSON path, and one that does not parse") {
  const std::string ftti =
      vehicleCopy("hhea", "check_safety_ftti", "safety.json", R"("fttiMs": 4000)", R"("fttiMs": 0)");
  const RunResult refused = runVcu({"check", "--config", ftti});
  CHECK(refused.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(refused.err,
                         "check_safety_ftti/safety.json: /hazards/1/fttiMs: error: must be a whole number "
                         "of ms above 0"),
                refused.err);
  CHECK(contains(refused.out, "safety.json: 1 error"));

  const std::string syntax =
      vehicleCopy("hhea", "check_safety_syntax", "safety.json", R"("hazards": [)", R"("hazards": [,)");
  const RunResult broken = runVcu({"check", "--config", syntax});
  CHECK(broken.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(broken.err, "check_safety_syntax/safety.json:"), broken.err);
  CHECK(contains(broken.out, "safety.json: 1 error"));
}

TEST_CASE("vcu check refuses a vehicle.json naming a safety file that does not exist") {
  const std::string vehicle = vehicleCopy("tractor", "check_safety_missing", "vehicle.json",
                                          R"("safety": "safety.json")", R"("safety": "hazards.json")");
  const RunResult result = runVcu({"check", "--config", vehicle});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(result.err, "vehicle.json: /safety: error: file '"), result.err);
}

TEST_CASE("vcu check gives safety.json the syntax check while vehicle.json does not load") {
  const std::string vehicle = vehicleCopy("hhea", "check_safety_vehicle_error", "vehicle.json",
                                          R"("node": "Vehicle_Control_Unit")", R"("node": "Vehicle_Control_Unix")");
  writeScratchFile("check_safety_vehicle_error/safety.json", "{\n  \"hazards\": [\n}");
  const RunResult result = runVcu({"check", "--config", vehicle});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK_MESSAGE(contains(result.err, "check_safety_vehicle_error/safety.json:3:"), result.err);
}
