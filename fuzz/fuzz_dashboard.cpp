// libFuzzer target: vcu-hmi's dashboard file (dashboard.json, services/hmi/README.md)
// through hmi::parseDashboardConfig on the HHEA catalog (display_logic.cpp is Qt-free and
// compiled into the target; Qt is not needed).
// Invariants: no crash, hang or leak; a refused file names an error.
#include "fuzz_support.hpp"

#include "display_logic.hpp"

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  auto dashboardResult = hmi::parseDashboardConfig(fuzz::asText(data, size), "dashboard.json", hhea.catalog);
  if (!dashboardResult) fuzz::require(!dashboardResult.error().message.empty());
  return 0;
}
