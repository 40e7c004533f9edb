// safety.json on its own (shared/safety/safety_case.hpp): the watchdog policy, hazards,
// safe states, detection mechanisms, injected faults, and the JSON path of every refusal.
#include <doctest/doctest.h>

#include <string>
#include <string_view>

#include "openvcu/safety/safety_case.hpp"

namespace {

using namespace openvcu;

constexpr std::string_view FILE_NAME = "safety.json";

/// A hazard that loads; tests replace one member.
constexpr std::string_view HAZARD = R"({
  "id": "H-BAT-TIMEOUT", "severity": "PL d",
  "description": "the battery stops sending", "safetyGoal": "open the HV path",
  "safeState": {"fsmStates": ["Battery Timeout"], "gpio": [{"line": "Cl15", "level": 0}],
                "bus": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 0}]},
  "detection": [{"kind": "receiveTimeout", "message": "HVESSS1_PGN61590"}],
  "fttiMs": 4000,
  "faults": [{"inject": "silence", "node": "VIC"}]
})";

std::string withHazard(const std::string& hazard) {
  return R"({"hazards": [)" + hazard + "]}";
}

/// HAZARD with the text `from` replaced by `to` (once; the test fails when it is absent).
std::string hazardWith(std::string_view from, std::string_view to) {
  std::string hazard(HAZARD);
  const auto at = hazard.find(from);
  REQUIRE(at != std::string::npos);
  hazard.replace(at, from.size(), to);
  return withHazard(hazard);
}

std::string errorOf(const std::string& text) {
  auto parsed = safety::parseSafety(text, std::string(FILE_NAME));
  REQUIRE_FALSE(parsed);
  return parsed.error().toString();
}

bool contains(const std::string& text, std::string_view part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("the watchdog section gives the services, the silence bound, restart and the device") {
  auto sut = safety::parseSafety(R"({"hazards": [], "watchdog": {"services": ["can-rx", "can-tx", "fsm", "gpio"],
                                   "silentAfterMs": 1500, "restart": true, "device": "/dev/watchdog"}})",
                                 std::string(FILE_NAME));
  REQUIRE(sut);
  REQUIRE(sut->watchdog);
  CHECK(sut->watchdog->services == std::vector<std::string>{"can-rx", "can-tx", "fsm", "gpio"});
  CHECK(sut->watchdog->silentAfterMs == 1500);
  CHECK(sut->watchdog->restart);
  CHECK(sut->watchdog->device == "/dev/watchdog");
}

TEST_CASE("the watchdog restarts by default and feeds no device unless one is named") {
  auto sut = safety::parseSafety(R"({"hazards": [], "watchdog": {"services": ["fsm"], "silentAfterMs": 800}})",
                                 std::string(FILE_NAME));
  REQUIRE(sut);
  REQUIRE(sut->watchdog);
  CHECK(sut->watchdog->restart);
  CHECK(sut->watchdog->device.empty());
}

TEST_CASE("a safety case without a watchdog section has no watchdog policy") {
  auto sut = safety::parseSafety(R"({"hazards": []})", std::string(FILE_NAME));
  REQUIRE(sut);
  CHECK_FALSE(sut->watchdog);
  CHECK(sut->hazards.empty());
}

TEST_CASE("a broken watchdog section is refused with the JSON path and the reason") {
  CHECK(contains(errorOf(R"({"hazards": [], "watchdog": {"services": ["fsm", "brake"], "silentAfterMs": 1500}})"),
                 "safety.json: /watchdog/services/1: unknown service 'brake'; the services are can-rx, can-tx"));
  CHECK(contains(errorOf(R"({"hazards": [], "watchdog": {"services": ["fsm", "fsm"], "silentAfterMs": 1500}})"),
                 "/watchdog/services/1: service 'fsm' is listed twice"));
  CHECK(contains(errorOf(R"({"hazards": [], "watchdog": {"services": [], "silentAfterMs": 1500}})"),
                 "/watchdog/services: must list at least one service"));
  CHECK(contains(errorOf(R"({"hazards": [], "watchdog": {"services": ["fsm"], "silentAfterMs": 0}})"),
                 "/watchdog/silentAfterMs: must be a whole number of ms above 0"));
  CHECK(contains(errorOf(R"({"hazards": [], "watchdog": {"services": ["fsm"], "silentAfterMs": 12.5}})"),
                 "/watchdog/silentAfterMs: must be a whole number of ms"));
  CHECK(contains(errorOf(R"({"hazards": [], "watchdog": {"services": ["fsm"]}})"), "/watchdog"));
  CHECK(contains(
      errorOf(R"({"hazards": [], "watchdog": {"services": ["fsm"], "silentAfterMs": 1500, "device": "watchdog"}})"),
      "/watchdog/device: must be an absolute device path"));
  CHECK(
      contains(errorOf(R"({"hazards": [], "watchdog": {"services": ["fsm"], "silentAfterMs": 1500, "restrat": true}})"),
               "restrat"));
}

TEST_CASE("a hazard gives its id, severity, goal, safe state in order, detection, FTTI and faults") {
  auto sut = safety::parseSafety(withHazard(std::string(HAZARD)), std::string(FILE_NAME));
  REQUIRE(sut);
  REQUIRE(sut->hazards.size() == 1);
  const safety::Hazard& hazard = sut->hazards[0];
  CHECK(hazard.id == "H-BAT-TIMEOUT");
  CHECK(hazard.severity == "PL d");
  CHECK(hazard.safetyGoal == "open the HV path");
  CHECK(hazard.safeState.fsmStates == std::vector<std::string>{"Battery Timeout"});
  REQUIRE(hazard.safeState.gpio.size() == 1);
  CHECK(hazard.safeState.gpio[0].line == "Cl15");
  CHECK_FALSE(hazard.safeState.gpio[0].level);
  REQUIRE(hazard.safeState.bus.size() == 1);
  CHECK(hazard.safeState.bus[0].signal == "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors");
  REQUIRE(hazard.detection.size() == 1);
  CHECK(hazard.detection[0].kind == safety::DetectionKind::ReceiveTimeout);
  CHECK(hazard.detection[0].message == "HVESSS1_PGN61590");
  CHECK(hazard.fttiMs == 4000);
  REQUIRE(hazard.faults.size() == 1);
  CHECK(hazard.faults[0].kind == safety::InjectKind::Silence);
  CHECK(hazard.faults[0].node == "VIC");
  CHECK(sut->findHazard("H-BAT-TIMEOUT") == &hazard);
  CHECK(sut->findHazard("H-OTHER") == nullptr);
}

TEST_CASE("every detection kind and fault kind reads with the target it takes") {
  const std::string hazard =
      hazardWith(R"("detection": [{"kind": "receiveTimeout", "message": "HVESSS1_PGN61590"}])",
                 R"("detection": [{"kind": "receiveTimeout", "signal": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts"},
                       {"kind": "j1939_76", "message": "HVESSS1_PGN61590"}, {"kind": "dm1", "node": "VIC"},
                       {"kind": "dtc", "fault": "hv_lost"}, {"kind": "gpioInput", "line": "ContactorFault"},
                       {"kind": "serviceWatchdog", "service": "fsm"}, {"kind": "addressLoss", "bus": "vehicle"},
                       {"kind": "statusSignal", "signal": "PDU.PDU_Tx_1.byPDU_Status"}])");
  std::string text = hazard;
  const std::string faults = R"("faults": [{"inject": "silence", "node": "VIC"},
      {"inject": "delay", "message": "HVESSS1_PGN61590", "delayMs": 200},
      {"inject": "corrupt", "message": "HVESSS1_PGN61590", "validCrc": true},
      {"inject": "freezeCounter", "message": "HVESSS1_PGN61590"}, {"inject": "replay", "message": "HVESSS1_PGN61590"},
      {"inject": "babble", "bus": "vehicle", "loadPercent": 60}, {"inject": "spoof", "message": "HVESSS1_PGN61590", "address": 240},
      {"inject": "busOff", "bus": "vehicle"}, {"inject": "addressClaim", "address": 33},
      {"inject": "kill", "service": "roudi"}, {"inject": "stop", "service": "fsm"},
      {"inject": "gpioStuck", "line": "ContactorFault", "level": 1},
      {"inject": "signal", "signal": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "value": 14},
      {"inject": "simFault", "name": "pdu"}])";
  text.replace(text.find(R"("faults": [{"inject": "silence", "node": "VIC"}])"),
               std::string_view(R"("faults": [{"inject": "silence", "node": "VIC"}])").size(), faults);
  auto sut = safety::parseSafety(text, std::string(FILE_NAME));
  REQUIRE_MESSAGE(sut, (sut ? "" : sut.error().toString()));
  const safety::Hazard& parsed = sut->hazards[0];
  REQUIRE(parsed.detection.size() == 8);
  CHECK(parsed.detection[0].signal == "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts");
  CHECK(parsed.detection[1].kind == safety::DetectionKind::J1939_76);
  CHECK(parsed.detection[2].node == "VIC");
  CHECK(parsed.detection[3].fault == "hv_lost");
  CHECK(parsed.detection[4].line == "ContactorFault");
  CHECK(parsed.detection[5].service == "fsm");
  CHECK(parsed.detection[6].bus == "vehicle");
  CHECK(parsed.detection[7].signal == "PDU.PDU_Tx_1.byPDU_Status");
  for (std::size_t i = 0; i < parsed.detection.size(); ++i) {
    CHECK(parsed.detection[i].kind == static_cast<safety::DetectionKind>(i));
  }
  CHECK(safety::detectionKindName(safety::DetectionKind::AddressLoss) == "addressLoss");
  REQUIRE(parsed.faults.size() == 14);
  for (std::size_t i = 0; i < parsed.faults.size(); ++i) {
    CHECK(parsed.faults[i].kind == static_cast<safety::InjectKind>(i));
  }
  CHECK(parsed.faults[1].delayMs == 200);
  CHECK(parsed.faults[2].validCrc == true);
  CHECK(parsed.faults[5].loadPercent == 60);
  CHECK(parsed.faults[6].address == 240);
  CHECK(parsed.faults[8].address == 33);
  CHECK(parsed.faults[8].bus.empty());
  CHECK(parsed.faults[9].service == "roudi");
  CHECK(parsed.faults[11].level == true);
  CHECK(parsed.faults[12].value == 14);
  CHECK(parsed.faults[13].name == "pdu");
  CHECK(safety::injectKindName(safety::InjectKind::AddressClaim) == "addressClaim");
}

TEST_CASE("a broken hazard is refused with the JSON path of the member and the reason") {
  CHECK(contains(errorOf(hazardWith(R"("fttiMs": 4000)", R"("fttiMs": 0)")),
                 "safety.json: /hazards/0/fttiMs: must be a whole number of ms above 0"));
  CHECK(contains(errorOf(hazardWith(R"("fttiMs": 4000)", R"("fttiMs": -5)")), "/hazards/0/fttiMs"));
  CHECK(contains(errorOf(hazardWith(R"("fttiMs": 4000,)", "")), "/hazards/0"));
  CHECK(contains(errorOf(hazardWith(R"("severity": "PL d")", R"("severity": "high")")),
                 "/hazards/0/severity: 'high' is not a severity tag"));
  CHECK(contains(errorOf(hazardWith(R"("severity": "PL d")", R"("severity": "ASIL E")")), "/hazards/0/severity"));
  CHECK(
      contains(errorOf(hazardWith(R"("id": "H-BAT-TIMEOUT")", R"("id": "H BAT")")), "/hazards/0/id: 'H BAT' must be"));
  CHECK(contains(errorOf(hazardWith(R"("safetyGoal": "open the HV path")", R"("safetyGoal": "")")),
                 "/hazards/0/safetyGoal: must not be empty"));
  CHECK(contains(errorOf(hazardWith(R"([{"kind": "receiveTimeout", "message": "HVESSS1_PGN61590"}])", "[]")),
                 "/hazards/0/detection: must name at least one detection mechanism"));
  CHECK(contains(errorOf(hazardWith(R"("kind": "receiveTimeout")", R"("kind": "timeout")")),
                 "/hazards/0/detection/0/kind: unknown detection kind 'timeout'; expected \"receiveTimeout\""));
  CHECK(contains(errorOf(hazardWith(R"("kind": "receiveTimeout")", R"("kind": "serviceWatchdog")")),
                 "/hazards/0/detection/0/message: \"serviceWatchdog\" takes no \"message\""));
  CHECK(contains(errorOf(hazardWith(R"("message": "HVESSS1_PGN61590"}])", R"("message": "A", "signal": "B"}])")),
                 "/hazards/0/detection/0/signal: give one of \"message\" and \"signal\""));
  CHECK(contains(errorOf(hazardWith(R"("level": 0)", R"("level": 2)")),
                 "/hazards/0/safeState/gpio/0/level: must be a level: 0 or 1"));
  CHECK(contains(errorOf(hazardWith(R"("fsmStates": ["Battery Timeout"])", R"("fsmStates": ["Battery Timeout", 3])")),
                 "/hazards/0/safeState/fsmStates/1: must be an FSM state name"));
  CHECK(contains(errorOf(hazardWith(R"("inject": "silence", "node": "VIC")", R"("inject": "unplug", "node": "VIC")")),
                 "/hazards/0/faults/0/inject: unknown fault 'unplug'"));
  CHECK(contains(errorOf(hazardWith(R"("inject": "silence", "node": "VIC")", R"("inject": "silence")")),
                 "/hazards/0/faults/0: \"silence\" needs \"node\" or \"message\""));
  CHECK(contains(errorOf(hazardWith(R"("inject": "silence", "node": "VIC")",
                                    R"("inject": "silence", "node": "VIC", "delayMs": 5)")),
                 "/hazards/0/faults/0/delayMs: \"silence\" takes no \"delayMs\""));
  CHECK(contains(
      errorOf(hazardWith(R"("inject": "silence", "node": "VIC")", R"("inject": "addressClaim", "address": 254)")),
      "/hazards/0/faults/0/address: must be a J1939 source address"));
  CHECK(
      contains(errorOf(hazardWith(R"("inject": "silence", "node": "VIC")", R"("inject": "stop", "service": "brake")")),
               "/hazards/0/faults/0/service: unknown process 'brake'"));
  CHECK(contains(errorOf(hazardWith(R"("inject": "silence", "node": "VIC")", R"("inject": "corrupt", "message": "X")")),
                 "/hazards/0/faults/0"));
  CHECK(contains(errorOf(hazardWith(R"("inject": "silence", "node": "VIC")",
                                    R"("inject": "babble", "bus": "vehicle", "loadPercent": 120)")),
                 "/hazards/0/faults/0/loadPercent: must be above 0 and at most 100"));
}

TEST_CASE("a safe state that names nothing is refused") {
  const std::string empty = hazardWith(
      R"({"fsmStates": ["Battery Timeout"], "gpio": [{"line": "Cl15", "level": 0}],
                "bus": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 0}]})",
      "{}");
  CHECK(contains(errorOf(empty),
                 "/hazards/0/safeState: names no FSM state, GPIO level, bus command or restarted service"));
}

TEST_CASE("two hazards with one id are refused at the second") {
  const std::string text = R"({"hazards": [)" + std::string(HAZARD) + "," + std::string(HAZARD) + "]}";
  CHECK(contains(errorOf(text), "safety.json: /hazards/1/id: hazard 'H-BAT-TIMEOUT' is defined twice"));
}

TEST_CASE("unknown keys, JSON syntax errors and a missing hazards list are refused") {
  CHECK(contains(errorOf(R"({"hazards": [], "hazzards": []})"), "hazzards"));
  CHECK(contains(errorOf(R"({"hazards": [})"), "safety.json:1:"));
  CHECK(contains(errorOf(R"({"watchdog": {"services": ["fsm"], "silentAfterMs": 100}})"), "hazards"));
  CHECK(contains(errorOf(R"([])"), "safety.json"));
}

TEST_CASE("loadSafety reads a file and names it in errors") {
  auto missing = safety::loadSafety("/nonexistent/safety.json");
  REQUIRE_FALSE(missing);
  CHECK(contains(missing.error().toString(), "/nonexistent/safety.json"));
}
