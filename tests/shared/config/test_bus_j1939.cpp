// Issue #24: a bus' "j1939" object in vehicle.json (this VCU's NAME, preferred address,
// address range) and every refusal with its JSON path.
#include <doctest/doctest.h>

#include <fstream>
#include <string>

#include "config_fixture.hpp"
#include "openvcu/config/vehicle.hpp"

using namespace openvcu;
using namespace openvcu::config;
using openvcu::test::TempConfig;

namespace {

constexpr auto GOOD_NAME =
    R"({"identityNumber": 1, "manufacturerCode": 0, "function": 128, "vehicleSystem": 1, "industryGroup": 3,
        "arbitraryAddressCapable": true})";
constexpr std::uint64_t GOOD_NAME_VALUE = 0xB002800000000001u;

std::string withJ1939(const std::string& j1939) {
  return R"({"instance": "t", "node": "VCU", "dbc": "small.dbc", "buses": [
            {"name": "vehicle", "link": "sim:vehicle", "messages": "all", "j1939": )" +
         j1939 + "}]}";
}

std::string withName(const std::string& name) {
  return withJ1939(R"({"name": )" + name + R"(, "preferredAddress": 33})");
}

/// Appends NmStationAddress 33 for the node VCU to the copied small.dbc.
void giveVcuAnAddress(const TempConfig& file) {
  std::ofstream(file.dir() + "/small.dbc", std::ios::app) << "BA_DEF_ BU_  \"NmStationAddress\" INT 0 255;\n"
                                                             "BA_DEF_DEF_  \"NmStationAddress\" 254;\n"
                                                             "BA_ \"NmStationAddress\" BU_ VCU 33;\n";
}

std::string firstError(const std::string& json) {
  TempConfig file(json);
  const auto result = loadVehicleConfig(file.path());
  if (result.ok()) return "loaded";
  const std::string text = result.error().toString();
  const auto at = text.find("vehicle.json");
  return text.substr(at == std::string::npos ? 0 : at);
}

}  // namespace

TEST_CASE("#24 a bus' j1939 object loads the NAME, the preferred address and the range") {
  TempConfig file(withJ1939(R"({"name": {"identityNumber": 1234, "manufacturerCode": 2047, "ecuInstance": 7,
                                         "functionInstance": 31, "function": 255, "vehicleSystem": 127,
                                         "vehicleSystemInstance": 15, "industryGroup": 7,
                                         "arbitraryAddressCapable": false, "comment": "all at their maximum"},
                                "preferredAddress": 253, "addressRange": [0, 253], "claim": false,
                                "comment": "edges"})"));

  const auto sut = loadVehicleConfig(file.path());

  REQUIRE_MESSAGE(sut.ok(), (sut.ok() ? "" : sut.error().toString()));
  REQUIRE(sut->buses[0].j1939);
  const BusJ1939& j1939 = *sut->buses[0].j1939;
  CHECK(j1939.name.toValue() == 0x7FFEFFFFFFE004D2u);  // all set but AAC and reserved; identity 1234
  CHECK(j1939.name.fits());
  CHECK(j1939.preferredAddress == 253);
  CHECK(j1939.rangeFirst == 0);
  CHECK(j1939.rangeLast == 253);
  CHECK_FALSE(j1939.claim);
}

TEST_CASE("#24 j1939 defaults: claim on, range 128..247, instances 0, address from NmStationAddress") {
  TempConfig file(withJ1939(std::string(R"({"name": )") + GOOD_NAME + "}"));
  giveVcuAnAddress(file);

  const auto sut = loadVehicleConfig(file.path());

  REQUIRE_MESSAGE(sut.ok(), (sut.ok() ? "" : sut.error().toString()));
  REQUIRE(sut->buses[0].j1939);
  const j1939::AddressClaimerConfig claimer = sut->buses[0].j1939->claimerConfig();
  CHECK(claimer.name.toValue() == GOOD_NAME_VALUE);
  CHECK(claimer.preferredAddress == 33);
  CHECK(claimer.rangeFirst == 128);
  CHECK(claimer.rangeLast == 247);
  CHECK(sut->buses[0].j1939->claim);
}

TEST_CASE("#24 a bus without a j1939 object has none") {
  TempConfig file(R"({"instance": "t", "node": "VCU", "dbc": "small.dbc",
                      "buses": [{"name": "vehicle", "link": "sim:vehicle", "messages": "all"}]})");
  const auto sut = loadVehicleConfig(file.path());
  REQUIRE(sut.ok());
  CHECK_FALSE(sut->buses[0].j1939);
}

TEST_CASE("#24 the HHEA vehicle bus claims 0x21 with its construction-equipment NAME") {
  const auto sut = loadVehicleConfig(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json");
  REQUIRE_MESSAGE(sut.ok(), (sut.ok() ? "" : sut.error().toString()));
  const BusConfig* bus = sut->findBus("vehicle");
  REQUIRE(bus);
  REQUIRE(bus->j1939);
  CHECK(bus->j1939->preferredAddress == 0x21);  // the DBC's NmStationAddress
  CHECK(bus->j1939->name.industryGroup == 3);
  CHECK_FALSE(bus->j1939->name.arbitraryAddressCapable);  // a fixed address: it sends J1939-76 pairs
  CHECK(bus->j1939->claim);
}

TEST_CASE("#24 NAME fields beyond their width are refused with the path and the width") {
  CHECK(firstError(withName(R"({"identityNumber": 2097152, "manufacturerCode": 0, "function": 128, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true})")) ==
        "vehicle.json: /buses/0/j1939/name/identityNumber: must be a whole number 0..2097151 (21 bits)");
  CHECK(
      firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 2048, "function": 128, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true})")) ==
      "vehicle.json: /buses/0/j1939/name/manufacturerCode: must be a whole number 0..2047 (11 bits, assigned by SAE)");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 128, "vehicleSystem": 1,
                                "industryGroup": 8, "arbitraryAddressCapable": true})")) ==
        "vehicle.json: /buses/0/j1939/name/industryGroup: must be a whole number 0..7 (3 bits)");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 128, "vehicleSystem": 128,
                                "industryGroup": 3, "arbitraryAddressCapable": true})")) ==
        "vehicle.json: /buses/0/j1939/name/vehicleSystem: must be a whole number 0..127 (7 bits)");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 12.5, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true})")) ==
        "vehicle.json: /buses/0/j1939/name/function: must be a whole number 0..255 (8 bits)");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 1, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true, "ecuInstance": 8})")) ==
        "vehicle.json: /buses/0/j1939/name/ecuInstance: must be a whole number 0..7 (3 bits)");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 1, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true, "functionInstance": 32})")) ==
        "vehicle.json: /buses/0/j1939/name/functionInstance: must be a whole number 0..31 (5 bits)");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 1, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true, "vehicleSystemInstance": -1})")) ==
        "vehicle.json: /buses/0/j1939/name/vehicleSystemInstance: must be a whole number 0..15 (4 bits)");
}

TEST_CASE("#24 a NAME missing a required field or with a wrong type is refused") {
  CHECK(firstError(withName(R"({"manufacturerCode": 0, "function": 1, "vehicleSystem": 1, "industryGroup": 3,
                                "arbitraryAddressCapable": true})")) ==
        "vehicle.json: /buses/0/j1939/name/identityNumber: missing (required)");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 1, "vehicleSystem": 1,
                                "industryGroup": 3})")) ==
        "vehicle.json: /buses/0/j1939/name/arbitraryAddressCapable: missing (required)");
  CHECK(firstError(withName(R"({"identityNumber": "1", "manufacturerCode": 0, "function": 1, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true})")) ==
        "vehicle.json: /buses/0/j1939/name/identityNumber: must be a number, not a string");
  CHECK(firstError(withName("[]")) == "vehicle.json: /buses/0/j1939/name: must be an object, not an array");
  CHECK(firstError(withJ1939(R"({"preferredAddress": 33})")) ==
        "vehicle.json: /buses/0/j1939/name: missing (required)");
}

TEST_CASE("#24 unknown keys in the j1939 object and its NAME are refused with a suggestion") {
  CHECK(firstError(withJ1939(std::string(R"({"name": )") + GOOD_NAME + R"(, "prefferedAddress": 33})")) ==
        "vehicle.json: /buses/0/j1939/prefferedAddress: unknown key 'prefferedAddress'; did you mean "
        "'preferredAddress'?");
  CHECK(firstError(withName(R"({"identityNumber": 1, "manufacturerCode": 0, "function": 1, "vehicleSystem": 1,
                                "industryGroup": 3, "arbitraryAddressCapable": true, "ecuInstanse": 1})")) ==
        "vehicle.json: /buses/0/j1939/name/ecuInstanse: unknown key 'ecuInstanse'; did you mean 'ecuInstance'?");
  CHECK(firstError(withJ1939("true")) == "vehicle.json: /buses/0/j1939: must be an object, not a boolean");
}

TEST_CASE("#24 preferred address and address range outside 0..253 or reversed are refused") {
  const std::string name = std::string(R"({"name": )") + GOOD_NAME;
  CHECK(firstError(withJ1939(name + R"(, "preferredAddress": 254})")) ==
        "vehicle.json: /buses/0/j1939/preferredAddress: must be a whole number 0..253 (254 is the null address, 255 "
        "global)");
  CHECK(firstError(withJ1939(name + R"(, "preferredAddress": 33, "addressRange": [200, 100]})")) ==
        "vehicle.json: /buses/0/j1939/addressRange: the first address 200 is above the last 100");
  CHECK(firstError(withJ1939(name + R"(, "preferredAddress": 33, "addressRange": [128, 255]})")) ==
        "vehicle.json: /buses/0/j1939/addressRange/1: must be a whole number 0..253 (254 is the null address, 255 "
        "global)");
  CHECK(firstError(withJ1939(name + R"(, "preferredAddress": 33, "addressRange": [128]})")) ==
        "vehicle.json: /buses/0/j1939/addressRange: must be [first, last], two addresses 0..253");
  CHECK(firstError(withJ1939(name + R"(, "preferredAddress": 33, "claim": "yes"})")) ==
        "vehicle.json: /buses/0/j1939/claim: must be true or false, not a string");
}

TEST_CASE("#24 without preferredAddress a node lacking NmStationAddress is refused") {
  CHECK(firstError(withJ1939(std::string(R"({"name": )") + GOOD_NAME + "}")) ==
        "vehicle.json: /buses/0/j1939/preferredAddress: missing, and this VCU's DBC node has no NmStationAddress to "
        "default to; give 0..253");
}

TEST_CASE("#24 an address range for a NAME that never moves is a warning, not an error") {
  TempConfig file(withJ1939(R"({"name": {"identityNumber": 1, "manufacturerCode": 0, "function": 1,
                                         "vehicleSystem": 1, "industryGroup": 3, "arbitraryAddressCapable": false},
                                "preferredAddress": 33, "addressRange": [128, 130]})"));
  std::vector<Error> warnings;

  const auto sut = loadVehicleConfig(file.path(), &warnings);

  REQUIRE(sut.ok());
  REQUIRE(sut->buses[0].j1939);
  bool warned = false;
  for (const Error& warning : warnings) {
    if (warning.location.jsonPath == "/buses/0/j1939/addressRange") warned = true;
  }
  CHECK(warned);
}
