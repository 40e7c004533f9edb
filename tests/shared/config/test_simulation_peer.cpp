// Issue 24: simulation.json's "j1939Peer" (simulation_peer.hpp) on config/hhea's vehicle: the
// test file's peer loads with its steps in time order; each kind of mistake is refused with
// its JSON path.

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "openvcu/config/simulation.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
const std::string GENERIC = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/ecu-sim/vehicle.json";
const std::string NAME = R"({"identityNumber": 7, "manufacturerCode": 0, "function": 128, "vehicleSystem": 1,
                             "industryGroup": 3, "arbitraryAddressCapable": false})";

Result<config::SimConfig> loadText(const std::string& text, const std::string& vehiclePath = HHEA) {
  auto vehicle = config::loadVehicleConfig(vehiclePath);
  REQUIRE_MESSAGE(vehicle, (vehicle ? "" : vehicle.error().toString()));
  const fs::path file = fs::temp_directory_path() / ("openvcu-sim-peer-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << text;
  auto result = config::loadSimConfig(file.string(), *vehicle);
  fs::remove(file);
  return result;
}

/// A generic-model file with this "j1939Peer" object.
std::string withPeer(const std::string& peer) {
  return R"({"model": "generic", "j1939Peer": )" + peer + "}";
}

std::string firstError(const std::string& text, const std::string& vehiclePath = HHEA) {
  const auto result = loadText(text, vehiclePath);
  return result ? "ok" : result.error().location.jsonPath + ": " + result.error().message;
}

}  // namespace

TEST_CASE("#24 the test file's j1939Peer loads: bus, address, NAME, the VCU's NAME and the script in time order") {
  auto vehicle = config::loadVehicleConfig(HHEA);
  REQUIRE(vehicle);
  const auto result =
      config::loadSimConfig(std::string(OPENVCU_SOURCE_DIR) + "/tests/data/j1939-peer/simulation.json", *vehicle);
  REQUIRE_MESSAGE(result, (result ? "" : result.error().toString()));
  REQUIRE(result->peer);
  const config::SimPeerConfig& peer = *result->peer;
  CHECK(peer.bus == "vehicle");
  CHECK(peer.busIndex == 0);
  CHECK(peer.address == 249);
  CHECK(peer.name.toValue() == 0x3002800000000007u);
  CHECK(peer.vcuName.toValue() == 0x3002800000000001u);  // config/hhea: a fixed address
  REQUIRE(peer.script.size() == 6);
  CHECK(peer.script[4].kind == config::SimPeerStep::Kind::Claim);
  CHECK(peer.script[4].address == 0x21);
  CHECK(peer.script[4].atNs == 3'000'000'000);
  CHECK(peer.script[5].kind == config::SimPeerStep::Kind::Request);
  CHECK(peer.script[5].pgn == 65226);
  CHECK(peer.script[5].toVcu);
  CHECK(peer.requestedPgns == std::vector<std::uint32_t>{65226, 65242, 64965, 65227});
}

TEST_CASE("#24 script steps are sorted by atMs and \"to\" takes an address") {
  const auto result = loadText(withPeer(R"({"bus": "vehicle", "address": 250, "name": )" + NAME + R"(,
      "script": [{"atMs": 900, "request": 65259, "to": 255}, {"atMs": 100, "claim": 34}]})"));
  REQUIRE_MESSAGE(result, (result ? "" : result.error().toString()));
  REQUIRE(result->peer->script.size() == 2);
  CHECK(result->peer->script[0].kind == config::SimPeerStep::Kind::Claim);
  CHECK(result->peer->script[1].to == 255);
  CHECK_FALSE(result->peer->script[1].toVcu);
  CHECK_FALSE(loadText(R"({"model": "generic"})")->peer);
}

TEST_CASE("#24 each kind of mistake in j1939Peer is refused with its JSON path") {
  const std::string head = R"({"bus": "vehicle", "address": 249, "name": )" + NAME;
  CHECK(firstError(withPeer(R"({"bus": "chassis", "address": 249, "name": )" + NAME + "}")) ==
        "/j1939Peer/bus: no bus 'chassis' in the vehicle");
  CHECK(firstError(withPeer(head + "}"), GENERIC).starts_with("/j1939Peer/bus: bus 'vehicle' has no \"j1939\" object"));
  CHECK(firstError(withPeer(R"({"bus": "vehicle", "address": 254, "name": )" + NAME + "}"))
            .starts_with("/j1939Peer/address: must be a whole number 0..253"));
  CHECK(firstError(withPeer(head + R"(, "script": [{"atMs": 1, "claim": 3, "request": 65226}]})")) ==
        "/j1939Peer/script/0: needs exactly one of \"claim\" (an address) and \"request\" (a PGN)");
  CHECK(firstError(withPeer(head + R"(, "script": [{"atMs": 1, "request": 65226, "to": "bms"}]})")) ==
        "/j1939Peer/script/0/to: expected \"vcu\" or an address 0..255");
  CHECK(firstError(withPeer(head + R"(, "script": [{"atMs": 1, "claim": 3, "to": 5}]})")) ==
        "/j1939Peer/script/0/to: only a \"request\" has a destination");
  CHECK(firstError(withPeer(head + R"(, "script": [{"atMs": 1.5, "claim": 3}]})"))
            .starts_with("/j1939Peer/script/0/atMs: must be a whole number"));
  CHECK(firstError(withPeer(head + R"(, "script": [{"atMs": 1, "request": 262144}]})"))
            .starts_with("/j1939Peer/script/0/request: must be a whole number 0..262143"));
  CHECK(firstError(withPeer(head + R"(, "extra": 1})")).starts_with("/j1939Peer/extra"));
  CHECK(firstError(withPeer(R"({"bus": "vehicle", "address": 249, "name": {"identityNumber": 1, "manufacturerCode": 0,
      "function": 128, "vehicleSystem": 1, "industryGroup": 3, "arbitraryAddressCapable": false}})")) ==
        "/j1939Peer/name: is the VCU's own NAME on bus 'vehicle'");
}
