// libFuzzer target: the GPIO map (gpio.json, docs/gpio.md) through config::loadGpioMap
// with HHEA's internal signals as the declared ones.
// Invariants: no crash, hang or leak; a refused map has an error diagnostic; a loaded one
// has chip indices in range and no error diagnostic.
#include "fuzz_support.hpp"

#include <vector>

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  const std::string path = fuzz::scratch().write("gpio.json", data, size);
  std::vector<Error> diagnostics;
  const auto maybeMap = config::loadGpioMap(path, hhea.vehicle.internalSignals, diagnostics);
  bool anyError = false;
  for (const Error& diagnostic : diagnostics) anyError = anyError || diagnostic.severity == Severity::Error;
  fuzz::require(maybeMap.has_value() != anyError);
  if (maybeMap) {
    for (const config::GpioLine& line : maybeMap->lines) fuzz::require(line.chip < maybeMap->chips.size());
  }
  return 0;
}
