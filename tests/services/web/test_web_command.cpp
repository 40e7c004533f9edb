// vcu-web's command check (shared/commands, openvcu::commands::parseCommand): what a page sends, refused with
// its JSON path before anything reaches the stack, or turned into the request the HMI sends.
#include <doctest/doctest.h>

#include "openvcu/commands/command_check.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"

namespace {

using namespace openvcu;

struct Hhea {
  config::VehicleConfig vehicle;
  signals::Catalog catalog;
};

const Hhea& hhea() {
  static const Hhea loaded = [] {
    auto vehicle = config::loadVehicleConfig(OPENVCU_SOURCE_DIR "/config/hhea/vehicle.json");
    REQUIRE(vehicle);
    auto catalog = config::buildCatalog(*vehicle);
    REQUIRE(catalog);
    return Hhea{std::move(*vehicle), std::move(*catalog)};
  }();
  return loaded;
}

Result<ipc::CommandRequest> parse(std::string_view body) {
  return commands::parseCommand(body, hhea().catalog, hhea().vehicle.database);
}

std::string errorOf(std::string_view body) {
  auto parsed = parse(body);
  REQUIRE_FALSE(parsed);
  return parsed.error().message;
}

}  // namespace

TEST_CASE("an operator switch by its value text becomes an OperatorSwitch with the raw value") {
  auto sut = parse(R"({"kind":"operator","key":"internal.operator.StartStop","value":"Start"})");
  REQUIRE(sut);
  CHECK(sut->kind == ipc::CommandKind::OperatorSwitch);
  CHECK(sut->key == "internal.operator.StartStop");
  CHECK(sut->value == 1);
  CHECK(commands::describeCommand(*sut) == "operator internal.operator.StartStop = 1");
}

TEST_CASE("a command is refused with the JSON path of what is wrong") {
  CHECK(errorOf("{not json").starts_with("/: not JSON ("));
  // one JSON policy with the configuration reader: a key given twice is refused, at any level
  CHECK(errorOf(R"({"kind":"operator","key":"internal.operator.StartStop","value":"Stop","value":"Start"})") ==
        R"(/: key "value" given twice (first at 1:56), at 1:71)");
  CHECK(errorOf("[1]").starts_with("/: expected an object"));
  CHECK(errorOf(R"({"kind":"reboot","key":"x"})").starts_with("/kind: unknown kind 'reboot'"));
  CHECK(errorOf(R"({"kind":"set","key":"VIC.NoSuch.Signal","value":1})") == "/key: unknown signal 'VIC.NoSuch.Signal'");
  CHECK(errorOf(R"({"kind":"set","key":"internal.operator.StartStop"})") == "/value: missing");
  CHECK(errorOf(R"({"kind":"operator","key":"internal.operator.StartStop","value":"Go"})")
            .starts_with("/value: 'Go' is not a value of internal.operator.StartStop"));
  CHECK(errorOf(R"({"kind":"operator","key":"internal.relay.Cl15","value":1})").starts_with("/key: 'internal.relay.Cl15' is not an operator switch"));
  CHECK(errorOf(R"({"kind":"set","key":"internal.relay.Cl15","value":1,"shell":"rm -rf /"})") == "/shell: unknown member");
  CHECK(errorOf(R"({"kind":"scheduleCycle","key":"NoSuchMessage","value":10})") == "/key: no DBC message 'NoSuchMessage'");
}

TEST_CASE("schedule commands take a DBC message and a bounded value") {
  auto cycle = parse(R"({"kind":"scheduleCycle","key":"HC1_Demands","value":50})");
  REQUIRE(cycle);
  CHECK(cycle->kind == ipc::CommandKind::ScheduleCycle);
  CHECK(cycle->value == 50);
  CHECK(errorOf(R"({"kind":"scheduleCycle","key":"HC1_Demands","value":0})") == "/value: a cycle of 1 to 3600000 ms");
  CHECK(errorOf(R"({"kind":"scheduleEnable","key":"HC1_Demands","value":2})") == "/value: 1 (transmit) or 0 (stop)");
}

TEST_CASE("a fault reset is the FSM's reset switch set to 1 as the HMI sends it") {
  auto sut = parse(R"({"kind":"faultReset"})");
  REQUIRE(sut);
  CHECK(sut->kind == ipc::CommandKind::SetSignal);
  CHECK(sut->key == "internal.operator.FaultReset");
  CHECK(sut->value == 1);
}
