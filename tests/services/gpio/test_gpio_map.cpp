// The GPIO map: the HHEA file, the keys it adds to the catalog, and refusals with file,
// JSON path and reason.

#include <filesystem>
#include <fstream>

#include "gpio_test_support.hpp"

using namespace gpiotest;
namespace fs = std::filesystem;

namespace {

/// Loads `gpioText` as the GPIO map of a copy of the HHEA configuration; the diagnostics.
std::vector<Error> loadMap(const std::string& gpioText, std::optional<config::GpioMap>* map = nullptr) {
  const fs::path folder = fs::temp_directory_path() / ("openvcu-gpio-map-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  const fs::path file = folder / "gpio.json";
  std::ofstream(file) << gpioText;
  auto vehicle = config::loadVehicleConfig(HHEA);
  REQUIRE(vehicle);
  std::vector<Error> diagnostics;
  auto loaded = config::loadGpioMap(file.string(), vehicle->internalSignals, diagnostics);
  if (map) *map = std::move(loaded);
  fs::remove_all(folder);
  return diagnostics;
}

bool has(const std::vector<Error>& diagnostics, const std::string& path, const std::string& part) {
  for (const Error& diagnostic : diagnostics) {
    if (diagnostic.location.jsonPath == path && diagnostic.message.find(part) != std::string::npos) return true;
  }
  return false;
}

std::string listing(const std::vector<Error>& diagnostics) {
  std::string text;
  for (const Error& diagnostic : diagnostics) text += diagnostic.toString() + "\n";
  return text;
}

const std::string CHIPS = R"("chips": [{"id": "main", "device": "gpiochip0"}])";

}  // namespace

TEST_CASE("the HHEA GPIO map: the Cl15 relay with 2 s delays and the contactor-fault input, and their keys") {
  Fixture f;
  const config::GpioMap& map = f.vehicle.gpio;
  REQUIRE(map.lines.size() == 2);
  CHECK(map.backend == config::GpioBackend::Sim);
  const config::GpioLine& relay = map.lines[f.line("Cl15")];
  CHECK(relay.direction == config::LineDirection::Output);
  CHECK(relay.offset == 17u);
  CHECK(relay.onDelayNs == 2 * SECOND);
  CHECK(relay.offDelayNs == 2 * SECOND);
  CHECK(relay.signal == "internal.relay.Cl15");
  const config::GpioLine& fault = map.lines[f.line("ContactorFault")];
  CHECK(fault.debounceNs == 20 * MS);
  CHECK(fault.bias == config::LineBias::PullDown);
  CHECK(map.inputBoundTo("internal.fault.Contactor") == &fault);
  CHECK(map.inputBoundTo("internal.relay.Cl15") == nullptr);
  for (const char* key : {"internal.gpio.Cl15", "internal.gpio.ContactorFault", "internal.gpio.sim.ContactorFault"}) {
    CHECK_MESSAGE(f.catalog.indexOf(key), key);
  }
  CHECK_FALSE(f.catalog.indexOf("internal.gpio.sim.Cl15"));  // outputs have no simulated input level
}

TEST_CASE("a GPIO map with mistakes is refused with the JSON path and the reason of each") {
  std::optional<config::GpioMap> map;
  const auto diagnostics = loadMap(R"({"backend": "gpiodd", )" + CHIPS + R"(, "lines": [
    {"name": "Cl15", "chip": "mian", "offset": 17, "direction": "output", "debounce": "5ms", "signal": "relay.Cl51"},
    {"name": "In", "chip": "main", "offset": 4, "line": "GPIO4", "direction": "in", "onDelay": "2 s", "signal": "operator.StartStop"},
    {"name": "Cl15", "chip": "main", "offset": 17, "direction": "input", "bias": "up", "signal": "relay.Cl15"}
  ]})", &map);
  INFO(listing(diagnostics));
  CHECK_FALSE(map);
  CHECK(has(diagnostics, "/backend", "expected \"sim\" or \"gpiod\""));
  CHECK(has(diagnostics, "/lines/0/chip", "did you mean 'main'?"));
  CHECK(has(diagnostics, "/lines/0/debounce", "only an input line has \"debounce\""));
  CHECK(has(diagnostics, "/lines/0/signal", "did you mean 'relay.Cl15'?"));
  CHECK(has(diagnostics, "/lines/1", "give exactly one of \"offset\""));
  CHECK(has(diagnostics, "/lines/1/direction", "expected \"input\" or \"output\""));
  CHECK(has(diagnostics, "/lines/1/onDelay", "a duration with a unit"));
  CHECK(has(diagnostics, "/lines/2/name", "line 'Cl15' is declared twice"));
  CHECK(has(diagnostics, "/lines/2", "offset 17 of this chip is already used by line 'Cl15'"));
  CHECK(has(diagnostics, "/lines/2/bias", "expected \"as-is\""));
}

TEST_CASE("a GPIO map line bound to a signal that cannot hold 0 and 1, or bound twice, is refused") {
  const auto diagnostics = loadMap(R"({)" + CHIPS + R"(, "lines": [
    {"name": "A", "chip": "main", "offset": 1, "direction": "output", "signal": "relay.Cl15"},
    {"name": "B", "chip": "main", "offset": 2, "direction": "input", "signal": "relay.Cl15"}
  ]})");
  INFO(listing(diagnostics));
  CHECK(has(diagnostics, "/lines/1/signal", "'internal.relay.Cl15' is already bound to line 'A'"));
  const auto syntax = loadMap("{\"chips\": [\n  {\"id\": \"main\",}\n]}");
  REQUIRE(syntax.size() == 1);
  CHECK(syntax[0].location.line == 2);
}

TEST_CASE("the vehicle configuration refuses a bad GPIO map with the map's file and path") {
  const fs::path folder = fs::temp_directory_path() / ("openvcu-gpio-vehicle-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  fs::copy(fs::path(OPENVCU_SOURCE_DIR) / "config" / "hhea", folder,
           fs::copy_options::overwrite_existing | fs::copy_options::recursive);
  std::ofstream(folder / "gpio.json") << R"({)" + CHIPS + R"(, "lines": [{"name": "X", "chip": "main", "offset": 1, "direction": "output", "signal": "relay.Cl15", "initial": 2}]})";
  auto loaded = config::loadVehicleConfig((folder / "vehicle.json").string());
  REQUIRE_FALSE(loaded);
  CHECK(loaded.error().toString().find("gpio.json") != std::string::npos);
  CHECK(loaded.error().location.jsonPath == "/lines/0/initial");
  fs::remove_all(folder);
}
