// Issue #19, "every bad input refused", for the HMI's dashboard.json: read through the one
// JSON reader, so an item given twice refuses the file with both places and its JSON path.

#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "dashboard_test_catalog.hpp"
#include "openvcu/config/dashboard.hpp"

using namespace openvcu;
using namespace openvcu::config;

TEST_CASE("#19 a dashboard file with a key given twice is refused with both places") {
  std::vector<signals::SignalInfo> infos;
  infos.push_back(openvcu::testing::socSignalInfo());
  auto catalog = signals::Catalog::create(std::move(infos));
  REQUIRE(catalog);

  const auto sut = parseDashboardConfig(
      "{\"items\": [{\"key\": \"VIC.HVESSD2_PGN61585.HS_FastUpdSOC\",\n"
      "              \"key\": \"internal.relay.Cl15\"}]}",
      "dash.json", *catalog);

  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString() == "dash.json:2:15: /items/0: key \"key\" given twice (first at 1:13)");
}
