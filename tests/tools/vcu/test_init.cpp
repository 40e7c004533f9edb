// Issue 22: `vcu init DIR --dbc FILE... --node NAME`: the folder it writes for HHEA's DBC and
// for every J1939 DBC of the team kit's corpus (../shared/corpus, not copied into the
// repository) passes `vcu check` with 0 errors; it refuses to overwrite, names unknown
// nodes and DBC errors, and keeps the schedule under can-tx's bus-load limit.

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "openvcu/dbc/parser.hpp"
#include "skip.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;
namespace fs = std::filesystem;

namespace {

const std::string HHEA_DBC = OPENVCU_SOURCE_DIR "/config/hhea/hhea.dbc";
const fs::path CORPUS = OPENVCU_TEAM_KIT "/corpus/dbc";
const char* const WRITTEN[] = {"vehicle.json",   "schedule.json", "receive.json",   "fsm.json",
                               "dashboard.json", "gpio.json",     "simulation.json"};

/// An empty scratch folder path (not created).
fs::path freshFolder(const std::string& name) {
  const fs::path folder = scratchFolder() / "init" / name;
  fs::remove_all(folder);
  fs::create_directories(folder.parent_path());
  return folder;
}

nlohmann::json readJson(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false, true);
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

/// Every entry of a folder with its content (what "unchanged" means).
std::map<std::string, std::string> snapshot(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(folder))
    files[entry.path().filename().string()] = readText(entry.path());
  return files;
}

/// `vcu init` then `vcu check` on the result: both succeed, check reports 0 errors.
void initAndCheck(const fs::path& folder, const std::vector<std::string>& dbcs, const std::string& node) {
  std::vector<std::string> arguments{"init", folder.string(), "--node", node, "--dbc"};
  arguments.insert(arguments.end(), dbcs.begin(), dbcs.end());
  const RunResult init = runVcu(arguments);
  INFO("vcu init stderr: " << init.err);
  REQUIRE(init.exitCode == EXIT_OK);
  CHECK(contains(init.out, "vcu check --config " + (folder / "vehicle.json").string()));
  for (const char* name : WRITTEN) CHECK(fs::is_regular_file(folder / name));
  for (const auto& entry : fs::directory_iterator(folder))
    CHECK(entry.path().filename().string().rfind(".vcu-init", 0) != 0);
  const RunResult check = runVcu({"check", "--config", (folder / "vehicle.json").string()});
  INFO("vcu check stdout: " << check.out << "\nstderr: " << check.err);
  CHECK(check.exitCode == EXIT_OK);
  CHECK(contains(check.out, ", 0 errors, "));
}

/// The corpus rule for the VCU node: the node transmitting the most messages (the first in
/// BU_ on a tie); empty when the DBC declares no nodes (9 of the 10 J1939 files: the test
/// then adds a node VCU to BU_, as vcu init's refusal tells the user).
std::string busiestNode(const openvcu::dbc::Database& database) {
  std::string best;
  std::size_t bestCount = 0;
  for (const auto& node : database.nodes) {
    std::size_t count = 0;
    for (const auto& message : database.messages) {
      const auto senders = message.transmitters();
      if (!message.pseudo && std::find(senders.begin(), senders.end(), node.name) != senders.end()) ++count;
    }
    if (best.empty() || count > bestCount) {
      best = node.name;
      bestCount = count;
    }
  }
  return best;
}

}  // namespace

TEST_CASE("vcu init on hhea.dbc writes a folder that vcu check passes, with every VCU message scheduled (#22)") {
  const fs::path folder = freshFolder("hhea");
  initAndCheck(folder, {HHEA_DBC}, "Vehicle_Control_Unit");

  auto database = openvcu::dbc::loadFile(HHEA_DBC);
  REQUIRE(database);
  const nlohmann::json schedule = readJson(folder / "schedule.json");
  REQUIRE(schedule.is_object());
  std::size_t sent = 0;
  for (const auto& message : database->messages) {
    if (message.pseudo || message.transmitter != "Vehicle_Control_Unit") continue;
    if (message.name.rfind("SHM_", 0) == 0) {  // the J1939-76 headers go out with their SDMs
      CHECK_FALSE(schedule["messages"].contains(message.name));
      continue;
    }
    ++sent;
    CHECK(schedule["messages"].contains(message.name));
  }
  CHECK(schedule["messages"].size() == sent);
  // the DBC comments mark five SDMs (S1_ES_PGN61427 among them); PropA_C4 is "not J1939-76 protected"
  CHECK(schedule["messages"]["S1_ES_PGN61427"].contains("safety"));
  CHECK_FALSE(schedule["messages"]["PropA_C4_PGN61184"].contains("safety"));

  const nlohmann::json fsm = readJson(folder / "fsm.json");
  REQUIRE(fsm["states"].size() == 3);
  const nlohmann::json receive = readJson(folder / "receive.json");
  // 3 x GenMsgCycleTime (HVESSS1 every 100 ms), at least 100 ms (ST_MOT_1 every 10 ms)
  CHECK(receive["messages"]["HVESSS1_PGN61590"]["timeoutMs"] == 300);
  CHECK(receive["messages"]["ST_MOT_1"]["timeoutMs"] == 100);
  const nlohmann::json vehicle = readJson(folder / "vehicle.json");
  CHECK(vehicle["buses"][0]["bitrate"] == 500000);  // hhea.dbc: BA_ "Baudrate" 500000
  CHECK(vehicle["buses"][0]["link"] == "sim:vehicle");
  CHECK(readText(folder / "hhea.dbc") == readText(HHEA_DBC));
}

TEST_CASE("vcu init on every J1939 DBC of the corpus writes a folder that vcu check passes (#22)") {
  if (!fs::is_directory(CORPUS)) {
    OPENVCU_SKIP("skipped: " << CORPUS.string() << " not found (the team kit is not beside the repository)");
  }
  std::size_t j1939Files = 0;
  std::size_t initialised = 0;
  for (const auto& entry : fs::recursive_directory_iterator(CORPUS)) {
    if (entry.path().extension() != ".dbc") continue;
    auto database = openvcu::dbc::loadFile(entry.path().string());
    if (!database) continue;  // the corpus holds invalid DBC on purpose
    const auto protocol =
        database->attributeText(database->networkAttributes, "ProtocolType", openvcu::dbc::ObjectType::Network);
    if (!protocol || *protocol != "J1939") continue;
    ++j1939Files;
    const std::string path = entry.path().string();
    INFO(path);
    const std::string name = entry.path().parent_path().filename().string() + "_" + entry.path().stem().string();
    const std::string node = busiestNode(*database);
    if (node.empty()) {
      // no BU_ node to be the VCU: init refuses and writes nothing; then the user's fix it
      // names (the VCU added to BU_; it transmits nothing, listens to every message)
      const fs::path folder = freshFolder(name);
      const RunResult refused = runVcu({"init", folder.string(), "--dbc", path, "--node", "VCU"});
      CHECK(refused.exitCode == EXIT_INPUT_ERROR);
      CHECK(contains(refused.err, "declares no nodes"));
      CHECK_FALSE(fs::exists(folder));
      std::string text = readText(entry.path());
      const std::size_t at = text.find("\nBU_:");
      REQUIRE(at != std::string::npos);
      text.insert(at + 6, " VCU");
      initAndCheck(freshFolder(name + "_vcu"), {writeScratchFile("init_corpus_" + name + ".dbc", text)}, "VCU");
      ++initialised;
      continue;
    }
    initAndCheck(freshFolder(name), {path}, node);
    ++initialised;
  }
  MESSAGE(j1939Files << " J1939 DBC files, " << initialised << " brought up with vcu init");
  CHECK(j1939Files > 0);
}

TEST_CASE("vcu init refuses to overwrite without --force and leaves the folder unchanged (#22)") {
  const fs::path folder = freshFolder("existing");
  fs::create_directories(folder);
  { std::ofstream(folder / "fsm.json") << "{\"mine\": true}\n"; }
  const auto before = snapshot(folder);

  const RunResult refused = runVcu({"init", folder.string(), "--dbc", HHEA_DBC, "--node", "Vehicle_Control_Unit"});
  CHECK(refused.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(refused.err, "refusing to overwrite " + (folder / "fsm.json").string()));
  CHECK(snapshot(folder) == before);

  const RunResult forced =
      runVcu({"init", folder.string(), "--dbc", HHEA_DBC, "--node", "Vehicle_Control_Unit", "--force"});
  INFO(forced.err);
  CHECK(forced.exitCode == EXIT_OK);
  CHECK(readJson(folder / "fsm.json")["initialState"] == "Standby");
}

TEST_CASE("vcu init names an unknown node with a did-you-mean and the node list, and writes nothing (#22)") {
  const fs::path folder = freshFolder("unknown_node");
  const RunResult sut = runVcu({"init", folder.string(), "--dbc", HHEA_DBC, "--node", "Vehicle_Control_Uni"});
  CHECK(sut.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(sut.err, "node 'Vehicle_Control_Uni' is not in the DBC; did you mean 'Vehicle_Control_Unit'?"));
  CHECK(contains(sut.err, "(nodes: "));
  CHECK(contains(sut.err, "VIC"));
  CHECK_FALSE(fs::exists(folder));
}

TEST_CASE("vcu init refuses an instance name the stack cannot use and writes nothing (#22)") {
  const fs::path folder = freshFolder("bad_instance");
  const RunResult sut = runVcu(
      {"init", folder.string(), "--dbc", HHEA_DBC, "--node", "Vehicle_Control_Unit", "--instance", "my tractor"});
  CHECK(sut.exitCode == EXIT_USAGE);
  CHECK(contains(sut.err, "--instance 'my tractor' must be 1-32 letters, digits, '-' or '_'"));
  CHECK_FALSE(fs::exists(folder));
}

TEST_CASE("vcu init reports a DBC syntax error with its file and line and writes nothing (#22)") {
  const std::string broken = writeScratchFile("init_broken.dbc",
                                              "VERSION \"\"\n\nBU_: VCU\n\nBO_ 100 Status: 8 VCU\n"
                                              " SG_ Speed : 0|16@1+ (1,0 [0|100] \"\" VCU\n");
  const fs::path folder = freshFolder("broken");
  const RunResult sut = runVcu({"init", folder.string(), "--dbc", broken, "--node", "VCU"});
  CHECK(sut.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(sut.err, broken + ":6:"));
  CHECK_FALSE(fs::exists(folder));
}

TEST_CASE("vcu init lengthens the heaviest cycles of a DBC over can-tx's bus-load limit and comments them (#22)") {
  // 12 extended 8-byte frames every 1 ms at 250 kbit/s: far over 50 % of the bus
  std::string text = "VERSION \"\"\n\nBU_: VCU ECU\n\n";
  for (int i = 0; i < 12; ++i) {
    text += "BO_ " + std::to_string(0x98FF0021u + (static_cast<unsigned>(i) << 8)) + " Fast" + std::to_string(i) +
            ": 8 VCU\n SG_ Value : 0|16@1+ (1,0) [0|65535] \"\" ECU\n\n";
  }
  text += "BO_ 2566914850 Slow: 8 ECU\n SG_ Level : 0|8@1+ (1,0) [0|255] \"\" VCU\n\n";
  text += "BA_DEF_ \"Baudrate\" INT 0 1000000;\nBA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 3600000;\n";
  text += "BA_DEF_DEF_ \"Baudrate\" 500000;\nBA_DEF_DEF_ \"GenMsgCycleTime\" 0;\nBA_ \"Baudrate\" 250000;\n";
  for (int i = 0; i < 12; ++i) {
    text += "BA_ \"GenMsgCycleTime\" BO_ " + std::to_string(0x98FF0021u + (static_cast<unsigned>(i) << 8)) + " 1;\n";
  }
  text += "BA_ \"GenMsgCycleTime\" BO_ 2566914850 100;\n";
  const std::string dbc = writeScratchFile("init_heavy.dbc", text);
  const fs::path folder = freshFolder("heavy");
  initAndCheck(folder, {dbc}, "VCU");
  const nlohmann::json schedule = readJson(folder / "schedule.json");
  std::size_t lengthened = 0;
  for (const auto& [name, entry] : schedule["messages"].items()) {
    if (entry.contains("cycleMs")) {
      ++lengthened;
      CHECK(entry["cycleMs"].get<int>() > 1);
      CHECK(contains(entry["comment"].get<std::string>(), "lengthened"));
    }
  }
  CHECK(lengthened > 0);
  CHECK(readJson(folder / "vehicle.json")["buses"][0]["bitrate"] == 250000);
  CHECK(readJson(folder / "receive.json")["messages"]["Slow"]["timeoutMs"] == 300);
}

TEST_CASE("vcu init makes one bus per DBC file with its own bit rate and message list (#22)") {
  const std::string header = "VERSION \"\"\n\nBU_: VCU BMS INV\n\n";
  const std::string attributes =
      "BA_DEF_ \"Baudrate\" INT 0 1000000;\nBA_DEF_ \"BusType\" STRING;\n"
      "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 3600000;\nBA_DEF_DEF_ \"Baudrate\" 500000;\n"
      "BA_DEF_DEF_ \"BusType\" \"CAN\";\nBA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n";
  const std::string battery =
      writeScratchFile("init_battery.dbc",
                       header + "BO_ 2566914849 VcuToBms: 8 VCU\n SG_ Request : 0|8@1+ (1,0) [0|3] \"\" BMS\n\n" +
                           "BO_ 2566914850 BmsStatus: 8 BMS\n SG_ Soc : 0|8@1+ (0.5,0) [0|100] \"%\" VCU\n\n" +
                           attributes + "BA_ \"Baudrate\" 250000;\n" +
                           "BA_ \"GenMsgCycleTime\" BO_ 2566914849 100;\nBA_ \"GenMsgCycleTime\" BO_ 2566914850 50;\n");
  const std::string drive =
      writeScratchFile("init_drive.dbc",
                       header + "BO_ 2566915105 VcuToInv: 8 VCU\n SG_ Torque : 0|16@1+ (0.1,0) [0|500] \"Nm\" INV\n\n" +
                           "BO_ 2566915107 InvStatus: 8 INV\n SG_ Speed : 0|16@1+ (1,0) [0|8000] \"rpm\" VCU\n\n" +
                           attributes + "BA_ \"BusType\" \"CAN FD\";\n" +
                           "BA_ \"GenMsgCycleTime\" BO_ 2566915105 10;\nBA_ \"GenMsgCycleTime\" BO_ 2566915107 10;\n");
  const fs::path folder = freshFolder("two_buses");
  initAndCheck(folder, {battery, drive}, "VCU");
  const nlohmann::json buses = readJson(folder / "vehicle.json")["buses"];
  REQUIRE(buses.size() == 2);
  CHECK(buses[0]["name"] == "init_battery");
  CHECK(buses[0]["bitrate"] == 250000);
  CHECK(buses[0]["messages"] == nlohmann::json::array({"VcuToBms", "BmsStatus"}));
  CHECK(buses[1]["name"] == "init_drive");
  CHECK(buses[1]["link"] == "sim:init_drive");
  CHECK(buses[1]["fd"] == true);
  CHECK(buses[1]["messages"] == nlohmann::json::array({"VcuToInv", "InvStatus"}));
  CHECK(fs::is_regular_file(folder / "init_battery.dbc"));
  CHECK(fs::is_regular_file(folder / "init_drive.dbc"));
  const nlohmann::json fsm = readJson(folder / "fsm.json");
  CHECK(fsm["states"][0]["transitions"][1]["condition"]["any"].size() == 2);  // a timeout per received message
}
