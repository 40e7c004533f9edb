// libFuzzer target: vehicle.json through config::loadVehicleConfig (the loader takes a
// path: the input is written to a scratch folder holding the DBCs and configuration files
// the seeds name: small.dbc, rx.dbc, hhea.dbc and HHEA's fsm/schedule/gpio/simulation/
// dashboard), then config::buildCatalog on a loaded configuration.
// Invariants: no crash, hang or leak; a refused file names an error; a loaded one has an
// instance name loadVehicleConfig calls valid and buses whose message indices exist.
#include "fuzz_support.hpp"

#include <vector>

using namespace openvcu;

namespace {

void prepare(fuzz::Scratch& folder) {
  const std::string root = fuzz::sourceDir();
  folder.link("small.dbc", root + "/tests/data/config/small.dbc");
  folder.link("rx.dbc", root + "/tests/data/can-rx/rx.dbc");
  folder.link("receive.json", root + "/tests/data/can-rx/receive.json");
  for (const char* name : {"hhea.dbc", "fsm.json", "schedule.json", "gpio.json", "simulation.json", "dashboard.json"}) {
    folder.link(name, root + "/config/hhea/" + name);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static fuzz::Scratch& folder = [] () -> fuzz::Scratch& {
    prepare(fuzz::scratch());
    return fuzz::scratch();
  }();
  const std::string path = folder.write("vehicle.json", data, size);
  std::vector<Error> warnings;
  auto vehicleResult = config::loadVehicleConfig(path, &warnings);
  if (!vehicleResult) {
    fuzz::require(!vehicleResult.error().message.empty());
    return 0;
  }
  const config::VehicleConfig& vehicle = *vehicleResult;
  fuzz::require(config::validInstanceName(vehicle.instance));
  for (const config::BusConfig& bus : vehicle.buses) {
    for (std::size_t index : bus.messages) fuzz::require(index < vehicle.database.messages.size());
  }
  auto catalogResult = config::buildCatalog(vehicle);
  if (catalogResult) fuzz::require(catalogResult->size() > 0);
  return 0;
}
