// `vcu fsm check|graph|replay` in-process: the thesis' listing, a clean machine, DOT and
// Mermaid output, and a replayed log on its own clock (deadlines between frames).

#include <doctest/doctest.h>

#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;

namespace {

const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
const std::string THESIS = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/fsm/thesis_listing_c2.json";

constexpr const char* CONNECTION_MACHINE = R"({"initialState": "Wait", "states": [
  {"name": "Wait", "transitions": [
    {"condition": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 1, "for": "500ms"},
     "actions": [{"event": "battery connected"}], "nextState": "Connected"}]},
  {"name": "Connected", "transitions": [
    {"condition": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "ageGt": "1s"},
     "actions": [{"raise": "battery_silent"}], "nextState": "Lost"}]},
  {"name": "Lost", "transitions": []}]})";

}  // namespace

TEST_CASE("vcu fsm check reports the thesis' listing and exits 1") {
  const RunResult result = runVcu({"fsm", "check", THESIS, "--config", HHEA});
  CHECK(result.exitCode == 1);
  CHECK(contains(result.err, "thesis_listing_c2.json: /initialState: error: initial state 'On Boot' is not defined"));
  CHECK(contains(result.err, "did you mean 'VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts'"));
  CHECK(contains(result.err, "warning: empty condition {}: always true"));
  CHECK(contains(result.out, "thesis_listing_c2.json: 12 errors, 24 warnings\n"));
  const RunResult quiet = runVcu({"fsm", "check", "--quiet", THESIS, "--config", HHEA});
  CHECK_FALSE(contains(quiet.err, "warning:"));  // diagnostics on stderr (#19)
  CHECK(contains(quiet.out, "12 errors, 24 warnings"));
}

TEST_CASE("vcu fsm check passes a clean machine with its size") {
  const std::string file = writeScratchFile("connection.json", CONNECTION_MACHINE);
  const RunResult result = runVcu({"fsm", "check", file, "--config", HHEA});
  CHECK_MESSAGE(result.exitCode == 0, (result.out + result.err));
  CHECK(contains(result.out, "connection.json: 0 errors, 0 warnings (3 states, 2 transitions)"));
  const RunResult noConfig = runVcu({"fsm", "check", file, "--config", "/nonexistent/vehicle.json"});
  CHECK(noConfig.exitCode == 1);
}

TEST_CASE("vcu fsm graph draws DOT and Mermaid, keys as written, without a configuration") {
  const RunResult dot = runVcu({"fsm", "graph", THESIS});
  CHECK_MESSAGE(dot.exitCode == 0, dot.err);
  CHECK(contains(dot.out, "digraph fsm {"));
  CHECK(contains(dot.out, "__start -> \"On Boot\";"));
  CHECK(contains(dot.out, "\"Start\" -> \"Battery Fault\" [label=\"VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts eq 14\"];"));
  CHECK(contains(dot.out, "\"Start\" -> \"Stop\" [label=\"always / 9 actions\"];"));
  const RunResult mermaid = runVcu({"fsm", "graph", "--mermaid", THESIS});
  CHECK(mermaid.exitCode == 0);
  CHECK(contains(mermaid.out, "stateDiagram-v2\n"));
  CHECK(contains(mermaid.out, "[*] --> undefined_On_Boot"));
  const RunResult broken = runVcu({"fsm", "graph", writeScratchFile("broken.json", "{\"states\": [")});
  CHECK(broken.exitCode == 1);
  CHECK(contains(broken.err, "broken.json:1:"));
}

TEST_CASE("vcu fsm replay runs the machine on the log's clock, deadlines between frames") {
  const std::string machine = writeScratchFile("connection.json", CONNECTION_MACHINE);
  // HVESSS1 (0x14F096F3): HS_HiUBusCnctnSts in bits 44..47 (byte 5, high nibble)
  std::string log = "(1700000000.000000) can0 14F096F3#0000000000000000\n";
  for (int tenth = 1; tenth <= 10; ++tenth) {
    log += "(1700000000." + std::to_string(tenth) + "00000) can0 14F096F3#0000000000100000\n";
    if (tenth == 10) log.replace(log.rfind("1700000000.10"), 13, "1700000001.00");
  }
  log += "(1700000002.500000) can0 18FF4040#0100000000000000\n";  // PDU_Tx_1, later
  const std::string logFile = writeScratchFile("connection.log", log);
  const RunResult result = runVcu({"fsm", "replay", machine, "--config", HHEA, logFile});
  CHECK_MESSAGE(result.exitCode == 0, result.err);
  const auto lines = splitLines(result.out);
  REQUIRE_MESSAGE(lines.size() == 5, result.out);
  CHECK(lines[0] == "0.000000 s  (start) -> Wait: initial state");
  CHECK(contains(lines[1], "0.600000 s  Wait -> Connected: VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts eq 1 for 500ms"));
  CHECK(lines[2] == "0.600000 s  event: battery connected");
  CHECK(contains(lines[3], "2.000000 s  Connected -> Lost: VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts ageGt 1s"));
  CHECK(lines[4] == "2.000000 s  fault raised battery_silent");
  CHECK(contains(result.err, "12 frames"));
  CHECK(contains(result.err, "final state 'Lost'"));
}

TEST_CASE("the shipped HHEA machine checks clean, and the recorded connection replays on time") {
  const RunResult check = runVcu({"fsm", "check", std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/fsm.json", "--config", HHEA});
  CHECK_MESSAGE(check.exitCode == 0, check.out);
  CHECK(contains(check.out, "0 errors, 0 warnings"));
  const std::string data = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/fsm/";
  const RunResult replay =
      runVcu({"fsm", "replay", data + "replay_test.json", "--config", HHEA, data + "hhea_connect_drive.log"});
  CHECK_MESSAGE(replay.exitCode == 0, replay.err);
  CHECK(contains(replay.out, "0.000000 s  Wait -> Awaiting HV: "));
  CHECK(contains(replay.out, "3.500000 s  Awaiting HV -> Connected: all(VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts eq 1 for 500ms"));
  CHECK(contains(replay.out, "5.500000 s  Connected -> Settled: after 2s"));
  CHECK(contains(replay.err, "360 frames"));
  CHECK(contains(replay.err, "final state 'Settled'"));
}
