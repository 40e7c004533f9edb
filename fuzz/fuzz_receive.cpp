// libFuzzer target: vcu-can-rx's receive settings (receive.json,
// services/can-rx/README.md) through loadReceiveConfig on the can-rx test vehicle
// (tests/data/can-rx: two buses, a J1939-76 pair, forwarding) and on HHEA.
// Invariants: no crash, hang or leak; a refused file names an error.
#include "fuzz_support.hpp"

#include "openvcu/config/receive.hpp"

using namespace openvcu;

namespace {

const config::VehicleConfig& rxVehicle() {
  static const config::VehicleConfig vehicle = [] {
    auto result = config::loadVehicleConfig(fuzz::sourceDir() + "/tests/data/can-rx/vehicle.json");
    fuzz::require(result.ok());
    return std::move(*result);
  }();
  return vehicle;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static config::VehicleConfig rx = rxVehicle();  // copies made once: only receiveFile changes
  static config::VehicleConfig hhea = fuzz::hhea().vehicle;
  const std::string path = fuzz::scratch().write("receive.json", data, size);
  for (config::VehicleConfig* vehicle : {&rx, &hhea}) {
    vehicle->receiveFile = path;
    auto receiveResult = config::loadReceiveConfig(*vehicle);
    if (!receiveResult) fuzz::require(!receiveResult.error().message.empty());
  }
  return 0;
}
