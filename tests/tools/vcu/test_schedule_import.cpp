// `vcu schedule import` (the sheet -> schedule JSON conversion, called on text) and the
// `vcu schedule` commands through the CLI entry. The runtime commands are only run as far
// as their local refusals: nothing here opens LCM (the test stack's URL is memq:// anyway).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <optional>

#include "diagnostics.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/dbc/parser.hpp"
#include "openvcu/schedule/schedule_config.hpp"
#include "openvcu/schedule/schedule_import.hpp"
#include "openvcu/signals/catalog.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;
using openvcu::Error;
using openvcu::Severity;
using openvcu::schedule::ImportOptions;
using openvcu::schedule::importScheduleCsv;
using Json = nlohmann::ordered_json;

namespace {

constexpr const char* SHEET_NAME = "sched.csv";
constexpr const char* HEADER = "NodeName,SheetName,UniqueID,Message,Signal,DeltaTime,IsSHM,CycleTime,Value\n";
constexpr const char* THIS_NODE = "Vehicle_Control_Unit";
constexpr const char* COLUMN_LIST = "NodeName,SheetName,UniqueID,Message,Signal,DeltaTime,IsSHM,CycleTime,Value";

/// The schedule for data/schedule/sheet.csv, in the order the import must write it.
constexpr const char* SHEET_SCHEDULE = R"({
  "include": ["S1_ES_PGN61427", "HVESSC1_PGN6912", "HC1_Demands"],
  "messages": {
    "S1_ES_PGN61427": {"cycleMs": 20, "group": "Battery",
                       "values": {"ShutDown_Clearance": 3, "Control_Es_Relay": 3, "Service_Mode_Request": 3,
                                  "Terminal_Voltage_Actual": 2047.5},
                       "safety": {"deltaUs": 292}},
    "HVESSC1_PGN6912": {"cycleMs": 100, "group": "Battery",
                        "values": {"HS_HiUBusCnctCmd": 3, "HS_PwrDwnCmd": 3, "HS_OperConsent": 1},
                        "safety": {"deltaUs": 567}},
    "HC1_Demands": {"cycleMs": 10, "group": "Inverter", "values": {"ControlWord": 6, "Torque_Request": -12.5}}
  },
  "groups": {"Battery": {"signal": "internal.tx.Battery"}, "Inverter": {"signal": "internal.tx.Inverter"}}
})";

const openvcu::dbc::Database& testDatabase() {
  static const openvcu::dbc::Database database = [] {
    auto loadResult = openvcu::dbc::loadFile(dataPath("schedule/schedule.dbc"));
    REQUIRE(loadResult);
    return std::move(*loadResult);
  }();
  return database;
}

/// A catalog holding only internal.tx.keepAlive, the key HHEA's battery group switches on.
openvcu::signals::Catalog keepAliveCatalog() {
  openvcu::signals::SignalInfo keepAlive;
  keepAlive.key = "internal.tx.keepAlive";
  keepAlive.kind = openvcu::signals::SignalKind::Internal;
  auto catalogResult = openvcu::signals::Catalog::create({keepAlive});
  REQUIRE(catalogResult);
  return std::move(*catalogResult);
}

std::string readText(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  REQUIRE(file.good());
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

struct Imported {
  std::optional<Json> schedule;
  std::vector<Error> diagnostics;

  /// The diagnostics of one severity as vcu prints them ("sched.csv:3: error: ...").
  [[nodiscard]] std::vector<std::string> lines(Severity severity) const {
    std::vector<std::string> out;
    for (const Error& diagnostic : diagnostics) {
      if (diagnostic.severity == severity) out.push_back(openvcu::cli::formatDiagnostic(diagnostic));
    }
    return out;
  }
  [[nodiscard]] std::vector<std::string> errors() const { return lines(Severity::Error); }
  [[nodiscard]] std::vector<std::string> warnings() const { return lines(Severity::Warning); }
  [[nodiscard]] std::vector<std::string> notes() const { return lines(Severity::Note); }
};

Imported importSheet(std::string_view text, const ImportOptions& options = {}) {
  Imported imported;
  auto importResult = importScheduleCsv(text, SHEET_NAME, testDatabase(), options, &imported.diagnostics);
  if (importResult) {
    imported.schedule = std::move(*importResult);
  } else {
    REQUIRE_FALSE(imported.errors().empty());
    CHECK(openvcu::cli::formatDiagnostic(importResult.error()) == imported.errors().front());
  }
  return imported;
}

/// One S1_ES_PGN61427 row that is fine on its own; tests append the rows they examine.
std::string sheetWith(std::string_view rows) {
  return std::string(HEADER) + "Battery,shm,61427,S1_ES_PGN61427,Control_Es_Relay,0.292,1,20,3\n" + std::string(rows);
}

/// A scratch folder of its own, emptied.
std::filesystem::path scratchFolder(std::string_view name) {
  const std::filesystem::path folder = openvcu::cli::test::scratchFolder() / name;
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

std::vector<std::string> folderEntries(const std::filesystem::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

// ---- conversion --------------------------------------------------------------------------------

TEST_CASE("a realistic sheet becomes the schedule: include, cycles, values, groups and safety, in sheet order") {
  const Imported sut = importSheet(readText(dataPath("schedule/sheet.csv")));

  REQUIRE(sut.schedule);
  CHECK(sut.schedule->dump(2) == Json::parse(SHEET_SCHEDULE).dump(2));
  CHECK(sut.errors().empty());
  CHECK(sut.warnings().empty());
}

TEST_CASE("an SHM row's DeltaTime of 0.292 ms is kept as 292 us, not truncated to whole ms like the original") {
  const Imported sut = importSheet(sheetWith(""));

  REQUIRE(sut.schedule);
  CHECK((*sut.schedule)["messages"]["S1_ES_PGN61427"]["safety"]["deltaUs"] == 292);
}

TEST_CASE("every NodeName becomes a send group on internal.tx.<NodeName>, with a note to declare the signals") {
  const Imported sut =
      importSheet(sheetWith(",,,HC1_Demands,ControlWord,,,10,6\n"
                            "Inverter,,,HVESSC1_PGN6912,HS_OperConsent,,,100,1\n"));

  REQUIRE(sut.schedule);
  CHECK((*sut.schedule)["messages"]["S1_ES_PGN61427"]["group"] == "Battery");
  CHECK_FALSE((*sut.schedule)["messages"]["HC1_Demands"].contains("group"));  // no NodeName: always sent
  CHECK((*sut.schedule)["groups"].dump() ==
        R"({"Battery":{"signal":"internal.tx.Battery"},"Inverter":{"signal":"internal.tx.Inverter"}})");
  CHECK(sut.notes() ==
        std::vector<std::string>{
            "sched.csv: note: the send groups switch on internal signals that vehicle.json must declare: "
            "internal.tx.Battery, internal.tx.Inverter; add \"internalSignals\": [{\"name\": \"tx.Battery\"}, "
            "{\"name\": \"tx.Inverter\"}] (initial value 0: the group is off until set), or map a node to an "
            "existing key with --group-signal NODE=KEY"});
}

TEST_CASE("--group-signal maps a node to an existing key, and the note names only the keys the catalog lacks") {
  const openvcu::signals::Catalog catalog = keepAliveCatalog();
  ImportOptions options;
  options.catalog = &catalog;
  options.groupSignals = {{"Battery", "internal.tx.keepAlive"}};

  const Imported sut = importSheet(sheetWith("Inverter,,,HC1_Demands,ControlWord,,,10,6\n"), options);

  REQUIRE(sut.schedule);
  CHECK((*sut.schedule)["groups"]["Battery"]["signal"] == "internal.tx.keepAlive");
  CHECK((*sut.schedule)["groups"]["Inverter"]["signal"] == "internal.tx.Inverter");
  REQUIRE(sut.notes().size() == 1);
  CHECK(contains(sut.notes().front(), "must declare: internal.tx.Inverter; add"));
  CHECK_FALSE(contains(sut.notes().front(), "Battery"));
}

TEST_CASE("a --group-signal key the catalog does not hold is an error with a suggestion") {
  const openvcu::signals::Catalog catalog = keepAliveCatalog();
  ImportOptions options;
  options.catalog = &catalog;
  options.groupSignals = {{"Battery", "internal.tx.keepalive"}};

  const Imported sut = importSheet(sheetWith(""), options);

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() == std::vector<std::string>{"vcu: error: --group-signal Battery=internal.tx.keepalive: unknown "
                                                 "signal 'internal.tx.keepalive' (did you mean "
                                                 "'internal.tx.keepAlive'?)"});
}

TEST_CASE("quoted fields may hold separators, doubled quotes and line breaks, line numbers still count") {
  const Imported sut =
      importSheet(std::string(HEADER) +
                  "\"Battery\",\"the \"\"main\"\", shm\nsheet\",,\"S1_ES_PGN61427\",\"Control_Es_Relay\","
                  "0.292,1,20,\"3\"\n"
                  ",,,HC1_Demands,ControlWord,,,10,abc\n");

  CHECK(sut.errors() ==
        std::vector<std::string>{"sched.csv:4: error: Value 'abc' of signal 'ControlWord' is not a number"});
  const Imported good = importSheet(std::string(HEADER) +
                                    "\"Battery\",\"the \"\"main\"\", shm sheet\",,\"S1_ES_PGN61427\",\"Control_Es_"
                                    "Relay\",0.292,1,20,\"3\"\n");
  REQUIRE(good.schedule);
  CHECK((*good.schedule)["messages"]["S1_ES_PGN61427"]["values"]["Control_Es_Relay"] == 3);
}

TEST_CASE("CRLF line ends and a UTF-8 BOM read the same as plain LF") {
  const std::string plain = readText(dataPath("schedule/sheet.csv"));
  std::string windows = "\xEF\xBB\xBF";
  for (const char c : plain) windows += c == '\n' ? std::string("\r\n") : std::string(1, c);

  const Imported sut = importSheet(windows);

  REQUIRE(sut.schedule);
  CHECK(sut.schedule->dump(2) == Json::parse(SHEET_SCHEDULE).dump(2));
}

TEST_CASE("empty lines and lines of empty fields are skipped but counted in line numbers") {
  const Imported sut = importSheet(sheetWith("\n,,,,,,,,\r\n   \n,,,HC1_Demand,ControlWord,,,10,6\n"));

  CHECK(sut.errors() ==
        std::vector<std::string>{"sched.csv:6: error: unknown message 'HC1_Demand' (did you mean 'HC1_Demands'?)"});
}

TEST_CASE("text that is not UTF-8 is read as Windows-1252, with a warning") {
  const Imported sut =
      importSheet(std::string(HEADER) + "Battery,Hauptbl\xE4tter,,S1_ES_PGN61427,Control_Es_Relay,0.292,1,20,3\n");

  REQUIRE(sut.schedule);
  CHECK(sut.warnings() == std::vector<std::string>{"sched.csv: warning: not UTF-8: read as Windows-1252"});
}

TEST_CASE("pandas' spellings are read: True/False, whole numbers as 20.0, nan for an empty cell") {
  const Imported sut = importSheet(std::string(HEADER) +
                                   "Battery,Main,61427.0,S1_ES_PGN61427,Control_Es_Relay,0.292,True,20.0,3.0\n"
                                   "Battery,Main,nan,S1_ES_PGN61427,Service_Mode_Request,nan,nan,nan,3\n"
                                   "Inverter,nonshm,nan,HC1_Demands,ControlWord,nan,False,10,6\n");

  REQUIRE(sut.schedule);
  CHECK((*sut.schedule)["messages"]["S1_ES_PGN61427"].dump() ==
        R"({"cycleMs":20,"group":"Battery","values":{"Control_Es_Relay":3,"Service_Mode_Request":3},)"
        R"("safety":{"deltaUs":292}})");
  CHECK_FALSE((*sut.schedule)["messages"]["HC1_Demands"].contains("safety"));
}

TEST_CASE("a row with Signal and Value empty lists its message without values") {
  const Imported sut = importSheet(sheetWith(",,,HC1_Demands,,,,10,\n"));

  REQUIRE(sut.schedule);
  CHECK((*sut.schedule)["include"].dump() == R"(["S1_ES_PGN61427","HC1_Demands"])");
  CHECK((*sut.schedule)["messages"]["HC1_Demands"].dump() == R"({"cycleMs":10})");
}

TEST_CASE("a UniqueID may be the CAN ID, the J1939 PGN or the original's PGN with the destination kept") {
  for (const char* uniqueId : {"0x0CEFF321", "217051937", "0xEF00", "61184", "61427", "0xeff3"}) {
    CAPTURE(uniqueId);
    const Imported sut = importSheet(std::string(HEADER) + "Battery,shm," + uniqueId +
                                     ",S1_ES_PGN61427,Control_Es_Relay,0.292,1,20,3\n");
    CHECK(sut.schedule);
  }
}

// ---- errors: each names file:line, and nothing is produced ----------------------------------------

TEST_CASE("a missing column is an error naming it, and nothing is produced") {
  const Imported sut = importSheet(
      "NodeName,SheetName,UniqueID,Message,Signal,DeltaTime,IsSHM,CycleTime\n"
      "Battery,shm,,S1_ES_PGN61427,Control_Es_Relay,0.292,1,20\n");

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:1: error: missing column 'Value' (the header needs " +
                                                 std::string(COLUMN_LIST) + ")"});
}

TEST_CASE("an extra column is an error naming it, a misspelt one gets a suggestion") {
  const Imported sut = importSheet(
      "NodeName,SheetName,UniqueID,Message,Signal,DeltaTime,IsSHM,Cycletime,Value,Comment\n"
      "Battery,shm,,S1_ES_PGN61427,Control_Es_Relay,0.292,1,20,3,keep-alive\n");

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() ==
        std::vector<std::string>{
            "sched.csv:1: error: unknown column 'Cycletime' (did you mean 'CycleTime'?)",
            "sched.csv:1: error: unknown column 'Comment' (the columns are " + std::string(COLUMN_LIST) + ")",
            "sched.csv:1: error: missing column 'CycleTime' (the header needs " + std::string(COLUMN_LIST) + ")"});
}

TEST_CASE("a sheet separated by semicolons (Excel in some locales) is refused with the reason") {
  const Imported sut = importSheet(
      "NodeName;SheetName;UniqueID;Message;Signal;DeltaTime;IsSHM;CycleTime;Value\n"
      "Battery;shm;;S1_ES_PGN61427;Control_Es_Relay;0,292;1;20;3\n");

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:1: error: the header is separated by ';', not ','; export "
                                                 "the sheet as comma-separated CSV (the header needs " +
                                                 std::string(COLUMN_LIST) + ")"});
}

TEST_CASE("a column named twice is an error") {
  const Imported sut =
      importSheet("NodeName,SheetName,UniqueID,Message,Signal,DeltaTime,IsSHM,CycleTime,Value,Value\n");

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:1: error: column 'Value' appears twice"});
}

TEST_CASE("an empty file and a header without rows are errors") {
  CHECK(importSheet("").errors() ==
        std::vector<std::string>{"sched.csv: error: no header: the first line names the columns " +
                                 std::string(COLUMN_LIST)});
  CHECK(importSheet(HEADER).errors() ==
        std::vector<std::string>{"sched.csv: error: no rows after the header: nothing to import"});
}

TEST_CASE("an unknown message is an error on its line with the closest name") {
  const Imported sut = importSheet(sheetWith("Inverter,,,HC1_Demand,ControlWord,,,10,6\n"));

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() ==
        std::vector<std::string>{"sched.csv:3: error: unknown message 'HC1_Demand' (did you mean 'HC1_Demands'?)"});
}

TEST_CASE("an unknown signal is an error naming its message, with the closest signal") {
  const Imported sut = importSheet(sheetWith(",,,HC1_Demands,ControlWrd,,,10,6\n"));

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() ==
        std::vector<std::string>{
            "sched.csv:3: error: unknown signal 'ControlWrd' in message 'HC1_Demands' (did you mean 'ControlWord'?)"});
}

TEST_CASE("cycle times of one message that disagree are an error on the later row") {
  const Imported sut = importSheet(sheetWith(",,,S1_ES_PGN61427,Service_Mode_Request,,,50,3\n"));

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:3: error: CycleTime 50 of message 'S1_ES_PGN61427' "
                                                 "disagrees with 20 on line 2"});
}

TEST_CASE("a message without any CycleTime is an error on its first row") {
  const Imported sut = importSheet(sheetWith(",,,HC1_Demands,ControlWord,,,,6\n,,,HC1_Demands,CS_Command1,,,,0\n"));

  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:3: error: no CycleTime for message 'HC1_Demands' (give "
                                                 "it on one of its rows)"});
}

TEST_CASE("IsSHM with DeltaTime 0 is an error: an SDM needs the SHM-to-SDM delay") {
  const Imported sut = importSheet(sheetWith("Battery,shm,,HVESSC1_PGN6912,HS_OperConsent,0,1,100,1\n"));

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:3: error: message 'HVESSC1_PGN6912' is an SDM (IsSHM 1) "
                                                 "but its DeltaTime is 0: J1939-76 needs the SHM-to-SDM delay in ms "
                                                 "(> 0)"});
}

TEST_CASE("an SDM's DeltaTime must be shorter than its cycle, and an 11-bit message cannot be an SDM") {
  const Imported sut =
      importSheet(sheetWith("Battery,shm,,HVESSC1_PGN6912,HS_OperConsent,100,1,100,1\n"
                            ",,,VCU_Status,Mode,0.5,yes,100,1\n"));

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() ==
        std::vector<std::string>{
            "sched.csv:3: error: DeltaTime 100 ms of message 'HVESSC1_PGN6912' is not shorter than its CycleTime "
            "100 ms",
            "sched.csv:4: error: message 'VCU_Status' has an 11-bit identifier: a J1939-76 SDM (IsSHM 1) needs a "
            "29-bit one"});
}

TEST_CASE("a safety header cannot be listed: it goes out with its SDM") {
  const Imported sut = importSheet(sheetWith("Battery,shm,,SHM_VCU_to_VIC,SHM_SequenceNumber,,1,20,0\n"));

  CHECK(sut.errors() == std::vector<std::string>{
                            "sched.csv:3: error: 'SHM_VCU_to_VIC' is a J1939-76 safety header (PGN 0x0E00): it goes "
                            "out with its SDM; list the SDM with IsSHM 1 instead"});
}

TEST_CASE("a UniqueID that is neither the message's ID nor its PGN is an error") {
  const Imported sut = importSheet(sheetWith("Battery,shm,61428,S1_ES_PGN61427,Service_Mode_Request,,,,3\n"));

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:3: error: UniqueID 61428 is not message 'S1_ES_PGN61427' "
                                                 "(ID 0x0CEFF321, PGN 0xEF00 (61184) or 0xEFF3 (61427) with its DA)"});
}

TEST_CASE("a Value that is not a number is an error") {
  const Imported sut = importSheet(sheetWith(",,,S1_ES_PGN61427,Service_Mode_Request,,,,three\n"));

  CHECK_FALSE(sut.schedule);
  CHECK(sut.errors() ==
        std::vector<std::string>{"sched.csv:3: error: Value 'three' of signal 'Service_Mode_Request' is not a number"});
}

TEST_CASE("a Value outside the signal's DBC range is an error") {
  const Imported sut = importSheet(sheetWith(",,,S1_ES_PGN61427,Service_Mode_Request,,,,4\n"));

  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:3: error: Value 4 of signal 'Service_Mode_Request' is "
                                                 "outside its DBC range [0|3]"});
}

TEST_CASE("a malformed IsSHM, CycleTime or DeltaTime is an error naming the text") {
  const Imported sut =
      importSheet(sheetWith(",,,HC1_Demands,ControlWord,,maybe,10,6\n"
                            ",,,HC1_Demands,CS_Command1,,,10.5,0\n"
                            ",,,HC1_Demands,SEQ_Command1,-1,,,0\n"));

  CHECK(sut.errors() ==
        std::vector<std::string>{"sched.csv:3: error: IsSHM 'maybe' is not 1/0, true/false or yes/no",
                                 "sched.csv:4: error: CycleTime '10.5' is not whole milliseconds 1..3600000",
                                 "sched.csv:5: error: DeltaTime '-1' is not a number of milliseconds >= 0"});
}

TEST_CASE("the same signal twice is an error when the values differ and a warning when they agree") {
  const Imported sut =
      importSheet(sheetWith(",,,S1_ES_PGN61427,Control_Es_Relay,,,,3\n"
                            ",,,S1_ES_PGN61427,Control_Es_Relay,,,,5\n"));

  CHECK(sut.warnings() == std::vector<std::string>{"sched.csv:3: warning: signal 'Control_Es_Relay' of message "
                                                   "'S1_ES_PGN61427' is already set on line 2"});
  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:4: error: signal 'Control_Es_Relay' of message "
                                                 "'S1_ES_PGN61427' is set to 5 here and to 3 on line 2"});
}

TEST_CASE("a row with another number of fields than the header is an error") {
  const Imported sut = importSheet(sheetWith(",,,HC1_Demands,ControlWord,,,10\n"));

  CHECK(sut.errors() == std::vector<std::string>{"sched.csv:3: error: 8 fields, but the header has 9 columns"});
}

TEST_CASE("a quote that never closes is an error on the line it opens") {
  const Imported sut =
      importSheet(sheetWith(",\"shm,,HC1_Demands,ControlWord,,,10,6\n,,,HC1_Demands,CS_Command1,,,10,0\n"));

  CHECK(sut.errors() ==
        std::vector<std::string>{"sched.csv:3: error: the quoted field opened here never closes (a '\"' is missing)"});
}

TEST_CASE("every error is reported, in line order, not only the first") {
  const Imported sut =
      importSheet(sheetWith(",,,HC1_Demand,ControlWord,,,10,6\n"
                            ",,,HC1_Demands,ControlWrd,,,10,6\n"
                            ",,,HC1_Demands,ControlWord,,,10,x\n"));

  CHECK_FALSE(sut.schedule);
  REQUIRE(sut.errors().size() == 3);
  CHECK(sut.errors()[0].rfind("sched.csv:3: ", 0) == 0);
  CHECK(sut.errors()[1].rfind("sched.csv:4: ", 0) == 0);
  CHECK(sut.errors()[2].rfind("sched.csv:5: ", 0) == 0);
}

// ---- warnings: the import still succeeds ----------------------------------------------------------

TEST_CASE("a sheet named nonshm while IsSHM is 1 is a warning, the message is imported as an SDM") {
  const Imported sut =
      importSheet(std::string(HEADER) + "Battery,nonshm,,S1_ES_PGN61427,Control_Es_Relay,0.292,1,20,3\n");

  REQUIRE(sut.schedule);
  CHECK((*sut.schedule)["messages"]["S1_ES_PGN61427"].contains("safety"));
  CHECK(sut.warnings() == std::vector<std::string>{"sched.csv:2: warning: sheet 'nonshm' but IsSHM 1: message "
                                                   "'S1_ES_PGN61427' is imported as a J1939-76 SDM"});
}

TEST_CASE("a DeltaTime on a message that is not an SDM is ignored with a warning") {
  const Imported sut = importSheet(sheetWith(",,,HC1_Demands,ControlWord,2,0,10,6\n"));

  REQUIRE(sut.schedule);
  CHECK_FALSE((*sut.schedule)["messages"]["HC1_Demands"].contains("safety"));
  CHECK(sut.warnings() == std::vector<std::string>{"sched.csv:3: warning: DeltaTime 2 ms of message 'HC1_Demands' "
                                                   "ignored: it is not an SDM (IsSHM is 0)"});
}

TEST_CASE("a message another node transmits is imported with a warning when the node is known") {
  ImportOptions options;
  options.node = THIS_NODE;

  const Imported sut = importSheet(sheetWith(",,,HVESSS1_PGN61590,HS_State,,,100,1\n"), options);

  REQUIRE(sut.schedule);
  CHECK(sut.warnings() == std::vector<std::string>{"sched.csv:3: warning: message 'HVESSS1_PGN61590' is transmitted "
                                                   "by VIC, not by Vehicle_Control_Unit"});
}

// ---- through the CLI entry ---------------------------------------------------------------------

TEST_CASE("vcu schedule import -o writes the JSON atomically, it reads back as the converted schedule") {
  const std::filesystem::path folder = scratchFolder("schedule-import");
  const std::string output = (folder / "schedule.json").string();
  const std::string sheet = dataPath("schedule/sheet.csv");

  const RunResult result =
      runVcu({"schedule", "import", sheet, "--config", dataPath("schedule/vehicle.json"), "-o", output});

  REQUIRE(result.exitCode == EXIT_OK);
  CHECK(result.out == output + ": 3 messages (2 J1939-76 SDMs), 9 values, 2 groups from " + sheet + "\n");
  CHECK(contains(result.err, sheet + ": note: the send groups switch on internal signals"));
  CHECK(folderEntries(folder) == std::vector<std::string>{"schedule.json"});  // no temporary left
  const std::string written = readText(output);
  CHECK(written == Json::parse(SHEET_SCHEDULE).dump(2) + "\n");
  CHECK(Json::parse(written) == Json::parse(SHEET_SCHEDULE));
}

TEST_CASE("what vcu schedule import writes loads with the schedule loader vcu-can-tx and vcu check use (#20)") {
  const std::filesystem::path folder = scratchFolder("schedule-import-loads");
  std::filesystem::copy_file(dataPath("schedule/schedule.dbc"), folder / "schedule.dbc");
  const RunResult imported = runVcu({"schedule", "import", dataPath("schedule/sheet.csv"), "--dbc",
                                     dataPath("schedule/schedule.dbc"), "--node", THIS_NODE, "-o",
                                     (folder / "schedule.json").string()});
  REQUIRE_MESSAGE(imported.exitCode == EXIT_OK, imported.err);
  // the send groups' signals, declared as the import's note asks
  const std::string vehiclePath = writeScratchFile("schedule-import-loads/vehicle.json", R"({
  "instance": "importtest",
  "node": "Vehicle_Control_Unit",
  "dbc": ["schedule.dbc"],
  "buses": [{"name": "vehicle", "link": "sim:vehicle", "messages": "all"}],
  "internalSignals": [{"name": "tx.Battery"}, {"name": "tx.Inverter"}],
  "schedule": "schedule.json",
  "lcm": "memq://"
})");
  auto vehicle = openvcu::config::loadVehicleConfig(vehiclePath);
  REQUIRE_MESSAGE(vehicle, vehicle.error().toString());
  auto catalog = openvcu::config::buildCatalog(*vehicle);
  REQUIRE_MESSAGE(catalog, catalog.error().toString());

  const auto sut = openvcu::schedule::loadSchedule(*vehicle, *catalog);

  REQUIRE_MESSAGE(sut, sut.error().toString());
  CHECK(sut->messages.size() == 3);
  const auto s1 = openvcu::schedule::findScheduled(*sut, *vehicle, "S1_ES_PGN61427");
  REQUIRE(s1);
  const openvcu::schedule::ScheduledMessage& entry = sut->messages[*s1];
  CHECK(entry.cycleNs == 20'000'000);
  REQUIRE(entry.safetyDeltaNs);
  CHECK(*entry.safetyDeltaNs == 292'000);
  REQUIRE(entry.group);
  CHECK(sut->groups[*entry.group].name == "Battery");
  CHECK(sut->groups.size() == 2);
}

TEST_CASE("vcu schedule import without -o prints the JSON on stdout") {
  const RunResult result = runVcu({"schedule", "import", dataPath("schedule/sheet.csv"), "--dbc",
                                   dataPath("schedule/schedule.dbc"), "--node", THIS_NODE});

  REQUIRE(result.exitCode == EXIT_OK);
  CHECK(result.out == Json::parse(SHEET_SCHEDULE).dump(2) + "\n");
}

TEST_CASE("vcu schedule import with an error prints every diagnostic, exits 1 and leaves the output alone") {
  const std::filesystem::path folder = scratchFolder("schedule-import-error");
  const std::string output = (folder / "schedule.json").string();
  {
    std::ofstream previous(output);
    previous << "previous";
  }
  const std::string sheet = writeScratchFile("schedule-error.csv", sheetWith(",,,HC1_Demands,ControlWrd,,,10,6\n"));

  const RunResult result =
      runVcu({"schedule", "import", sheet, "--dbc", dataPath("schedule/schedule.dbc"), "-o", output});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.out.empty());
  CHECK(contains(result.err, sheet + ":3: error: unknown signal 'ControlWrd' in message 'HC1_Demands' (did you "
                                     "mean 'ControlWord'?)\n"));
  CHECK(contains(result.err, sheet + ": note: 1 error: nothing written\n"));
  CHECK(readText(output) == "previous");
  CHECK(folderEntries(folder) == std::vector<std::string>{"schedule.json"});
}

TEST_CASE("vcu schedule import refuses --config with --dbc, and a malformed --group-signal") {
  const RunResult both = runVcu({"schedule", "import", dataPath("schedule/sheet.csv"), "--config",
                                 dataPath("schedule/vehicle.json"), "--dbc", dataPath("schedule/schedule.dbc")});
  const RunResult malformed = runVcu({"schedule", "import", dataPath("schedule/sheet.csv"), "--dbc",
                                      dataPath("schedule/schedule.dbc"), "--group-signal", "Battery"});

  CHECK(both.exitCode == EXIT_USAGE);
  CHECK(malformed.exitCode == EXIT_USAGE);
  CHECK(contains(malformed.err, "--group-signal 'Battery': expected NODE=KEY"));
}

TEST_CASE("vcu schedule import names an unknown --node with a suggestion") {
  const RunResult result = runVcu({"schedule", "import", dataPath("schedule/sheet.csv"), "--dbc",
                                   dataPath("schedule/schedule.dbc"), "--node", "Vehicle_Control_Uni"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err ==
        "vcu: error: --node 'Vehicle_Control_Uni' is not a node of the DBC (did you mean 'Vehicle_Control_Unit'?)\n");
}

// ---- runtime commands: the refusals answered before anything is sent ------------------------------

TEST_CASE("vcu schedule cycle, enable and disable refuse an unknown message locally, with a suggestion") {
  for (const std::vector<std::string>& command : std::vector<std::vector<std::string>>{
           {"cycle", "HC1_Demand", "50"}, {"enable", "HC1_Demand"}, {"disable", "HC1_Demand"}}) {
    std::vector<std::string> arguments{"schedule"};
    arguments.insert(arguments.end(), command.begin(), command.end());
    arguments.insert(arguments.end(), {"--config", dataPath("schedule/vehicle.json")});
    CAPTURE(command.front());

    const RunResult result = runVcu(arguments);

    CHECK(result.exitCode == EXIT_INPUT_ERROR);
    CHECK(result.out.empty());  // neither "accepted" nor "refused": nothing was asked
    CHECK(result.err == "vcu: error: unknown message 'HC1_Demand' (did you mean 'HC1_Demands'?)\n");
  }
}

TEST_CASE("vcu schedule cycle refuses a cycle time outside 1..3600000 ms or not whole locally") {
  const std::string config = dataPath("schedule/vehicle.json");
  const RunResult zero = runVcu({"schedule", "cycle", "HC1_Demands", "0", "--config", config});
  const RunResult fraction = runVcu({"schedule", "cycle", "HC1_Demands", "2.5", "--config", config});
  const RunResult text = runVcu({"schedule", "cycle", "HC1_Demands", "fast", "--config", config});

  CHECK(zero.exitCode == EXIT_INPUT_ERROR);
  CHECK(zero.err == "vcu: error: cycle time '0': the cycle must be a whole number of ms from 1 to 3600000, not 0\n");
  CHECK(fraction.exitCode == EXIT_INPUT_ERROR);
  CHECK(fraction.err ==
        "vcu: error: cycle time '2.5': the cycle must be a whole number of ms from 1 to 3600000, not 2.5\n");
  CHECK(text.exitCode == EXIT_INPUT_ERROR);
  CHECK(text.err == "vcu: error: cycle time 'fast': expected milliseconds, 1..3600000\n");
}

TEST_CASE("vcu schedule default refuses an unknown key, an internal signal and a bad value locally") {
  const std::string config = dataPath("schedule/vehicle.json");

  const RunResult unknown =
      runVcu({"schedule", "default", "Vehicle_Control_Unit.HC1_Demands.ControlWrd", "6", "--config", config});
  const RunResult internal = runVcu({"schedule", "default", "internal.tx.keepAlive", "1", "--config", config});
  const RunResult badValue = runVcu(
      {"schedule", "default", "Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay", "Connect", "--config", config});

  CHECK(unknown.exitCode == EXIT_INPUT_ERROR);
  CHECK(unknown.err ==
        "vcu: error: unknown signal 'Vehicle_Control_Unit.HC1_Demands.ControlWrd' (did you mean "
        "'Vehicle_Control_Unit.HC1_Demands.ControlWord'?)\n");
  CHECK(internal.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(internal.err, "'internal.tx.keepAlive' is an internal signal"));
  CHECK(badValue.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(badValue.err, "'Connect' is not a number nor a value of"));
  CHECK((unknown.out + internal.out + badValue.out).empty());
}
