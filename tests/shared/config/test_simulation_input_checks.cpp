// Issue #19, "every bad input refused", for the simulation file: read through the one JSON
// reader (a key given twice, a number beyond a double refused with place and path), and a
// range error prints its numbers short (not the 309 digits of std::to_string(1e308)).

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "openvcu/config/simulation.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";

Result<config::SimConfig> loadText(const std::string& text) {
  auto vehicle = config::loadVehicleConfig(HHEA);
  REQUIRE_MESSAGE(vehicle, (vehicle ? "" : vehicle.error().toString()));
  const fs::path file = fs::temp_directory_path() / ("openvcu-sim-input-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << text;
  auto result = config::loadSimConfig(file.string(), *vehicle);
  fs::remove(file);
  return result;
}

}  // namespace

TEST_CASE("#19 a simulation file with a key given twice is refused with both places") {
  const auto sut = loadText("{\"battery\": {\"lowSoc\": 15,\n  \"lowSoc\": 150}}");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().ends_with(":2:3: /battery: key \"lowSoc\" given twice (first at 1:14)"));
}

TEST_CASE("#19 a fault value beyond a double (infinity) is refused with its place and JSON path") {
  const auto sut = loadText(R"({"battery": {"lowSoc": 1e400}})");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().location.jsonPath == "/battery/lowSoc");
  CHECK(sut.error().location.column == 24);
  CHECK(sut.error().message.find("out of range") != std::string::npos);
}

TEST_CASE("#19 a range error names the bounds and the value in short form") {
  const auto sut = loadText(R"({"model": "hhea", "battery": {"capacityAh": 1e308}})");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().ends_with("/battery/capacityAh: must be within [0.1, 10000], not 1e+308"));
}
