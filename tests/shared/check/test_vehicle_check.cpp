// Issue 22: the whole-vehicle checks (check::checkVehicle), one small J1939 vehicle per case
// written by the test: a VCU (0x21), a battery BMS (0xF3) and an inverter INV (0xEF) on one
// bus. The clean vehicle gives no diagnostic; each case changes one thing.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "openvcu/check/vehicle_check.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

/// One BO_ of the fixture DBC (J1939PG, 8 bytes, one 8-bit signal per name).
struct MessageSpec {
  std::string name;
  std::uint32_t canId{};  ///< 29-bit
  std::string sender;
  std::uint32_t cycleMs{};  ///< 0: no GenMsgCycleTime
  std::vector<std::string> signalNames;
};

/// A vehicle folder in the temporary directory: hhea-like files, small enough to read.
class VehicleFolder {
 public:
  VehicleFolder() {
    static int counter = 0;
    m_dir = fs::temp_directory_path() /
            ("openvcu-vehicle-check-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    fs::create_directories(m_dir);
    messages = {{"BMS_Status", 0x18FF10F3, "BMS", 100, {"SOC", "Mode"}},
                {"BMS_Temps", 0x18FF11F3, "BMS", 1000, {"Temp"}},
                {"VCU_Command", 0x18FF2021, "VCU", 100, {"Enable"}},
                {"INV_Status", 0x18FF30EF, "INV", 50, {"Speed"}}};
    // The clean vehicle's FSM reads BMS Mode and the operator switch; its dashboard the rest.
    fsm = R"({"initialState": "Standby", "states": [
      {"name": "Standby", "transitions": [{"condition": {"internal.operator.Start": 1}, "nextState": "Running"}]},
      {"name": "Running", "entry": [{"signal": "VCU.VCU_Command.Enable", "value": 1}],
       "transitions": [{"condition": {"BMS.BMS_Status.Mode": 2, "internal.operator.Start": 0}, "nextState": "Standby"}]}]})";
    dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "BMS.BMS_Temps.Temp"},
                              {"key": "INV.INV_Status.Speed"}]})";
  }
  ~VehicleFolder() { fs::remove_all(m_dir); }
  VehicleFolder(const VehicleFolder&) = delete;
  VehicleFolder& operator=(const VehicleFolder&) = delete;

  std::vector<MessageSpec> messages;
  std::map<std::string, int> addresses{{"VCU", 33}, {"BMS", 243}, {"INV", 239}};
  std::uint32_t bitrate{250000};
  std::string fsm;
  std::string dashboard;   ///< empty: no dashboard.json
  std::string schedule;    ///< empty: the schedule's defaults
  std::string simulation;  ///< empty: no simulation file
  std::string diagnostics; ///< empty: no diagnostics.json
  std::string busMessages{"\"all\""};
  std::string internalSignals{R"([{"name": "operator.Start"}, {"name": "mode.Eco"}])"};

  /// Writes the files, loads the vehicle and runs the whole-vehicle checks.
  std::vector<Error> check() {
    writeFiles();
    auto vehicle = config::loadVehicleConfig(path());
    REQUIRE_MESSAGE(vehicle.ok(), vehicle.error().toString());
    auto catalog = config::buildCatalog(*vehicle);
    REQUIRE_MESSAGE(catalog.ok(), catalog.error().toString());
    return check::checkVehicle(*vehicle, *catalog);
  }

  void writeFiles() const {
    std::string dbc = "VERSION \"\"\n\nNS_ :\n\nBS_:\n\nBU_:";
    for (const auto& [node, address] : addresses) dbc += " " + node;
    dbc += "\n\n";
    for (const MessageSpec& message : messages) {
      dbc += "BO_ " + std::to_string(0x80000000u | message.canId) + " " + message.name + ": 8 " + message.sender + "\n";
      for (std::size_t i = 0; i < message.signalNames.size(); ++i) {
        dbc +=
            " SG_ " + message.signalNames[i] + " : " + std::to_string(8 * i) + "|8@1+ (1,0) [0|250] \"\" Vector__XXX\n";
      }
      dbc += "\n";
    }
    dbc +=
        "BA_DEF_ BU_ \"NmStationAddress\" INT 0 255;\nBA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n"
        "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\";\n"
        "BA_DEF_DEF_ \"NmStationAddress\" 254;\nBA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n"
        "BA_DEF_DEF_ \"VFrameFormat\" \"J1939PG\";\n";
    for (const auto& [node, address] : addresses) {
      dbc += "BA_ \"NmStationAddress\" BU_ " + node + " " + std::to_string(address) + ";\n";
    }
    for (const MessageSpec& message : messages) {
      if (message.cycleMs == 0) continue;
      dbc += "BA_ \"GenMsgCycleTime\" BO_ " + std::to_string(0x80000000u | message.canId) + " " +
             std::to_string(message.cycleMs) + ";\n";
    }
    write("vehicle.dbc", dbc);
    std::string vehicle = R"({"instance": "check", "node": "VCU", "dbc": "vehicle.dbc", "buses": [{"name": "can0",
      "link": "sim:can0", "bitrate": )" +
                          std::to_string(bitrate) + R"(, "messages": )" + busMessages + R"(}],
      "internalSignals": )" +
                          internalSignals + R"(, "fsm": "fsm.json")";
    if (!schedule.empty()) vehicle += R"(, "schedule": "schedule.json")";
    if (!simulation.empty()) vehicle += R"(, "simulation": "simulation.json")";
    if (!diagnostics.empty()) vehicle += R"(, "diagnostics": "diagnostics.json")";
    write("vehicle.json", vehicle + "}");
    write("fsm.json", fsm);
    if (!dashboard.empty()) write("dashboard.json", dashboard);
    if (!schedule.empty()) write("schedule.json", schedule);
    if (!simulation.empty()) write("simulation.json", simulation);
    if (!diagnostics.empty()) write("diagnostics.json", diagnostics);
  }

  [[nodiscard]] std::string path() const { return (m_dir / "vehicle.json").string(); }
  [[nodiscard]] std::string file(const std::string& name) const { return (m_dir / name).string(); }

 private:
  void write(const std::string& name, const std::string& text) const { std::ofstream(m_dir / name) << text; }
  fs::path m_dir;
};

std::vector<Error> withSeverity(const std::vector<Error>& diagnostics, Severity severity) {
  std::vector<Error> selected;
  std::copy_if(diagnostics.begin(), diagnostics.end(), std::back_inserter(selected),
               [&](const Error& e) { return e.severity == severity; });
  return selected;
}

std::string all(const std::vector<Error>& diagnostics) {
  std::string text;
  for (const Error& diagnostic : diagnostics) text += diagnostic.toString() + "\n";
  return text;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("a vehicle whose files fit together gives no whole-vehicle diagnostic (#22)") {
  VehicleFolder sut;
  const auto diagnostics = sut.check();
  CHECK_MESSAGE(diagnostics.empty(), all(diagnostics));
}

TEST_CASE("received signals no file reads are one warning per bus naming the unread messages (#22)") {
  VehicleFolder sut;
  sut.dashboard.clear();  // only the FSM reads: BMS Mode
  const auto diagnostics = sut.check();
  REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
  const Error& warning = diagnostics.front();
  CHECK(warning.severity == Severity::Warning);
  CHECK(warning.location.file == sut.path());
  CHECK(warning.location.jsonPath == "/buses/0/messages");
  CHECK(contains(warning.message, "3 of 4 received signals are read by no file"));
  CHECK(contains(warning.message, "2 of its 3 received messages have none read: BMS_Temps (line "));
  CHECK(contains(warning.message, "INV_Status (line "));
  CHECK_FALSE(contains(warning.message, "BMS_Status"));  // Mode is read
}

TEST_CASE("an FSM condition on a declared signal nobody writes is a warning at the condition's path (#22)") {
  VehicleFolder sut;
  sut.fsm = R"({"initialState": "Standby", "states": [
    {"name": "Standby", "transitions": [{"condition": {"internal.operator.Start": 1}, "nextState": "Running"}]},
    {"name": "Running", "entry": [{"signal": "VCU.VCU_Command.Enable", "value": 1}],
     "transitions": [{"condition": {"all": [{"BMS.BMS_Status.Mode": 2}, {"internal.operator.Start": 0}, {"internal.mode.Eco": 1}]}, "nextState": "Standby"}]}]})";
  const auto diagnostics = sut.check();
  REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
  const Error& warning = diagnostics.front();
  CHECK(warning.severity == Severity::Warning);
  CHECK(warning.location.file == sut.file("fsm.json"));
  CHECK(warning.location.jsonPath.starts_with("/states/1/transitions/0/condition"));
  CHECK(contains(warning.message, "internal.mode.Eco, which nobody writes"));
}

TEST_CASE("a signal an FSM action sets or an operator switch is not 'written by nobody' (#22)") {
  VehicleFolder sut;
  sut.fsm = R"({"initialState": "Standby", "states": [
    {"name": "Standby", "entry": [{"signal": "internal.mode.Eco", "value": 1}],
     "transitions": [{"condition": {"all": [{"internal.operator.Start": 1}, {"internal.mode.Eco": 1}]}, "nextState": "Running"}]},
    {"name": "Running", "entry": [{"signal": "VCU.VCU_Command.Enable", "value": 1}],
     "transitions": [{"condition": {"BMS.BMS_Status.Mode": 2, "internal.operator.Start": 0}, "nextState": "Standby"}]}]})";
  const auto diagnostics = sut.check();
  CHECK_MESSAGE(diagnostics.empty(), all(diagnostics));
}

TEST_CASE("an expected bus load above 70 % warns and above 100 % is an error, naming the heaviest message (#22)") {
  VehicleFolder sut;
  sut.bitrate = 10000;  // one 8-byte extended frame: 14.6 ms
  SUBCASE("the DBC cycles as written: about 60 %, no diagnostic") {
    const auto diagnostics = sut.check();
    CHECK_MESSAGE(diagnostics.empty(), all(diagnostics));
  }
  SUBCASE("the inverter every 30 ms: about 80 %, a warning") {
    sut.messages[3].cycleMs = 30;
    const auto diagnostics = sut.check();
    REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
    CHECK(diagnostics.front().severity == Severity::Warning);
    CHECK(diagnostics.front().location.jsonPath == "/buses/0");
    CHECK(contains(diagnostics.front().message, "bus 'can0': the cyclic frames expected on it take"));
    CHECK(contains(diagnostics.front().message, "more than 70.0 %"));
    CHECK(contains(diagnostics.front().message, "heaviest: INV_Status (INV) every 30 ms"));
  }
  SUBCASE("the inverter every 20 ms: about 104 %, an error") {
    sut.messages[3].cycleMs = 20;
    const auto diagnostics = sut.check();
    const auto errors = withSeverity(diagnostics, Severity::Error);
    REQUIRE_MESSAGE(errors.size() == 1, all(diagnostics));
    CHECK(contains(errors.front().message, "more than 100.0 %: they cannot all be sent"));
    CHECK(contains(errors.front().message, "VCU's schedule"));
  }
}

TEST_CASE("two nodes declaring one NmStationAddress are an error, sending with another's address a warning (#22)") {
  VehicleFolder sut;
  SUBCASE("the inverter's NmStationAddress is the battery's") {
    sut.addresses["INV"] = 243;
    const auto diagnostics = sut.check();
    REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
    CHECK(diagnostics.front().severity == Severity::Error);
    CHECK(
        contains(diagnostics.front().message, "source address 0xF3 (243) is used by 2 nodes: BMS (message BMS_Status"));
    CHECK(contains(diagnostics.front().message, "INV (NmStationAddress)"));
    CHECK(contains(diagnostics.front().message, "Two nodes declare it as their NmStationAddress"));
  }
  SUBCASE("a charger sends with the VCU's address") {
    sut.addresses["CHG"] = 229;
    sut.messages.push_back({"CHG_Status", 0x18FF4021, "CHG", 100, {"Current"}});
    sut.dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "BMS.BMS_Temps.Temp"},
                                  {"key": "INV.INV_Status.Speed"}, {"key": "CHG.CHG_Status.Current"}]})";
    const auto diagnostics = sut.check();
    REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));  // 0xE5, CHG's NmStationAddress, is its alone
    CHECK(diagnostics.front().severity == Severity::Warning);
    CHECK(
        contains(diagnostics.front().message, "source address 0x21 (33) is used by 2 nodes: VCU (message VCU_Command"));
    CHECK(contains(diagnostics.front().message, "CHG (message CHG_Status 0x18FF4021)"));
    CHECK(diagnostics.front().location.file == sut.file("vehicle.dbc"));
    CHECK(diagnostics.front().location.line > 0);
  }
}

TEST_CASE("identifiers that collide on a bus: a scheduled ID equal to another node's, and a priority-only twin (#22)") {
  VehicleFolder sut;
  SUBCASE("the schedule sends VCU_Command with the battery's source address: its ID is BMS_Status2's") {
    sut.messages.push_back({"BMS_Status2", 0x18FF20F3, "BMS", 0, {"Extra"}});
    sut.dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "BMS.BMS_Temps.Temp"},
                                  {"key": "INV.INV_Status.Speed"}, {"key": "BMS.BMS_Status2.Extra"}]})";
    sut.schedule = R"({"messages": {"VCU_Command": {"source": "0xF3"}}})";
    const auto errors = withSeverity(sut.check(), Severity::Error);
    REQUIRE(!errors.empty());
    const auto it = std::find_if(errors.begin(), errors.end(),
                                 [](const Error& e) { return contains(e.message, "goes out as 0x18FF20F3"); });
    REQUIRE_MESSAGE(it != errors.end(), all(errors));
    CHECK(it->location.file == sut.file("schedule.json"));
    CHECK(it->location.jsonPath == "/messages/VCU_Command");
    CHECK(contains(it->message, "the identifier of BMS_Status2 (sent by BMS)"));
  }
  SUBCASE("the inverter's message has the battery status' identifier on the same bus: an error") {
    sut.messages.push_back({"INV_Copy", 0x18FF10F3, "INV", 0, {"Copy"}});
    sut.dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "BMS.BMS_Temps.Temp"},
                                  {"key": "INV.INV_Status.Speed"}, {"key": "INV.INV_Copy.Copy"}]})";
    const auto errors = withSeverity(sut.check(), Severity::Error);  // and a warning: INV sends with 0xF3
    REQUIRE_MESSAGE(errors.size() == 1, all(errors));
    CHECK(contains(errors.front().message,
                   "INV_Copy (INV) has the identifier 0x18FF10F3 of BMS_Status (BMS): every such frame decodes as"));
    CHECK(errors.front().location.line > 0);
  }
  SUBCASE("two battery messages differ only by priority: a warning") {
    sut.messages.push_back({"BMS_Status_P3", 0x0CFF10F3, "BMS", 0, {"Other"}});
    sut.dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "BMS.BMS_Temps.Temp"},
                                  {"key": "INV.INV_Status.Speed"}, {"key": "BMS.BMS_Status_P3.Other"}]})";
    const auto diagnostics = sut.check();
    REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
    CHECK(diagnostics.front().severity == Severity::Warning);
    CHECK(contains(diagnostics.front().message, "BMS_Status (0x18FF10F3, BMS) and BMS_Status_P3 (0x0CFF10F3, BMS)"));
    CHECK(contains(diagnostics.front().message, "differ only by priority"));
    CHECK(diagnostics.front().location.line > 0);
  }
  SUBCASE("the inverter sends the battery's PGN with the battery's address: an error") {
    sut.messages.push_back({"INV_Echo", 0x0CFF10F3, "INV", 0, {"Other"}});
    sut.dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "BMS.BMS_Temps.Temp"},
                                  {"key": "INV.INV_Status.Speed"}, {"key": "INV.INV_Echo.Other"}]})";
    const auto errors = withSeverity(sut.check(), Severity::Error);
    REQUIRE_MESSAGE(errors.size() == 1, all(errors));
    CHECK(contains(errors.front().message, "BMS_Status (0x18FF10F3, BMS) and INV_Echo (0x0CFF10F3, INV)"));
    CHECK(contains(errors.front().message, "two nodes send frames no receiver can tell apart"));
  }
}

TEST_CASE("a simulation J1939-76 check on a message no configured bus carries is an error at its JSON path (#22)") {
  VehicleFolder sut;
  sut.busMessages = R"(["BMS_Status", "BMS_Temps", "VCU_Command"])";  // INV_Status on no bus
  sut.dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "BMS.BMS_Temps.Temp"}]})";
  sut.simulation = R"({"safety": [{"message": "INV_Status"}]})";
  const auto diagnostics = sut.check();
  REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
  CHECK(diagnostics.front().severity == Severity::Error);
  CHECK(diagnostics.front().location.file == sut.file("simulation.json"));
  CHECK(diagnostics.front().location.jsonPath == "/safety/0/message");
  CHECK(contains(diagnostics.front().message, "'INV_Status' is on no configured bus"));
}

TEST_CASE("a file that does not load is left out of the whole-vehicle checks with one note (#22)") {
  VehicleFolder sut;
  sut.schedule = R"({"messages": {"NoSuchMessage": {}}})";  // its loader's error: vcu check reports it
  const auto diagnostics = sut.check();
  REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
  CHECK(diagnostics.front().severity == Severity::Note);
  CHECK(diagnostics.front().location.file == sut.file("schedule.json"));
}

TEST_CASE("the shipped HHEA vehicle has no whole-vehicle error (#22)") {
  const std::string path = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
  auto vehicle = config::loadVehicleConfig(path);
  REQUIRE_MESSAGE(vehicle.ok(), vehicle.error().toString());
  auto catalog = config::buildCatalog(*vehicle);
  REQUIRE(catalog.ok());
  const auto diagnostics = check::checkVehicle(*vehicle, *catalog);
  MESSAGE(all(diagnostics));
  CHECK_MESSAGE(withSeverity(diagnostics, Severity::Error).empty(), all(diagnostics));
}

TEST_CASE("a DTC on a state the FSM does not have is an error at its JSON path (#24)") {
  VehicleFolder sut;
  sut.diagnostics = R"({"dtcs": [{"name": "run", "fsmState": "Runing", "spn": 520192, "fmi": 31}]})";
  const auto diagnostics = sut.check();
  REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
  CHECK(diagnostics.front().severity == Severity::Error);
  CHECK(diagnostics.front().location.file == sut.file("diagnostics.json"));
  CHECK(diagnostics.front().location.jsonPath == "/dtcs/0/fsmState");
  CHECK(contains(diagnostics.front().message, "has no state 'Runing'; did you mean 'Running'?"));
}

TEST_CASE("an FSM state raising a fault that no DTC maps is a warning at the state (#24)") {
  VehicleFolder sut;
  sut.fsm = R"({"initialState": "Standby", "states": [
    {"name": "Standby", "transitions": [{"condition": {"BMS.BMS_Status.Mode": 2}, "nextState": "Fault"},
                                        {"condition": {"internal.operator.Start": 1}, "nextState": "Hot"}]},
    {"name": "Fault", "entry": [{"raise": "bms_fault", "severity": "error", "text": "BMS fault"}]},
    {"name": "Hot", "entry": [{"raise": "hot", "severity": "warning", "text": "too hot"}]}]})";
  sut.diagnostics = R"({"dtcs": [{"name": "bms", "fsmState": "Fault", "spn": 520192, "fmi": 12, "lamps": ["red"]}]})";
  const auto warnings = withSeverity(sut.check(), Severity::Warning);
  std::vector<Error> unmapped;
  std::copy_if(warnings.begin(), warnings.end(), std::back_inserter(unmapped),
               [](const Error& e) { return contains(e.message, "no DTC"); });
  REQUIRE_MESSAGE(unmapped.size() == 1, all(warnings));
  CHECK(unmapped.front().location.file == sut.file("fsm.json"));
  CHECK(unmapped.front().location.jsonPath == "/states/2");
  CHECK(contains(unmapped.front().message, "state 'Hot' raises fault 'hot'"));
}

TEST_CASE("the shipped HHEA diagnostics map every FSM state that raises a fault (#24)") {
  const std::string path = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
  auto vehicle = config::loadVehicleConfig(path);
  REQUIRE_MESSAGE(vehicle.ok(), vehicle.error().toString());
  REQUIRE_FALSE(vehicle->diagnosticsFile.empty());
  auto catalog = config::buildCatalog(*vehicle);
  REQUIRE(catalog.ok());
  const auto diagnostics = check::checkVehicle(*vehicle, *catalog);
  for (const Error& diagnostic : diagnostics) {
    CHECK_MESSAGE(diagnostic.location.file != vehicle->diagnosticsFile, diagnostic.toString());
    CHECK_MESSAGE(!contains(diagnostic.message, "no DTC"), diagnostic.toString());
  }
}

TEST_CASE("a signal a DTC of diagnostics.json reads is not 'read by no file' (#24)") {
  VehicleFolder sut;
  sut.dashboard = R"({"items": [{"key": "BMS.BMS_Status.SOC"}, {"key": "INV.INV_Status.Speed"}]})";
  const auto withoutDtc = sut.check();
  REQUIRE_MESSAGE(withoutDtc.size() == 1, all(withoutDtc));  // BMS_Temps.Temp is read by no file
  CHECK(contains(withoutDtc.front().message, "BMS_Temps"));
  sut.diagnostics = R"({"dtcs": [{"name": "hot", "signal": "BMS.BMS_Temps.Temp", "activeWhen": {"gt": 90},
                                  "spn": 520192, "fmi": 0, "lamps": ["amber"]}]})";
  const auto withDtc = sut.check();
  CHECK_MESSAGE(withDtc.empty(), all(withDtc));
}

TEST_CASE("a diagnostics.json that accepts DTC clears from any node is a warning at its JSON path") {
  VehicleFolder sut;
  sut.diagnostics = R"({"dm3": "refuse", "dm11": "accept"})";
  const auto diagnostics = sut.check();
  REQUIRE_MESSAGE(diagnostics.size() == 1, all(diagnostics));
  CHECK(diagnostics.front().severity == Severity::Warning);
  CHECK(diagnostics.front().location.file == sut.file("diagnostics.json"));
  CHECK(diagnostics.front().location.jsonPath == "/dm11");
  CHECK(contains(diagnostics.front().message, "DM11 (clear active DTCs) is accepted from any node on the bus"));
}

TEST_CASE("a simulation wake signal the catalog does not have is an error naming the signal and path") {
  VehicleFolder sut;
  SUBCASE("a misspelt operator switch") {
    sut.simulation = R"({"model": "hhea", "wakeSignal": "internal.operator.Strat"})";
    const auto errors = withSeverity(sut.check(), Severity::Error);
    REQUIRE_MESSAGE(errors.size() == 1, all(errors));
    CHECK(errors.front().location.file == sut.file("simulation.json"));
    CHECK(errors.front().location.jsonPath == "/wakeSignal");
    CHECK(contains(errors.front().message,
                   "unknown signal 'internal.operator.Strat'; did you mean 'internal.operator.Start'?"));
  }
  SUBCASE("a signal of the catalog") {
    sut.simulation = R"({"model": "hhea", "wakeSignal": "internal.operator.Start"})";
    const auto errors = withSeverity(sut.check(), Severity::Error);
    CHECK_MESSAGE(errors.empty(), all(errors));
  }
}
