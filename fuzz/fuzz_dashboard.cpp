// libFuzzer target: vcu-hmi's dashboard file (dashboard.json, services/hmi/README.md)
// through config::parseDashboardConfig (shared/config) on the HHEA catalog.
// Invariants: no crash, hang or leak; a refused file names an error.
#include "fuzz_support.hpp"

#include "openvcu/config/dashboard.hpp"

using namespace openvcu;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::Hhea& hhea = fuzz::hhea();
  auto dashboardResult = config::parseDashboardConfig(fuzz::asText(data, size), "dashboard.json", hhea.catalog);
  if (!dashboardResult) fuzz::require(!dashboardResult.error().message.empty());
  return 0;
}
