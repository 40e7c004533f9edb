#include "config_fixture.hpp"
#include "openvcu/config/catalog.hpp"

#include <doctest/doctest.h>

#include <set>
#include <string_view>

using namespace openvcu;
using namespace openvcu::config;
using openvcu::test::CONFIG_DATA_DIR;

TEST_CASE("the catalog lists bus signals by bus order, then internal and built-in signals") {
  const auto config = loadVehicleConfig(CONFIG_DATA_DIR + "/small.json");
  REQUIRE(config.ok());
  const auto sut = buildCatalog(*config);
  REQUIRE(sut.ok());
  REQUIRE(sut->size() >= 5);
  CHECK((*sut)[0].key == "VCU.Command.Enable");
  CHECK((*sut)[0].bus == "vehicle");
  CHECK((*sut)[1].key == "BMS.Status.SOC");
  CHECK((*sut)[1].unit == "%");
  CHECK((*sut)[1].comment == "state of charge");
  CHECK((*sut)[2].key == "BMS.Status.Mode");
  CHECK((*sut)[2].valueTexts.size() == 3);
  CHECK((*sut)[3].key == "internal.operator.Start");
  CHECK((*sut)[3].kind == signals::SignalKind::Internal);
  CHECK(sut->indexOf("internal.fsm.state").has_value());
  CHECK(sut->indexOf("internal.service.can-rx.heartbeat").has_value());
}

TEST_CASE("the same configuration always yields the same layout hash") {
  const auto config = loadVehicleConfig(CONFIG_DATA_DIR + "/small.json");
  REQUIRE(config.ok());
  const auto first = buildCatalog(*config);
  const auto second = buildCatalog(*config);
  REQUIRE(first.ok());
  REQUIRE(second.ok());
  CHECK(first->layoutHash() == second->layoutHash());
}

TEST_CASE("an internal signal named like a built-in one is refused") {
  auto config = loadVehicleConfig(CONFIG_DATA_DIR + "/small.json");
  REQUIRE(config.ok());
  config->internalSignals.push_back(InternalSignal{"fsm.state", "", 0, 1, 0, "", {}});
  CHECK_FALSE(buildCatalog(*config).ok());
}

TEST_CASE("the HHEA catalog holds every decodable signal of its DBC") {
  const auto config = loadVehicleConfig(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json");
  REQUIRE(config.ok());
  const auto sut = buildCatalog(*config);
  REQUIRE_MESSAGE(sut.ok(), (sut.ok() ? "" : sut.error().toString()));
  CHECK(sut->indexOf("VIC.HVESSD2_PGN61585.HS_FastUpdSOC").has_value());
  CHECK(sut->indexOf("internal.operator.StartStop").has_value());
}

TEST_CASE("the services of a stack have unique names and writer ids, found both ways (#20)") {
  std::set<std::string_view> names;
  std::set<openvcu::signals::WriterId> writers;
  for (const config::ServiceEntry& entry : config::SERVICES) {
    CHECK(names.insert(entry.name).second);
    CHECK(writers.insert(entry.writer).second);
    CHECK(entry.writer > 0);
    CHECK(entry.writer < 200);  // 200 and up: tools and tests
    CHECK(&config::serviceEntry(entry.id) == &entry);
    CHECK(config::serviceOfWriter(entry.writer) == entry.name);
    CHECK(config::findService(entry.name) == &entry);
  }
  CHECK(config::writerOf(config::ServiceId::Fsm) == 3);
  CHECK_FALSE(config::serviceOfWriter(240).has_value());
  CHECK(config::findService("vcu-fsm") == nullptr);
}
