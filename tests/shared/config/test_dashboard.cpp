// The HMI dashboard file (dashboard.json, config::parseDashboardConfig): defaults for
// label, unit and format, the dials' scales, the header and status keys checked against
// the catalog, and every refusal with its JSON path (issue 10; loader in shared/config
// since issue 20).
#include <doctest/doctest.h>

#include "dashboard_test_catalog.hpp"

#include <string>
#include <vector>

#include "openvcu/config/dashboard.hpp"

using namespace openvcu;
using namespace openvcu::config;

namespace {

signals::Catalog smallCatalog() { return openvcu::testing::dashboardCatalog(); }

}  // namespace

TEST_CASE("a dashboard file is read with defaults for label, unit and format") {
  const signals::Catalog catalog = smallCatalog();
  const auto sut = parseDashboardConfig(
      R"({"dials": {"voltage": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC"},
          "items": [{"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC"}, {"key": "internal.relay.Cl15", "label": "Cl15", "format": "%.0f"}]})",
      "dash.json", catalog);
  REQUIRE_MESSAGE(sut, sut.error().toString());
  REQUIRE(sut->items.size() == 2);
  CHECK(sut->items[0].label == "HS_FastUpdSOC");
  CHECK(sut->items[0].unit == "%");
  CHECK(sut->items[0].format == "%.1f");
  CHECK(sut->items[1].label == "Cl15");
  CHECK(sut->voltageKey == "VIC.HVESSD2_PGN61585.HS_FastUpdSOC");
  CHECK(sut->staleAfterMs == 2000);
  CHECK(sut->socKey.empty());
  CHECK(sut->statusKeys.empty());
}

TEST_CASE("a dashboard file names the header's and the status table's signals and they are checked too") {
  const signals::Catalog catalog = smallCatalog();
  const auto sut = parseDashboardConfig(
      R"({"header": {"soc": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC"}, "status": ["internal.relay.Cl15", "internal.fault.Contactor"], "items": []})",
      "dash.json", catalog);
  REQUIRE_MESSAGE(sut, sut.error().toString());
  CHECK(sut->socKey == "VIC.HVESSD2_PGN61585.HS_FastUpdSOC");
  CHECK(sut->statusKeys == std::vector<std::string>{"internal.relay.Cl15", "internal.fault.Contactor"});
  const auto badStatus = parseDashboardConfig(R"({"status": ["internal.relay.Cl15", 7], "items": []})", "d", catalog);
  REQUIRE_FALSE(badStatus);
  CHECK(badStatus.error().toString().find("/status/1") != std::string::npos);
  const auto badHeader = parseDashboardConfig(R"({"header": {"soc": "nope"}, "items": []})", "d", catalog);
  REQUIRE_FALSE(badHeader);
  CHECK(badHeader.error().toString().find("/header/soc") != std::string::npos);
}

TEST_CASE("a dial is a key or a key with its scale, checked (defaults 0..1000 V, -400..400 A, -300..300 kW)") {
  const signals::Catalog catalog = smallCatalog();
  const auto sut = parseDashboardConfig(
      R"({"dials": {"voltage": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "min": 0, "max": 850},
                    "power": {"min": -150, "max": 250}}, "items": []})",
      "dash.json", catalog);
  REQUIRE_MESSAGE(sut, sut.error().toString());
  CHECK(sut->voltageKey == "VIC.HVESSD2_PGN61585.HS_FastUpdSOC");
  CHECK(sut->voltageRange.minimum == 0);
  CHECK(sut->voltageRange.maximum == 850);
  CHECK(sut->currentRange.minimum == -400);  // not in the file: the default
  CHECK(sut->currentRange.maximum == 400);
  CHECK(sut->powerKey.empty());  // computed from U x I
  CHECK(sut->powerRange.minimum == -150);
  CHECK(sut->powerRange.maximum == 250);
  const auto inverted =
      parseDashboardConfig(R"({"dials": {"current": {"min": 5, "max": -5}}, "items": []})", "d", catalog);
  REQUIRE_FALSE(inverted);
  CHECK(inverted.error().toString().find("/dials/current: min must be below max") != std::string::npos);
  const auto wrongType = parseDashboardConfig(R"({"dials": {"voltage": 12}, "items": []})", "d", catalog);
  REQUIRE_FALSE(wrongType);
  CHECK(wrongType.error().toString().find("/dials/voltage") != std::string::npos);
  const auto badKey = parseDashboardConfig(R"({"dials": {"voltage": {"key": "nope"}}, "items": []})", "d", catalog);
  REQUIRE_FALSE(badKey);
  CHECK(badKey.error().toString().find("/dials/voltage/key") != std::string::npos);
  const auto extra = parseDashboardConfig(R"({"dials": {"voltage": {"maximum": 5}}, "items": []})", "d", catalog);
  REQUIRE_FALSE(extra);
}

TEST_CASE("a dashboard file with an unknown key is refused with its JSON path and a suggestion") {
  const signals::Catalog catalog = smallCatalog();
  const auto sut = parseDashboardConfig(R"({"items": [{"key": "internal.relay.Cl16"}]})", "dash.json", catalog);
  REQUIRE_FALSE(sut);
  const std::string text = sut.error().toString();
  CHECK_MESSAGE(text.find("/items/0/key") != std::string::npos, text);
  CHECK_MESSAGE(text.find("did you mean 'internal.relay.Cl15'") != std::string::npos, text);
}

TEST_CASE("a dashboard file with bad JSON, a bad format or a mistyped member is refused, never thrown") {
  const signals::Catalog catalog = smallCatalog();
  CHECK_FALSE(parseDashboardConfig("{", "dash.json", catalog));
  CHECK_FALSE(parseDashboardConfig(R"({"items": [{"key": "internal.relay.Cl15", "format": "%s"}]})", "d", catalog));
  CHECK_FALSE(parseDashboardConfig(R"({"itemz": []})", "d", catalog));
  CHECK_FALSE(parseDashboardConfig(R"({"items": [], "staleAfterMs": 5})", "d", catalog));
  CHECK_FALSE(loadDashboardConfig("/nonexistent/dash.json", catalog));
}

TEST_CASE("a number format is one printf number conversion and nothing that reads memory") {
  CHECK(isSafeNumberFormat("%.1f"));
  CHECK(isSafeNumberFormat("%+08.3e %%"));
  CHECK_FALSE(isSafeNumberFormat("%s"));
  CHECK_FALSE(isSafeNumberFormat("%n"));
  CHECK_FALSE(isSafeNumberFormat("%.1f %.1f"));
  CHECK_FALSE(isSafeNumberFormat("no conversion"));
}
