// fsm::loadMachine / parseMachine: the thesis' listing and its defect report, the thesis'
// format, every check (errors and warnings with their JSON paths) and the compiled form.

#include <doctest/doctest.h>

#include "fsm_test_support.hpp"

using namespace openvcu;
using fsmtest::count;
using fsmtest::listing;

namespace {

const std::string THESIS = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/fsm/thesis_listing_c2.json";

/// A one-state machine around one transition (JSON text of the transition).
std::string oneTransition(const std::string& transition, const std::string& extraStates = "") {
  return R"({"initialState": "A", "states": [{"name": "A", "transitions": [)" + transition + R"(]},
            {"name": "B", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": 0},
                                           "nextState": "A"}]})" +
         extraStates + "]}";
}

}  // namespace

TEST_CASE("the thesis' listing C.2 gives a precise defect report") {
  const fsmtest::Hhea hhea;
  const std::vector<Error> diagnostics = fsm::checkMachine(THESIS, hhea.vehicle, hhea.catalog);
  INFO(listing(diagnostics));
  std::size_t errors = 0;
  for (const Error& diagnostic : diagnostics) errors += diagnostic.severity == Severity::Error ? 1 : 0;
  CHECK(errors == 12);
  // the initial state that does not exist
  CHECK(count(diagnostics, Severity::Error, "/initialState", "initial state 'On Boot' is not defined") == 1);
  // the typos, each with the key that was meant
  CHECK(count(diagnostics, Severity::Error, "/states/4/transitions/1/condition/VIC.HVSS1_PGN61590.HS_HiUBusCnctnSts",
              "did you mean 'VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts'") == 1);
  CHECK(count(diagnostics, Severity::Error, "/states/1/transitions/7/actions/0/signal",
              "unknown signal 'Vehilce_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors' (did you mean "
              "'Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors'?)") == 1);
  CHECK(count(diagnostics, Severity::Error, "/states/1/transitions/8/actions/0/signal", "Vehilce_Control_Unit") == 1);
  // the _Rx1 keys the DBC does not have
  CHECK(count(diagnostics, Severity::Error,
              "/states/0/transitions/0/condition/Vehicle_Control_Unit.HVESSC1_PGN6912_Rx1.HS_OperConsent_Rx1",
              "did you mean 'Vehicle_Control_Unit.HVESSC1_PGN6912.HS_OperConsent'") == 1);
  // the all-list asking every InverterStatus to be 1 and 13 at once
  CHECK(count(diagnostics, Severity::Error, "/states/1/transitions/0/condition/all", "can never be true") == 4);
  CHECK(count(diagnostics, Severity::Error, "/states/1/transitions/0/condition/all",
              "HVLP_SA71.HS2_Status_Feedback.InverterStatus eq 1, HVLP_SA71.HS2_Status_Feedback.InverterStatus eq 13") == 1);
  // the next state nobody defined
  CHECK(count(diagnostics, Severity::Error, "/states/3/transitions/7/nextState",
              "next state 'OBC Charger Ready' is not defined") == 1);
  // the key repeated four times where four inverters were meant
  CHECK(count(diagnostics, Severity::Warning, "/states/3/transitions/0/condition/all/1",
              "the same condition 4 times: 'Vehicle_Control_Unit.HC1_Demands_2.ControlWord eq 6'") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/3/transitions/1/condition/all/1", "the same condition 4 times") == 1);
  // the empty condition and the empty actions
  CHECK(count(diagnostics, Severity::Warning, "/states/1/transitions/8/condition", "always true") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/1/transitions/0/actions/0", "empty action") == 1);
  // the misspelt state nothing leads to
  CHECK(count(diagnostics, Severity::Warning, "/states/0", "no transition leads to state 'VCU Initilization'") == 1);
}

TEST_CASE("the thesis' format without its typos is accepted unchanged") {
  const fsmtest::Hhea hhea;
  const std::string text = R"({
    "initialState": "Start",
    "states": [
      {"name": "Start", "transitions": [
        {"condition": {"VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts": 14}, "actions": [{ }], "nextState": "Battery Fault"},
        {"condition": {"any": [{"key": "PDU.PDU_Tx_1.byPDU_Status", "ne": 1}]}, "actions": [{ }], "nextState": "Stop"},
        {"condition": {"all": [{"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 89},
                               {"key": "Vehicle_Control_Unit.BMS.BMS_Control", "eq": 0}]},
         "actions": [{"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 1}], "nextState": "Start"},
        {"condition": {"any": [{"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "in": [2, 3]},
                               {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "neq": 0},
                               {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "le": 10},
                               {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "ge": 95},
                               {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "lt": 5}]},
         "actions": [], "nextState": "Stop"}
      ]},
      {"name": "Battery Fault", "transitions": [
        {"condition": {"all": [{"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "ne": 14}]}, "actions": [{ }],
         "nextState": "Start"}]},
      {"name": "Stop", "transitions": []}
    ]})";
  std::vector<Error> diagnostics;
  auto machine = hhea.compile(text, &diagnostics);
  REQUIRE_MESSAGE(machine, listing(diagnostics));
  CHECK(machine->states.size() == 3);
  CHECK(machine->states[0].transitions.size() == 4);
  CHECK(machine->states[0].transitions[2].target == 0);
  CHECK(machine->initial == 0);
}

TEST_CASE("compiled: keys are table indices, value names are numbers, send groups are their signal") {
  const fsmtest::Hhea hhea;
  const fsm::Machine machine = hhea.good(R"({"initialState": "A", "states": [
      {"name": "A", "entry": [{"sendGroup": "keepAlive", "on": true}], "transitions": [
        {"condition": {"key": "internal.operator.StartStop", "eq": "Start"},
         "actions": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 1},
                     {"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 1}],
         "nextState": "B"}]},
      {"name": "B", "transitions": [
        {"condition": {"all": [{"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 1},
                               {"key": "Vehicle_Control_Unit.BMS.BMS_Control", "eq": 0}]}, "nextState": "A"}]}]})");
  REQUIRE(machine.states[0].entry.size() == 1);
  CHECK(machine.states[0].entry[0].kind == fsm::ActionKind::SetSignal);
  CHECK(machine.states[0].entry[0].signal == hhea.key(fsmtest::KEEP_ALIVE));
  CHECK(machine.states[0].entry[0].value == 1.0);
  const fsm::Transition& toB = machine.states[0].transitions[0];
  CHECK(toB.target == 1);
  const fsm::ConditionNode& start = machine.nodes[toB.condition];
  CHECK(start.kind == fsm::NodeKind::Compare);
  CHECK(start.value == 1.0);  // "Start" from the value table
  const fsm::SignalRef& startStop = machine.signals[start.signal];
  CHECK(startStop.index == hhea.key(fsmtest::START_STOP));
  CHECK(startStop.plane == fsm::ReadPlane::Command);
  CHECK(startStop.initial == 0.0);
  CHECK(toB.actions[0].signal == hhea.key(fsmtest::CONTACTOR_A));
  for (const fsm::SignalRef& ref : machine.signals) {
    const std::string& key = hhea.catalog[ref.index].key;
    if (key == fsmtest::CONNECTION) CHECK(ref.plane == fsm::ReadPlane::Bus);           // received
    if (key == fsmtest::BMS_CONTROL) CHECK(ref.plane == fsm::ReadPlane::Command);      // transmitted
  }
  CHECK(machine.states[1].signals.size() == 2);
}

TEST_CASE("errors name the JSON path and the reason") {
  const fsmtest::Hhea hhea;
  struct Case {
    std::string text;
    std::string path;
    std::string part;
  };
  const std::vector<Case> cases = {
      {R"({"initialState": "A", "stats": [], "states": [{"name": "A"}]})", "/stats", "did you mean 'states'"},
      {R"({"initialState": "A", "states": [{"name": "A"}, {"name": "A"}]})", "/states/1/name", "defined twice"},
      {oneTransition(R"({"condition": {}})"), "/states/0/transitions/0/nextState", "missing"},
      {oneTransition(R"({"nextState": "B"})"), "/states/0/transitions/0/condition", "a condition or an after"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "eq": 1}, "nextState": "C"})"),
       "/states/0/transitions/0/nextState", "next state 'C' is not defined"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "eq": 1}, "nextState": "b"})"),
       "/states/0/transitions/0/nextState", "did you mean 'B'"},
      {oneTransition(R"({"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "eq": 1},
          "actions": [{"signal": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "value": 1}], "nextState": "B"})"),
       "/states/0/transitions/0/actions/0/signal", "is not transmitted by Vehicle_Control_Unit"},
      {oneTransition(R"({"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "eq": 1},
          "actions": [{"signal": "internal.fsm.state", "value": 1}], "nextState": "B"})"),
       "/states/0/transitions/0/actions/0/signal", "status the stack reports"},
      {oneTransition(R"({"condition": {"key": "internal.fault.Contactor", "eq": "Fault"},
          "actions": [{"signal": "internal.fault.Contactor", "value": 0}], "nextState": "B"})"),
       "/states/0/transitions/0/actions/0/signal", "read from GPIO input line ContactorFault"},
      {oneTransition(R"({"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "eq": 1},
          "actions": [{"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 2}], "nextState": "B"})"),
       "/states/0/transitions/0/actions/0/value", "outside Vehicle_Control_Unit.BMS.BMS_Control's range [0, 1]"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "eq": "Strat"}, "nextState": "B"})"),
       "/states/0/transitions/0/condition/eq", "did you mean 'Start'"},
      {oneTransition(R"({"condition": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 16}, "nextState": "B"})"),
       "/states/0/transitions/0/condition/eq", "never equal"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "eq": 1, "for": 2}, "nextState": "B"})"),
       "/states/0/transitions/0/condition/for", "with a unit"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "eq": 1}, "after": "2 s",
          "nextState": "B"})"),
       "/states/0/transitions/0/after", "positive duration"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "eq": 1},
          "actions": [{"sendGroup": "keepAlve", "on": true}], "nextState": "B"})"),
       "/states/0/transitions/0/actions/0/sendGroup", "did you mean 'keepAlive'"},
      {oneTransition(R"({"condition": {"all": [{"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 50},
          {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "lt": 30}]}, "nextState": "B"})"),
       "/states/0/transitions/0/condition/all", "can never be true"},
      {oneTransition(R"({"condition": {"all": [{"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 1},
          {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "ne": 1}]}, "nextState": "B"})"),
       "/states/0/transitions/0/condition/all", "can never be true"},
      {oneTransition(R"({"condition": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 1, "in": [2, 3]},
          "nextState": "B"})"),
       "/states/0/transitions/0/condition", "can never be true"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "quality": "fresh"}, "nextState": "B"})"),
       "/states/0/transitions/0/condition/quality", "expected valid, stale, neverReceived or outOfRange"},
      {oneTransition(R"({"condition": {"signal": "internal.operator.StartStop", "eq": 1}, "nextState": "B"})"),
       "/states/0/transitions/0/condition", "needs \"key\""},
      {oneTransition(R"({"condition": {"all": [], "any": []}, "nextState": "B"})"), "/states/0/transitions/0/condition",
       "one of all, any and not"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop"}, "nextState": "B"})"),
       "/states/0/transitions/0/condition", "no operator"},
      {oneTransition(R"({"condition": {"key": "internal.operator.StartStop", "eq": 1},
          "actions": [{"singal": "x"}], "nextState": "B"})"),
       "/states/0/transitions/0/actions/0", "did you mean 'signal'"},
  };
  for (const Case& item : cases) {
    std::vector<Error> diagnostics;
    const auto result = hhea.compile(item.text, &diagnostics);
    INFO(item.text);
    INFO(listing(diagnostics));
    CHECK_FALSE(result);
    CHECK(count(diagnostics, Severity::Error, item.path, item.part) == 1);
  }
}

TEST_CASE("JSON syntax errors have line and column") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile("{\n  \"initialState\": \"A\",\n  \"states\": [,]\n}", &diagnostics);
  REQUIRE_FALSE(result);
  CHECK(result.error().location.line == 3);
  CHECK(result.error().location.column > 0);
}

TEST_CASE("warnings: unreachable, shadowed, repeated, self-transitions doing nothing, thresholds outside the range") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(R"({"initialState": "A", "states": [
      {"name": "A", "transitions": [
        {"condition": {"key": "internal.operator.StartStop", "eq": 1}, "nextState": "A"},
        {"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 150}, "nextState": "B"},
        {"condition": {}, "actions": [{"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 1},
                                       {"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 0}],
         "nextState": "B"},
        {"condition": {"key": "internal.operator.StartStop", "eq": 0}, "nextState": "B"}]},
      {"name": "B", "transitions": [
        {"condition": {"any": [{"key": "internal.operator.StartStop", "eq": 0},
                               {"key": "internal.operator.StartStop", "eq": 0}]}, "after": "1s", "nextState": "A"},
        {"condition": {"any": [{"key": "internal.operator.StartStop", "eq": 0},
                               {"key": "internal.operator.StartStop", "eq": 0}]}, "after": "1s", "nextState": "A"}]},
      {"name": "Orphan", "transitions": []}]})",
                                   &diagnostics);
  INFO(listing(diagnostics));
  REQUIRE(result);  // warnings only
  CHECK(count(diagnostics, Severity::Warning, "/states/0/transitions/0", "returns to its own state 'A' and does nothing") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/0/transitions/1/condition/gt", "outside") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/0/transitions/2/condition", "always true") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/0/transitions/2/actions/1", "set twice") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/0/transitions/3", "never taken: an earlier transition") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/1/transitions/0/condition/any/1", "the same condition 2 times") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/1/transitions/1", "never taken: same condition as") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/states/2", "unreachable from the initial state 'A'") == 1);
}

TEST_CASE("a missing file is an error naming it") {
  const fsmtest::Hhea hhea;
  const auto result = fsm::loadMachine("/nonexistent/fsm.json", hhea.vehicle, hhea.catalog);
  REQUIRE_FALSE(result);
  CHECK(result.error().location.file == "/nonexistent/fsm.json");
  CHECK(result.error().message.find("cannot read") != std::string::npos);
}
