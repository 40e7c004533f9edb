// libFuzzer target: vcu-ecu-sim's simulation file (simulation.json,
// services/ecu-sim/README.md) through loadSimConfig on the HHEA vehicle.
// Invariants: no crash, hang or leak; a refused file names an error.
#include "fuzz_support.hpp"

#include "openvcu/config/simulation.hpp"

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  const std::string path = fuzz::scratch().write("simulation.json", data, size);
  auto simResult = config::loadSimConfig(path, hhea.vehicle);
  if (!simResult) fuzz::require(!simResult.error().message.empty());
  return 0;
}
