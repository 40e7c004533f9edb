// merge() and loadFiles(): the "combined DBC" of several files.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <string>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {

const std::string VEHICLE =
    "BU_: Vcu Battery\n"
    "BO_ 256 VcuStatus: 8 Vcu\n"
    " SG_ State : 0|4@1+ (1,0) [0|15] \"\" Battery\n"
    "BO_ 2566844926 BatteryStatus: 8 Battery\n"
    " SG_ Soc : 32|8@1+ (0.4,0) [0|100] \"%\" Vcu\n"
    "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n"
    "BA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n"
    "BA_ \"GenMsgCycleTime\" BO_ 2566844926 100;\n"
    "VAL_TABLE_ OnOff 1 \"On\" 0 \"Off\" ;\n";

const std::string CHARGER =
    "BU_: Vcu Charger\n"
    "BO_ 2566844926 BatteryStatus: 8 Battery\n"
    " SG_ Soc : 32|8@1+ (0.4,0) [0|100] \"%\" Vcu\n"
    "BO_ 2550588916 ChargerCommand: 8 Vcu\n"
    " SG_ MaxVoltage : 0|16@1+ (0.1,0) [0|6553.5] \"V\" Charger\n"
    "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n"
    "BA_ \"GenMsgCycleTime\" BO_ 2566844926 100;\n"
    "VAL_TABLE_ OnOff 1 \"On\" 0 \"Off\" ;\n";

Database parsedDatabase(const std::string& text, std::string_view name) {
  ParseOutput parsed = parse(text, name);
  INFO(describe(parsed));
  REQUIRE_FALSE(parsed.hasErrors());
  return std::move(parsed.database);
}

/// The vehicle database as the merge target, a copy of it as it was, and a merge of
/// "other.dbc" into it.
struct MergeIntoVehicle {
  Database sut = parsedDatabase(VEHICLE, "vehicle.dbc");
  const Database before = sut;

  Status mergeOther(const std::string& text) { return merge(sut, parsedDatabase(text, "other.dbc"), "other.dbc"); }
};

}  // namespace

TEST_CASE("merge adds the other file's messages and nodes and keeps identical definitions once") {
  Database sut = parsedDatabase(VEHICLE, "vehicle.dbc");
  const Database charger = parsedDatabase(CHARGER, "charger.dbc");

  const Status status = merge(sut, charger, "charger.dbc");

  REQUIRE(status.ok());
  CHECK(sut.messages.size() == 3);
  CHECK(sut.nodes.size() == 3);
  CHECK(sut.attributeDefinitions.size() == 1);
  CHECK(sut.valueTables.size() == 1);
  const Message* command = sut.findMessage(0x1806E5F4u, true);
  REQUIRE(command != nullptr);
  CHECK(command->name == "ChargerCommand");
  CHECK(sut.findMessage("BatteryStatus") == &sut.messages[1]);
  CHECK(sut.findNode("Charger") != nullptr);
}

TEST_CASE("merge of a database with itself changes nothing") {
  Database sut = parsedDatabase(VEHICLE, "vehicle.dbc");
  const Database copy = sut;

  REQUIRE(merge(sut, copy, "vehicle.dbc").ok());

  CHECK(sut == copy);
}

TEST_CASE("merge keeps identical environment variables, signal groups and relation attributes once") {
  Database sut = parsedDatabase(readFixture("grammar_all_statements.dbc"), "grammar_all_statements.dbc");
  REQUIRE(!sut.environmentVariables.empty());
  REQUIRE(!sut.signalGroups.empty());
  REQUIRE(!sut.relationAttributes.empty());
  const Database copy = sut;

  REQUIRE(merge(sut, copy, "again.dbc").ok());

  CHECK(sut.environmentVariables.size() == copy.environmentVariables.size());
  CHECK(sut.signalGroups.size() == copy.signalGroups.size());
  CHECK(sut.relationAttributes.size() == copy.relationAttributes.size());
  CHECK(sut == copy);
}

TEST_CASE_FIXTURE(MergeIntoVehicle,
                  "merge refuses a message with the same ID but another layout and leaves the target unchanged") {
  const Status status = mergeOther(
      "BU_: Vcu\n"
      "\n"
      "BO_ 256 VcuStatus: 8 Vcu\n"
      " SG_ State : 0|8@1+ (1,0) [0|255] \"\" Battery\n"
      "BO_ 999 Extra: 8 Vcu\n");

  REQUIRE_FALSE(status.ok());
  CHECK(status.error().location.file == "other.dbc");
  CHECK(status.error().location.line == 3);
  CHECK(status.error().toString().find("other.dbc:3: message 'VcuStatus' (ID 0x100) conflicts") == 0);
  CHECK(sut == before);
  CHECK(sut.findMessage("Extra") == nullptr);
}

TEST_CASE_FIXTURE(MergeIntoVehicle, "merge refuses a message name already used for another ID") {
  const Status status = mergeOther("BO_ 300 VcuStatus: 8 Vcu\n");

  REQUIRE_FALSE(status.ok());
  CHECK(status.error().message.find("already used for ID 0x100") != std::string::npos);
  CHECK(sut == before);
}

TEST_CASE_FIXTURE(MergeIntoVehicle,
                  "merge refuses an attribute defined with another type and leaves the target unchanged") {
  const Status status = mergeOther("BA_DEF_ BO_ \"GenMsgCycleTime\" FLOAT 0 65535;\n");

  REQUIRE_FALSE(status.ok());
  CHECK(status.error().location.file == "other.dbc");
  CHECK(status.error().location.line == 1);
  CHECK(sut == before);
}

TEST_CASE("merge refuses an ENUM attribute with another value list") {
  Database sut = parsedDatabase("BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\";\n",
                                "a.dbc");
  const Database other = parsedDatabase(
      "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"StandardCAN_FD\",\"ExtendedCAN_FD\",\"J1939PG\";\n",
      "b.dbc");

  const Status status = merge(sut, other, "b.dbc");

  CHECK_FALSE(status.ok());
}

TEST_CASE("loadFiles merges fixture files and reports a missing file with its path") {
  const std::string vehicle = (fixtureDir() / "multiplexing.dbc").string();
  const std::string j1939 = (fixtureDir() / "j1939_hhea_vcu.dbc").string();
  const std::string missing = (fixtureDir() / "does_not_exist.dbc").string();

  const Result<Database> sut = loadFiles({vehicle, j1939});
  const Result<Database> refused = loadFiles({vehicle, missing});

  REQUIRE(sut.ok());
  CHECK(sut->findMessage("Muxed") != nullptr);
  CHECK(sut->findMessage("S1_ES_PGN61427") != nullptr);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().location.file == missing);
}

TEST_CASE("loadFile refuses a file with errors and reports the first one") {
  const std::string path = (fixtureDir() / "does_not_exist.dbc").string();

  const Result<Database> sut = loadFile(path);

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message.find("cannot open") == 0);
}
