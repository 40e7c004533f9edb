// `vcu safety campaign` on the whole headless HHEA stack in the sandbox (iox-roudi,
// vcu-can-rx, vcu-can-tx, vcu-fsm, vcu-gpio, vcu-ecu-sim), with a test-local safety case of
// two hazards whose faults and observations exist on that stack:
//   - the battery (VIC) going silent in Ready -> Battery Timeout, the contactors commanded
//     open on the bus, can-rx's receive timeout of HVESSS1;
//   - vcu-fsm hanging (SIGSTOP) while Driving -> vcu-can-tx's dead-man commands the safe
//     values (contactors open, inverters disabled) and raises writer_lost.fsm.
// A campaign with an FTTI of 1 ms must fail and name the miss.

#include <doctest/doctest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "safety_campaign_stack.hpp"

namespace {

constexpr std::int64_t BATTERY_FTTI_MS = 4000;
constexpr std::int64_t HANG_FTTI_MS = 4000;
constexpr double HVESSS1_TIMEOUT_MS = 3000;  // fsm.json: "ageGt": "3s"
constexpr double HVESSS1_CYCLE_MS = 100;     // hhea.dbc GenMsgCycleTime

/// The test-local safety case: the two hazards, FTTIs as given.
nlohmann::json safetyCase(std::int64_t batteryFttiMs, std::int64_t hangFttiMs) {
  return nlohmann::json::parse(R"({
    "hazards": [
      {"id": "T-BAT-SILENT", "severity": "PL d",
       "description": "the battery stops sending", "safetyGoal": "open the HV path",
       "during": ["Ready"],
       "safeState": {"fsmStates": ["Battery Timeout"],
                     "bus": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 0}]},
       "detection": [{"kind": "receiveTimeout", "message": "HVESSS1_PGN61590"}],
       "fttiMs": 1000,
       "faults": [{"inject": "silence", "node": "VIC"}]},
      {"id": "T-FSM-HANG", "severity": "PL d",
       "description": "vcu-fsm hangs while driving", "safetyGoal": "open the HV path, disable the drive",
       "during": ["Driving"],
       "safeState": {"bus": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 0},
                             {"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupB_Contactors", "value": 0}]},
       "detection": [{"kind": "dtc", "fault": "writer_lost.fsm"}],
       "fttiMs": 1000,
       "faults": [{"inject": "stop", "service": "fsm"}]}
    ]})")
      .patch(nlohmann::json::parse(
          "[{\"op\": \"replace\", \"path\": \"/hazards/0/fttiMs\", \"value\": " + std::to_string(batteryFttiMs) +
          "}, {\"op\": \"replace\", \"path\": \"/hazards/1/fttiMs\", \"value\": " + std::to_string(hangFttiMs) + "}]"));
}

}  // namespace

TEST_CASE(
    "the campaign brings HHEA to Ready and Driving, and the battery's silence and vcu-fsm's hang pass within the "
    "FTTI") {
  SKIP_UNLESS_ISOLATED();
  CampaignStack stack;
  const fs::path safety = stack.writeSafety(safetyCase(BATTERY_FTTI_MS, HANG_FTTI_MS));
  const fs::path folder = safety.parent_path();
  const auto result = stack.vcu({"safety", "campaign", "--safety", safety.string(), "--repeat", "1", "--json",
                                 (folder / "c.json").string(), "--junit", (folder / "c.xml").string(), "--html",
                                 (folder / "c.html").string()});
  MESSAGE(result.out);
  CHECK_MESSAGE(result.exitCode() == 0, result.describe());
  CHECK(contains(result.out, "T-BAT-SILENT #1 PASS"));
  CHECK(contains(result.out, "T-FSM-HANG #1 PASS"));
  CHECK(contains(result.out, "campaign passed: 2 passed, 0 failed"));

  const nlohmann::json report = readJson(folder / "c.json");
  REQUIRE_FALSE(report.is_discarded());
  CHECK(report["passed"] == true);
  REQUIRE(report["hazards"].size() == 2);
  for (const auto& hazard : report["hazards"]) {
    CHECK_MESSAGE(hazard["verdict"] == "PASS", hazard.dump());
    const double ftti = hazard["fttiMs"].get<double>();
    for (const auto& item : hazard["repetitions"][0]["items"]) {
      REQUIRE_MESSAGE(item["reachedMs"].is_number(), item.dump());
      const double ms = item["reachedMs"].get<double>();
      // a reaction takes time: none is 0 or before the injection, none beyond the FTTI
      CHECK_MESSAGE(ms > 0, item.dump());
      CHECK_MESSAGE(ms < ftti, item.dump());
    }
  }
  // the battery timeout is fsm.json's "ageGt 3s" counted from the last HVESSS1 (every
  // 100 ms) before the injection: not before 3 s less one cycle
  const auto& battery = report["hazards"][0]["repetitions"][0]["items"][0];
  CHECK(battery["item"] == "fsm Battery Timeout");
  CHECK(battery["reachedMs"].get<double>() >= HVESSS1_TIMEOUT_MS - HVESSS1_CYCLE_MS);
  CHECK(report["coverage"]["fsmStatesReached"] == nlohmann::json::array({"Battery Timeout"}));

  std::ifstream junit(folder / "c.xml");
  const std::string xml((std::istreambuf_iterator<char>(junit)), std::istreambuf_iterator<char>());
  CHECK(contains(xml, "<testsuite name=\"vcu safety campaign\" tests=\"2\" failures=\"0\""));
  CHECK(contains(xml, "<testcase classname=\"safety."));
  CHECK(contains(xml, "</testsuite>"));
  std::ifstream html(folder / "c.html");
  const std::string page((std::istreambuf_iterator<char>(html)), std::istreambuf_iterator<char>());
  CHECK(contains(page, "<svg"));
  CHECK(contains(page, "campaign passed"));
  CHECK_FALSE(contains(page, "http"));  // self-contained: nothing fetched
}

TEST_CASE("a campaign whose FTTI cannot be met exits 1 and names the miss") {
  SKIP_UNLESS_ISOLATED();
  CampaignStack stack;
  const fs::path safety = stack.writeSafety(safetyCase(BATTERY_FTTI_MS, 1));
  const fs::path folder = safety.parent_path();
  const auto result = stack.vcu({"safety", "campaign", "--safety", safety.string(), "--hazard", "T-FSM-HANG", "--junit",
                                 (folder / "f.xml").string()});
  MESSAGE(result.out);
  CHECK_MESSAGE(result.exitCode() == 1, result.describe());
  CHECK(contains(result.out, "T-FSM-HANG #1 FAIL"));
  CHECK(contains(result.out, "miss #1: fault writer_lost.fsm not seen within 2.0 ms"));
  CHECK(contains(result.out, "campaign FAILED: 0 passed, 1 failed"));
  std::ifstream junit(folder / "f.xml");
  const std::string xml((std::istreambuf_iterator<char>(junit)), std::istreambuf_iterator<char>());
  CHECK(contains(xml, "failures=\"1\""));
  CHECK(contains(xml, "<failure message=\"FTTI 1 ms missed\">"));
}
