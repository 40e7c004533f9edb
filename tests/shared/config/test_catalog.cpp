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

namespace {

const signals::SignalInfo& signalOf(const signals::Catalog& catalog, std::string_view key) {
  const auto index = catalog.indexOf(key);
  REQUIRE_MESSAGE(index.has_value(), key);
  return catalog[*index];
}

std::string_view ownerOf(const signals::Catalog& catalog, std::string_view key) {
  return serviceOfWriter(signalOf(catalog, key).owner).value_or("none");
}

}  // namespace

TEST_CASE("each signal of the catalog says its direction and the one service that owns it (#20)") {
  const auto config = loadVehicleConfig(CONFIG_DATA_DIR + "/small.json");
  REQUIRE(config.ok());
  const auto sut = buildCatalog(*config);
  REQUIRE(sut.ok());

  CHECK(signalOf(*sut, "VCU.Command.Enable").direction == signals::SignalDirection::Transmitted);
  CHECK(ownerOf(*sut, "VCU.Command.Enable") == "can-tx");
  CHECK(signalOf(*sut, "BMS.Status.SOC").direction == signals::SignalDirection::Received);
  CHECK(ownerOf(*sut, "BMS.Status.SOC") == "can-rx");
  CHECK(signalOf(*sut, "internal.operator.Start").direction == signals::SignalDirection::Internal);
  CHECK(ownerOf(*sut, "internal.operator.Start") == "fsm");
  CHECK_FALSE(signalOf(*sut, "internal.operator.Start").reported);
  CHECK(ownerOf(*sut, "internal.fsm.state") == "fsm");
  CHECK(signalOf(*sut, "internal.fsm.state").reported);
  CHECK(ownerOf(*sut, "internal.service.gpio.heartbeat") == "gpio");
  CHECK(signalOf(*sut, "internal.service.gpio.heartbeat").reported);
  CHECK(ownerOf(*sut, "internal.bus.vehicle.load") == "can-rx");
  CHECK(signalOf(*sut, "internal.bus.vehicle.state").reported);
}

TEST_CASE("a send group belongs to can-tx and an input-bound signal to vcu-gpio (#20)") {
  auto config = loadVehicleConfig(CONFIG_DATA_DIR + "/small.json");
  REQUIRE(config.ok());
  config->internalSignals.push_back(InternalSignal{"tx.Pump", "", 0, 1, 0, "", {}});
  config->internalSignals.push_back(InternalSignal{"relay.Key", "", 0, 1, 0, "", {}});
  GpioLine key;
  key.name = "Key";
  key.direction = LineDirection::Input;
  key.signal = "internal.relay.Key";
  config->gpio.lines.push_back(key);

  const auto sut = buildCatalog(*config);

  REQUIRE_MESSAGE(sut.ok(), (sut.ok() ? "" : sut.error().toString()));
  CHECK(ownerOf(*sut, "internal.tx.Pump") == "can-tx");
  CHECK(ownerOf(*sut, "internal.relay.Key") == "gpio");
  CHECK(ownerOf(*sut, "internal.gpio.Key") == "gpio");
  CHECK(signalOf(*sut, "internal.gpio.Key").reported);
  CHECK(ownerOf(*sut, "internal.gpio.sim.Key") == "gpio");
  CHECK_FALSE(signalOf(*sut, "internal.gpio.sim.Key").reported);
}

TEST_CASE("a key two services would own is refused, naming the key and both owners (#20)") {
  auto config = loadVehicleConfig(CONFIG_DATA_DIR + "/small.json");
  REQUIRE(config.ok());
  config->internalSignals.push_back(InternalSignal{"tx.Pump", "", 0, 1, 0, "", {}});
  GpioLine pump;
  pump.name = "PumpSwitch";
  pump.direction = LineDirection::Input;
  pump.signal = "internal.tx.Pump";
  config->gpio.lines.push_back(pump);

  const auto sut = buildCatalog(*config);

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message ==
        "'internal.tx.Pump' has two owners: can-tx (a send group: the namespace internal.tx.) and gpio (input line "
        "'PumpSwitch' is bound to it); bind the line to another signal");
}

TEST_CASE("every signal of the HHEA loader has exactly one owning service (#20)") {
  const auto config = loadVehicleConfig(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json");
  REQUIRE(config.ok());
  const auto sut = buildCatalog(*config);
  REQUIRE(sut.ok());

  std::size_t owned = 0;
  for (const signals::SignalInfo& signal : sut->signals()) {
    if (serviceOfWriter(signal.owner).has_value()) ++owned;
    else MESSAGE("no owner: " << signal.key);
  }
  CHECK(owned == sut->size());
  CHECK(ownerOf(*sut, "internal.operator.StartStop") != "none");
}
