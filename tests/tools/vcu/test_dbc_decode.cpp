#include <nlohmann/json.hpp>

#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;
using nlohmann::json;

namespace {

// Lines of data/drive.log (1-based).
constexpr std::size_t EEC1_FROM_SA_00 = 0;   // 0CF00400: PGN 0xF004, not the DBC's exact ID 0CF004FE
constexpr std::size_t EEC1_EXACT = 1;        // 0CF004FE
constexpr std::size_t STATUS_MODE_1 = 2;     // 123, mux value 1 selects Voltage
constexpr std::size_t STATUS_MODE_2 = 3;     // 123 on can1, mux value 2 selects Current; Ratio +inf
constexpr std::size_t UNKNOWN_STANDARD = 4;  // 7FF
constexpr std::size_t XBR_TO_0B = 5;         // 0C040B21: PDU1 to 0x0B, the destination the DBC defines
constexpr std::size_t XBR_TO_03 = 6;         // 0C040321: PDU1 to 0x03, not defined
constexpr std::size_t CCVS1_FROM_SA_21 = 7;  // 18FEF121
constexpr std::size_t DRIVE_LOG_FRAMES = 8;

std::vector<json> decodeToJson(const std::vector<std::string>& arguments, int expectedExitCode = EXIT_OK) {
  const RunResult result = runVcu(arguments);
  REQUIRE(result.exitCode == expectedExitCode);
  std::vector<json> frames;
  for (const std::string& line : splitLines(result.out)) frames.push_back(json::parse(line));
  return frames;
}

std::vector<json> decodeDriveLog(const std::string& matchMode) {
  return decodeToJson({"dbc", "decode", "--match", matchMode, dataPath("vehicle.dbc"), dataPath("drive.log")});
}

}  // namespace

TEST_CASE("decode writes one JSON object per frame in the oracle's shape") {
  const std::vector<json> frames = decodeDriveLog("j1939");

  REQUIRE(frames.size() == DRIVE_LOG_FRAMES);
  const json& sut = frames[EEC1_EXACT];
  CHECK(sut["t"].get<double>() == doctest::Approx(1700000000.0002));
  CHECK(sut["bus"] == "can0");
  CHECK(sut["id"] == 0x0CF004FE);
  CHECK(sut["ext"] == true);
  CHECK(sut["msg"] == "EEC1");
  CHECK(sut["signals"] == json::parse(R"({"EngTorqueMode":3,"ActualTorque":35,"EngineSpeedWithALongName":1250})"));
  CHECK(sut["raw"] == json::parse(R"({"EngTorqueMode":3,"ActualTorque":160,"EngineSpeedWithALongName":10000})"));
}

TEST_CASE("decode prints the time exactly as logged and integral values as integers") {
  const RunResult result = runVcu({"dbc", "decode", dataPath("vehicle.dbc"), dataPath("drive.log")});

  REQUIRE(result.exitCode == EXIT_OK);
  CHECK(splitLines(result.out)[EEC1_EXACT] ==
        R"({"t":1700000000.000200,"bus":"can0","id":217056510,"ext":true,"msg":"EEC1",)"
        R"("signals":{"EngTorqueMode":3,"ActualTorque":35,"EngineSpeedWithALongName":1250},)"
        R"("raw":{"EngTorqueMode":3,"ActualTorque":160,"EngineSpeedWithALongName":10000}})");
}

TEST_CASE("decode lists only the multiplexed signals the multiplexor selects") {
  const std::vector<json> frames = decodeDriveLog("j1939");

  REQUIRE(frames.size() == DRIVE_LOG_FRAMES);
  const json& modeOne = frames[STATUS_MODE_1]["signals"];
  const json& modeTwo = frames[STATUS_MODE_2]["signals"];
  CHECK(modeOne["Voltage"].get<double>() == doctest::Approx(12.34));
  CHECK_FALSE(modeOne.contains("Current"));
  CHECK(modeOne["Ratio"] == 1.5);
  CHECK(modeOne["Temperature"] == -40);
  CHECK(modeTwo["Current"].get<double>() == doctest::Approx(-12.3));
  CHECK(frames[STATUS_MODE_2]["raw"]["Current"] == -123);
  CHECK_FALSE(modeTwo.contains("Voltage"));
  CHECK(frames[STATUS_MODE_2]["bus"] == "can1");
}

TEST_CASE("decode writes a non-finite float signal as the string \"inf\"") {
  const std::vector<json> frames = decodeDriveLog("j1939");

  REQUIRE(frames.size() == DRIVE_LOG_FRAMES);
  CHECK(frames[STATUS_MODE_2]["signals"]["Ratio"] == "inf");
  CHECK(frames[STATUS_MODE_2]["raw"]["Ratio"] == "inf");
}

TEST_CASE("decode writes msg null and empty objects for a frame no message matches") {
  const std::vector<json> frames = decodeDriveLog("j1939");

  REQUIRE(frames.size() == DRIVE_LOG_FRAMES);
  const json& sut = frames[UNKNOWN_STANDARD];
  CHECK(sut["id"] == 0x7FF);
  CHECK(sut["ext"] == false);
  CHECK(sut["msg"].is_null());
  CHECK(sut["signals"] == json::object());
  CHECK(sut["raw"] == json::object());
}

TEST_CASE("decode --match j1939 matches extended frames by PGN whatever their source address") {
  const std::vector<json> frames = decodeDriveLog("j1939");

  REQUIRE(frames.size() == DRIVE_LOG_FRAMES);
  CHECK(frames[EEC1_FROM_SA_00]["msg"] == "EEC1");
  CHECK(frames[EEC1_FROM_SA_00]["id"] == 0x0CF00400);
  CHECK(frames[CCVS1_FROM_SA_21]["msg"] == "CCVS1");
  CHECK(frames[CCVS1_FROM_SA_21]["signals"]["WheelSpeed"] == 25);
}

TEST_CASE("decode --match j1939 matches a PDU1 frame only for the destination the DBC defines") {
  const std::vector<json> frames = decodeDriveLog("j1939");

  REQUIRE(frames.size() == DRIVE_LOG_FRAMES);
  CHECK(frames[XBR_TO_0B]["msg"] == "XBR");
  CHECK(frames[XBR_TO_0B]["signals"]["Demand"] == 50);
  CHECK(frames[XBR_TO_03]["msg"].is_null());
}

TEST_CASE("decode --match exact matches only the exact identifiers") {
  const std::vector<json> frames = decodeDriveLog("exact");

  REQUIRE(frames.size() == DRIVE_LOG_FRAMES);
  CHECK(frames[EEC1_FROM_SA_00]["msg"].is_null());
  CHECK(frames[EEC1_EXACT]["msg"] == "EEC1");
  CHECK(frames[XBR_TO_0B]["msg"].is_null());
  CHECK(frames[CCVS1_FROM_SA_21]["msg"].is_null());
  CHECK(frames[STATUS_MODE_1]["msg"] == "VcuStatus");
}

TEST_CASE("decode --format csv writes the header, then one row per signal") {
  const RunResult result = runVcu({"dbc", "decode", "--format", "csv", dataPath("vehicle.dbc"), dataPath("drive.log")});

  REQUIRE(result.exitCode == EXIT_OK);
  const std::vector<std::string> lines = splitLines(result.out);
  REQUIRE(lines.size() > 4);
  CHECK(lines[0] == "t,bus,id,ext,msg,signal,raw,physical");
  CHECK(lines[1] == "1700000000.000100,can0,217056256,true,EEC1,EngTorqueMode,3,3");
  CHECK(lines[3] == "1700000000.000100,can0,217056256,true,EEC1,EngineSpeedWithALongName,10000,1250");
  CHECK(contains(result.out, "\n1700000000.030000,can0,2047,false,,,,\n"));  // unknown frame: one row
  CHECK(contains(result.out, "\n1700000000.020000,can1,291,false,VcuStatus,Ratio,inf,inf\n"));
}

TEST_CASE("decode reports a malformed log line with its line number, goes on, and exits 1") {
  const std::string log = dataPath("malformed.log");

  const RunResult result = runVcu({"dbc", "decode", dataPath("vehicle.dbc"), log});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, log + ":3:26: error: data length 10 exceeds 8 for a classic frame\n"));
  CHECK(contains(result.err, log + ":4:"));
  CHECK(contains(result.err, log + ": error: 2 malformed lines skipped\n"));
  CHECK(splitLines(result.out).size() == 2);  // the good frames before and after
}

TEST_CASE("decode prints the first 20 malformed lines, then only their count") {
  constexpr int BAD_LINES = 25;
  std::string content;
  for (int i = 0; i < BAD_LINES; ++i) content += "(1.000000) can0 123#XYZ\n";
  content += "(2.000000) can0 123#0100000000000000\n";
  const std::string log = writeScratchFile("many_bad_lines.log", content);

  const RunResult result = runVcu({"dbc", "decode", dataPath("vehicle.dbc"), log});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, log + ":20:"));
  CHECK_FALSE(contains(result.err, log + ":21:"));
  CHECK(contains(result.err, "25 malformed lines skipped (the first 20 shown)"));
  CHECK(splitLines(result.out).size() == 1);
}

TEST_CASE("decode --limit stops after that many frames") {
  constexpr int LIMIT = 3;

  const RunResult result =
      runVcu({"dbc", "decode", "--limit", std::to_string(LIMIT), dataPath("vehicle.dbc"), dataPath("drive.log")});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(splitLines(result.out).size() == LIMIT);
}

TEST_CASE("decode merges several DBC files") {
  const std::string log = writeScratchFile("door.log", "(3.000000) can0 500#0200\n");

  const std::vector<json> frames = decodeToJson({"dbc", "decode", dataPath("vehicle.dbc"), dataPath("body.dbc"), log});

  REQUIRE(frames.size() == 1);
  CHECK(frames[0]["msg"] == "DoorStatus");
  CHECK(frames[0]["signals"] == json::parse(R"({"DriverDoorOpen":0,"PassengerDoorOpen":1})"));
}

TEST_CASE("decode refuses a DBC with errors, prints them and decodes nothing") {
  const RunResult result = runVcu({"dbc", "decode", dataPath("broken.dbc"), dataPath("drive.log")});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "broken.dbc:11:20: error: "));
  CHECK(result.out.empty());
}

TEST_CASE("decode refuses DBC files that conflict") {
  const RunResult result =
      runVcu({"dbc", "decode", dataPath("vehicle.dbc"), dataPath("conflicting.dbc"), dataPath("drive.log")});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "conflicting.dbc:9: error: message 'EEC1'"));
  CHECK(result.out.empty());
}

TEST_CASE("decode reports a missing log with the OS reason") {
  const std::string log = dataPath("no_such.log");

  const RunResult result = runVcu({"dbc", "decode", dataPath("vehicle.dbc"), log});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err == log + ": error: cannot open log: No such file or directory\n");
}

TEST_CASE("decode refuses a directory given as the log as not a regular file, no 'read error' (#19)") {
  const std::string folder = std::string(VCU_TEST_DATA);

  const RunResult result = runVcu({"dbc", "decode", dataPath("vehicle.dbc"), folder});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err == folder + ": error: not a regular file (directory)\n");
  CHECK(result.out.empty());
}

TEST_CASE("decode needs at least a DBC and a log, and known option values") {
  CHECK(runVcu({"dbc", "decode", dataPath("vehicle.dbc")}).exitCode == EXIT_USAGE);
  CHECK(runVcu({"dbc", "decode", "--format", "xml", dataPath("vehicle.dbc"), dataPath("drive.log")}).exitCode ==
        EXIT_USAGE);
  CHECK(runVcu({"dbc", "decode", "--match", "fuzzy", dataPath("vehicle.dbc"), dataPath("drive.log")}).exitCode ==
        EXIT_USAGE);
}
