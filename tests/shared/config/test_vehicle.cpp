#include "config_fixture.hpp"
#include "openvcu/config/vehicle.hpp"

#include <doctest/doctest.h>

using namespace openvcu;
using namespace openvcu::config;
using openvcu::test::CONFIG_DATA_DIR;
using openvcu::test::TempConfig;

namespace {
constexpr auto GOOD_BUS = R"({"name": "vehicle", "link": "sim:vehicle", "messages": "all"})";

std::string withBus(const std::string& bus, const std::string& extra = "") {
  return R"({"instance": "t", "node": "VCU", "dbc": "small.dbc", "buses": [)" + bus + "]" + extra + "}";
}

std::string firstError(const std::string& json) {
  TempConfig file(json);
  const auto result = loadVehicleConfig(file.path());
  if (result.ok()) return "loaded";
  const std::string text = result.error().toString();
  return text.substr(text.find("vehicle.json") == std::string::npos ? 0 : text.find("vehicle.json"));
}
}  // namespace

TEST_CASE("the small test configuration loads with its buses, messages and internal signals") {
  const auto sut = loadVehicleConfig(CONFIG_DATA_DIR + "/small.json");
  REQUIRE_MESSAGE(sut.ok(), (sut.ok() ? "" : sut.error().toString()));
  CHECK(sut->instance == "test-small");
  CHECK(sut->node == "VCU");
  REQUIRE(sut->buses.size() == 2);
  CHECK(sut->buses[0].link.kind == LinkKind::Sim);
  CHECK(sut->buses[0].bitrate == 250000);
  REQUIRE(sut->buses[0].messages.size() == 1);
  CHECK(sut->database.messages[sut->buses[0].messages[0]].name == "Command");
  CHECK(sut->buses[1].link.toString() == "socketcan:can1");
  CHECK(sut->buses[1].messages.size() == 1);  // "all" takes what the vehicle bus left
  CHECK(sut->busOf(sut->buses[1].messages[0]) == &sut->buses[1]);
  REQUIRE(sut->internalSignals.size() == 1);
  CHECK(sut->internalSignals[0].values.size() == 2);
  CHECK(sut->lcmUrl == DEFAULT_LCM_URL);
}

TEST_CASE("the HHEA configuration loads") {
  const auto sut = loadVehicleConfig(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json");
  REQUIRE_MESSAGE(sut.ok(), (sut.ok() ? "" : sut.error().toString()));
  CHECK(sut->node == "Vehicle_Control_Unit");
  CHECK(!sut->buses.empty());
}

TEST_CASE("paths resolve relative to the configuration file") {
  TempConfig file(withBus(GOOD_BUS));
  const auto sut = loadVehicleConfig(file.path());
  REQUIRE(sut.ok());
  REQUIRE(sut->dbcFiles.size() == 1);
  CHECK(sut->dbcFiles[0] == file.dir() + "/small.dbc");
}

TEST_CASE("configuration errors name the file, the JSON path and the reason") {
  CHECK(firstError(withBus(R"({"name": "vehicle", "link": "cam:0", "messages": "all"})")) ==
        "vehicle.json: /buses/0/link: unknown link 'cam:0'; expected socketcan:IFACE, sim:NAME or replay:FILE");
  CHECK(firstError(withBus(R"({"name": "vehicle", "link": "sim:v", "messages": ["Comand"]})")) ==
        "vehicle.json: /buses/0/messages/0: no message 'Comand' in the DBC; did you mean 'Command'?");
  CHECK(firstError(withBus(R"({"name": "vehicle", "link": "sim:v", "bitrate": 12.5, "messages": "all"})")) ==
        "vehicle.json: /buses/0/bitrate: must be a whole number of bit/s between 10000 and 8000000");
  CHECK(firstError(withBus(GOOD_BUS, R"(, "lcm": "http://x")")) ==
        "vehicle.json: /lcm: LCM URL must start with udpm://, memq:// or file://");
  CHECK(firstError(withBus(GOOD_BUS, R"(, "lcm": "tcpq://127.0.0.1:7700")")) ==
        "vehicle.json: /lcm: tcpq:// is refused: its hub relays events from any client that reaches its port, "
        "so events could come from another host; use udpm://...?ttl=0");
  CHECK(firstError(withBus(GOOD_BUS, R"(, "fsm": "missing.json")")).find("/fsm: file '") != std::string::npos);
  CHECK(firstError(withBus(R"({"name": "vehicle", "link": "replay:nope.log", "messages": "all"})"))
            .find("/buses/0/link: replay file") != std::string::npos);
}

TEST_CASE("a message assigned to two buses is refused") {
  const std::string json = withBus(R"({"name": "a", "link": "sim:a", "messages": ["Status"]},
                                      {"name": "b", "link": "sim:b", "messages": ["Status"]})");
  CHECK(firstError(json) == "vehicle.json: /buses/1/messages/0: message 'Status' is already on bus 'a'; a message lives on one bus");
}

TEST_CASE("an unknown node gets a did-you-mean") {
  const std::string json = R"({"instance": "t", "node": "VCUU", "dbc": "small.dbc", "buses": [)" + std::string(GOOD_BUS) + "]}";
  CHECK(firstError(json) == "vehicle.json: /node: node 'VCUU' is not in the DBC's BU_ list; did you mean 'VCU'?");
}

TEST_CASE("a mistyped top-level key is refused with a suggestion") {
  CHECK(firstError(withBus(GOOD_BUS, R"(, "internalSignal": [])")) ==
        "vehicle.json: /internalSignal: unknown key 'internalSignal'; did you mean 'internalSignals'?");
}

TEST_CASE("internal signal errors: bad name, duplicate, range") {
  CHECK(firstError(withBus(GOOD_BUS, R"(, "internalSignals": [{"name": "a b"}])")) ==
        "vehicle.json: /internalSignals/0/name: 'a b' must be letters, digits, '_' and '.'");
  CHECK(firstError(withBus(GOOD_BUS, R"(, "internalSignals": [{"name": "a"}, {"name": "a"}])")) ==
        "vehicle.json: /internalSignals/1/name: internal signal 'a' is declared twice (first at /internalSignals/0)");
  CHECK(firstError(withBus(GOOD_BUS, R"(, "internalSignals": [{"name": "a", "min": 5, "max": 1}])")) ==
        "vehicle.json: /internalSignals/0/min: min is above max");
  CHECK(firstError(withBus(GOOD_BUS, R"(, "internalSignals": [{"name": "a", "values": {"x": "X"}}])")) ==
        "vehicle.json: /internalSignals/0/values/x: value keys must be integers");
}

TEST_CASE("a bad instance name and invalid JSON are refused") {
  CHECK(firstError(R"({"instance": "a/b", "node": "VCU", "dbc": "small.dbc", "buses": []})") ==
        "vehicle.json: /instance: 'a/b' must be 1-32 letters, digits, '-' or '_'");
  CHECK(firstError("{ \"instance\": }").find("vehicle.json:1:15: invalid JSON") == 0);
}

TEST_CASE("a DBC error is reported with the DBC's own location") {
  TempConfig file(withBus(GOOD_BUS));
  std::ofstream(file.dir() + "/small.dbc", std::ios::app) << "BO_ oops\n";
  const auto sut = loadVehicleConfig(file.path());
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().location.file == file.dir() + "/small.dbc");
  CHECK(sut.error().location.line > 0);
}

TEST_CASE("checkVehicleConfig lists every problem, not only the first") {
  TempConfig file(withBus(R"({"name": "v", "link": "x", "messages": ["Nope"]})", R"(, "lcm": "x")"));
  const auto sut = checkVehicleConfig(file.path());
  CHECK(sut.size() == 3);
}

TEST_CASE("link texts parse into kind and target") {
  CHECK(parseLink("socketcan:can0", ".")->kind == LinkKind::SocketCan);
  CHECK(parseLink("sim:vehicle", ".")->target == "vehicle");
  CHECK(parseLink("replay:logs/a.log", "/cfg")->target == "/cfg/logs/a.log");
  CHECK_FALSE(parseLink("socketcan:", ".").ok());
  CHECK_FALSE(parseLink("socketcan:averyveryverylongname", ".").ok());
  CHECK_FALSE(parseLink("sim:a b", ".").ok());
}
