// fsm::Engine on the HHEA catalog with signals in memory and a clock the test sets: every
// operator, nesting, `for` / `after` / `ageGt` / quality, transition order, self-transitions,
// the loop guard, relevance, resume after a restart, reload, causes and outputs.

#include <doctest/doctest.h>

#include <optional>

#include "fsm_test_support.hpp"
#include "openvcu/fsm/engine.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0 = 10'000 * MS;
constexpr std::int64_t REALTIME = 1'795'000'000'000'000'000;

struct Bench {
  fsmtest::Hhea hhea;
  fsm::MemoryAccess memory{hhea.catalog.size()};
  std::optional<fsm::Engine> engine;
  std::int64_t now{T0};

  void start(const std::string& text, fsm::StartMode mode = fsm::StartMode::Fresh) {
    auto slots = fsm::StatusSlots::find(hhea.catalog);
    REQUIRE(slots);
    engine.emplace(hhea.good(text), hhea.catalog, memory, std::move(*slots));
    engine->start(now, REALTIME + now, mode);
  }
  void bus(const char* key, double value, signals::Quality quality = signals::Quality::Valid) {
    memory.setBus(hhea.key(key), value, now, quality);
  }
  void command(const char* key, double value) { memory.setCommand(hhea.key(key), value, now, 99); }
  bool step() { return engine->step(now, REALTIME + now); }
  void at(std::int64_t t) {
    now = t;
    step();
  }
  [[nodiscard]] std::string state() const { return engine->stateName(); }
  [[nodiscard]] std::optional<double> commanded(const char* key) const {
    const signals::CommandValue& value = memory.slot(hhea.key(key)).command;
    if (value.updates == 0) return std::nullopt;
    return value.value;
  }
  [[nodiscard]] std::uint64_t commandWrites(const char* key) const { return memory.slot(hhea.key(key)).command.updates; }
  [[nodiscard]] double status(const char* key) const { return memory.slot(hhea.key(key)).bus.value; }
};

/// Two states: A -> B when `condition` holds; back to A on a FaultReset, which the way back
/// consumes (so that A and B cannot take turns forever while FaultReset stays 1: issue 18).
std::string machineAB(const std::string& condition, const std::string& extra = "") {
  return R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{"condition": )" +
         condition + extra + R"(, "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "internal.operator.FaultReset", "eq": 1},
                                   "actions": [{"signal": "internal.operator.FaultReset", "value": 0}],
                                   "nextState": "A"}]}]})";
}

}  // namespace

TEST_CASE("start enters the initial state: entry actions, the state slots, an 'initial state' transition") {
  Bench bench;
  bench.start(R"({"initialState": "Standby", "states": [
    {"name": "Standby", "entry": [{"sendGroup": "keepAlive", "on": false},
                                   {"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 1}],
     "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": "Start"}, "nextState": "Waking"}]},
    {"name": "Waking", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": "Stop"},
                                        "nextState": "Standby"}]}]})");
  CHECK(bench.state() == "Standby");
  CHECK(bench.commanded(fsmtest::KEEP_ALIVE) == 0.0);
  CHECK(bench.commanded(fsmtest::BMS_CONTROL) == 1.0);
  CHECK(bench.status("internal.fsm.state") == 0.0);
  CHECK(bench.status("internal.fsm.stateEntered") == doctest::Approx(static_cast<double>(T0) / 1e9));
  CHECK(bench.status("internal.fsm.stateSince") == doctest::Approx(static_cast<double>(REALTIME + T0) / 1e9));
  CHECK(bench.status("internal.fsm.machine") == static_cast<double>(bench.engine->machine().hash));
  REQUIRE(bench.engine->outputs().transitions.size() == 1);
  CHECK(bench.engine->outputs().transitions[0].toState == "Standby");
  CHECK(bench.engine->outputs().transitions[0].cause == "initial state");

  bench.command(fsmtest::START_STOP, 1);
  CHECK(bench.step());
  CHECK(bench.state() == "Waking");
  CHECK(bench.status("internal.fsm.state") == 1.0);
}

TEST_CASE("comparison operators, value never received, internal initial values") {
  struct Case {
    const char* condition;
    double value;
    bool expected;
  };
  const Case cases[] = {
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "eq": 50})", 50, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "eq": 50})", 51, false},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "ne": 50})", 51, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "neq": 50})", 50, false},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "lt": 50})", 49.5, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "lt": 50})", 50, false},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "le": 50})", 50, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 89})", 89.5, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 89})", 89, false},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "ge": 89})", 89, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "in": [10, 20, 30]})", 20, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "in": [10, 20, 30]})", 25, false},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "ge": 10, "le": 20})", 15, true},
      {R"({"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "ge": 10, "le": 20})", 25, false},
      {R"({"VIC.HVESSD2_PGN61585.HS_FastUpdSOC": 40})", 40, true},
  };
  for (const Case& item : cases) {
    Bench bench;
    INFO(item.condition << " with " << item.value);
    bench.start(machineAB(item.condition));
    CHECK(bench.state() == "A");  // nothing received yet: every comparison is false
    bench.bus(fsmtest::SOC, item.value);
    bench.step();
    CHECK((bench.state() == "B") == item.expected);
  }
  Bench bench;
  bench.start(machineAB(R"({"key": "PDU.PDU_Tx_1.byPDU_Status", "ne": 1})"));
  bench.step();
  CHECK(bench.state() == "A");  // ne on a signal never received is false (the thesis' PDU fault at power-on)
  Bench initial;
  initial.start(machineAB(R"({"key": "internal.operator.StartStop", "eq": "Stop"})"));
  CHECK(initial.state() == "B");  // never commanded: its configured initial value 0 = Stop
}

TEST_CASE("nested all, any and not") {
  const std::string condition = R"({"all": [{"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 20},
      {"any": [{"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 1},
               {"not": {"key": "PDU.PDU_Tx_1.byPDU_Status", "eq": 1}}]}]})";
  Bench bench;
  bench.start(machineAB(condition));
  bench.bus(fsmtest::SOC, 50);
  bench.bus(fsmtest::CONNECTION, 0);
  bench.bus(fsmtest::PDU_STATUS, 1);
  bench.step();
  CHECK(bench.state() == "A");  // all(true, any(false, not(true)))
  bench.bus(fsmtest::PDU_STATUS, 3);
  bench.step();
  CHECK(bench.state() == "B");  // not(false) makes the any true
}

TEST_CASE("for: true only after holding continuously, a break restarts the timer") {
  Bench bench;
  bench.start(machineAB(R"({"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 1, "for": "500ms"})"));
  CHECK(bench.engine->nextDeadlineNs() == fsm::NO_DEADLINE);
  bench.bus(fsmtest::CONNECTION, 1);
  bench.step();
  CHECK(bench.state() == "A");
  CHECK(bench.engine->nextDeadlineNs() == T0 + 500 * MS);
  CHECK(bench.status("internal.fsm.timer.0") == doctest::Approx(static_cast<double>(T0) / 1e9));
  bench.now = T0 + 300 * MS;
  bench.bus(fsmtest::CONNECTION, 0);
  bench.step();
  CHECK(bench.engine->nextDeadlineNs() == fsm::NO_DEADLINE);
  CHECK(bench.status("internal.fsm.timer.0") == 0.0);
  bench.now = T0 + 400 * MS;
  bench.bus(fsmtest::CONNECTION, 1);
  bench.step();
  bench.at(T0 + 899 * MS);
  CHECK(bench.state() == "A");
  bench.at(bench.engine->nextDeadlineNs());
  CHECK(bench.now == T0 + 900 * MS);
  CHECK(bench.state() == "B");
}

TEST_CASE("after: counts from the state's entry") {
  Bench bench;
  bench.start(R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{"after": "2s", "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 50},
                                   "after": "1s", "nextState": "A"}]}]})");
  CHECK(bench.engine->nextDeadlineNs() == T0 + 2'000 * MS);
  bench.at(T0 + 1'999 * MS);
  CHECK(bench.state() == "A");
  bench.at(T0 + 2'000 * MS);
  CHECK(bench.state() == "B");
  bench.now = T0 + 2'500 * MS;
  bench.bus(fsmtest::SOC, 60);
  bench.step();
  CHECK(bench.state() == "B");  // condition true, but only 0.5 s in B
  bench.at(bench.engine->nextDeadlineNs());
  CHECK(bench.now == T0 + 3'000 * MS);
  CHECK(bench.state() == "A");
}

TEST_CASE("ageGt and quality: timeouts and stale values") {
  Bench bench;
  bench.start(machineAB(R"({"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "ageGt": "3s"})"));
  CHECK(bench.state() == "B");  // never received counts as old
  Bench timeout;
  timeout.bus(fsmtest::CONNECTION, 1);
  timeout.start(machineAB(R"({"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "ageGt": "3s"})"));
  CHECK(timeout.state() == "A");
  timeout.now = T0 + 2'000 * MS;
  timeout.bus(fsmtest::CONNECTION, 1);  // the same value again: a new time stamp
  timeout.step();
  timeout.at(T0 + 4'000 * MS);          // the first deadline (T0 + 3 s) is past but the value is 2 s old
  CHECK(timeout.state() == "A");
  timeout.at(timeout.engine->nextDeadlineNs());
  CHECK(timeout.now > T0 + 5'000 * MS);
  CHECK(timeout.now <= T0 + 5'000 * MS + 1);
  CHECK(timeout.state() == "B");

  Bench stale;
  stale.start(machineAB(R"({"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "quality": ["stale", "outOfRange"]})"));
  stale.bus(fsmtest::CONNECTION, 1);
  stale.step();
  CHECK(stale.state() == "A");
  stale.memory.setQuality(stale.hhea.key(fsmtest::CONNECTION), signals::Quality::Stale);
  stale.step();
  CHECK(stale.state() == "B");
}

TEST_CASE("a transition runs exit, its actions, then entry, and the state is written last") {
  Bench bench;
  bench.start(R"({"initialState": "A", "states": [
    {"name": "A", "exit": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 1},
                           {"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupB_Contactors", "value": 1}],
     "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 50},
                      "actions": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 2},
                                  {"raise": "soc_high", "severity": "warning", "text": "SOC above 50"},
                                  {"event": "going to B"}],
                      "nextState": "B"}]},
    {"name": "B", "entry": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 3},
                            {"clear": "soc_high"}],
     "transitions": []}]})");
  bench.engine->clearOutputs();
  bench.bus(fsmtest::SOC, 60);
  bench.step();
  CHECK(bench.state() == "B");
  CHECK(bench.commanded(fsmtest::CONTACTOR_A) == 3.0);  // exit 1, action 2, entry 3
  CHECK(bench.commandWrites(fsmtest::CONTACTOR_A) == 3);
  CHECK(bench.commanded("Vehicle_Control_Unit.PDU_Rx_1.Close_GroupB_Contactors") == 1.0);
  const fsm::Outputs& outputs = bench.engine->outputs();
  REQUIRE(outputs.faults.size() == 2);
  CHECK(outputs.faults[0].name == "soc_high");
  CHECK(outputs.faults[0].active);
  CHECK(outputs.faults[0].severity == ipc::FaultSeverity::Warning);
  CHECK_FALSE(outputs.faults[1].active);
  REQUIRE(outputs.events.size() == 1);
  CHECK(outputs.events[0].text == "going to B");
  REQUIRE(outputs.transitions.size() == 1);
  CHECK(outputs.transitions[0].fromState == "A");
  CHECK(outputs.transitions[0].cause ==
        "VIC.HVESSD2_PGN61585.HS_FastUpdSOC gt 50 [VIC.HVESSD2_PGN61585.HS_FastUpdSOC = 60] (/states/0/transitions/0)");
}

TEST_CASE("self-transitions fire on the rising edge, step 6 -> 3 -> 5 at once, and never block later ones") {
  Bench bench;
  bench.start(R"({"initialState": "Drive", "states": [
    {"name": "Drive", "entry": [{"signal": "Vehicle_Control_Unit.HC1_Demands.ControlWord", "value": 6}],
     "transitions": [
       {"condition": {"key": "Vehicle_Control_Unit.HC1_Demands.ControlWord", "eq": 6},
        "actions": [{"signal": "Vehicle_Control_Unit.HC1_Demands.ControlWord", "value": 3}], "nextState": "Drive"},
       {"condition": {"key": "Vehicle_Control_Unit.HC1_Demands.ControlWord", "eq": 3},
        "actions": [{"signal": "Vehicle_Control_Unit.HC1_Demands.ControlWord", "value": 5}], "nextState": "Drive"},
       {"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 10},
        "actions": [{"event": "soc above 10"}], "nextState": "Drive"},
       {"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 90}, "nextState": "Full"}]},
    {"name": "Full", "transitions": []}]})");
  CHECK(bench.commanded(fsmtest::CONTROL_WORD) == 5.0);
  CHECK(bench.commandWrites(fsmtest::CONTROL_WORD) == 3);  // 6 (entry), 3, 5 in the start step
  CHECK(bench.engine->counters().selfTransitions == 2);
  bench.engine->clearOutputs();
  bench.bus(fsmtest::SOC, 20);
  bench.step();
  CHECK(bench.engine->outputs().events.size() == 1);
  bench.bus(fsmtest::SOC, 30);  // still above 10: no second firing
  bench.step();
  CHECK(bench.engine->outputs().events.size() == 1);
  bench.bus(fsmtest::SOC, 95);  // the held self-transition does not block the one after it
  bench.step();
  CHECK(bench.state() == "Full");
}

TEST_CASE("the loop guard stops a machine that never settles, raises fsm_loop once and waits for an input (#18)") {
  Bench bench;
  // The checker refuses A <-> B on one condition (machine_cycles.hpp); the engine must not
  // spin even on such a machine, so the cycle is closed after compiling: B -> C becomes B -> A.
  fsm::Machine machine = bench.hhea.good(R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 10}, "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 10}, "nextState": "C"}]},
    {"name": "C", "transitions": []}]})");
  machine.states[1].transitions[0].target = 0;
  auto slots = fsm::StatusSlots::find(bench.hhea.catalog);
  REQUIRE(slots);
  bench.engine.emplace(std::move(machine), bench.hhea.catalog, bench.memory, std::move(*slots));
  bench.engine->start(bench.now, REALTIME + bench.now, fsm::StartMode::Fresh);
  bench.engine->clearOutputs();

  bench.bus(fsmtest::SOC, 20);
  bench.step();
  CHECK(bench.engine->counters().loopGuards == 1);
  CHECK(bench.engine->counters().transitions == fsm::MAX_FIRINGS);
  REQUIRE(bench.engine->outputs().faults.size() == 1);
  CHECK(bench.engine->outputs().faults[0].name == "fsm_loop");
  CHECK(bench.engine->outputs().faults[0].active);
  // No deadline and no input change: the stopped machine is not evaluated again, however
  // often the engine is stepped (its own writes woke the service's thread: no spin).
  CHECK(bench.engine->nextDeadlineNs() == fsm::NO_DEADLINE);
  bench.engine->clearOutputs();
  const std::uint64_t evaluations = bench.engine->counters().evaluations;
  for (int wake = 0; wake < 100; ++wake) {
    bench.now += MS;
    CHECK_FALSE(bench.step());
  }
  CHECK(bench.engine->counters().evaluations == evaluations);
  CHECK(bench.engine->counters().transitions == fsm::MAX_FIRINGS);

  // An input change: at most MAX_FIRINGS + 1 more transitions, the fault is not raised again.
  bench.bus(fsmtest::SOC, 30);
  CHECK(bench.step());
  CHECK(bench.engine->counters().loopGuards == 2);
  CHECK(bench.engine->counters().transitions <= 2 * fsm::MAX_FIRINGS + 1);
  CHECK(bench.engine->outputs().faults.empty());
  // The input that lets it settle clears the fault.
  bench.bus(fsmtest::SOC, 5);
  CHECK(bench.step());
  REQUIRE(bench.engine->outputs().faults.size() == 1);
  CHECK(bench.engine->outputs().faults[0].name == "fsm_loop");
  CHECK_FALSE(bench.engine->outputs().faults[0].active);
  CHECK(bench.engine->counters().loopGuards == 2);
}

TEST_CASE("only changes of the current state's signals evaluate, equal commands are not rewritten") {
  Bench bench;
  bench.start(R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 10},
        "actions": [{"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 1}], "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "PDU.PDU_Tx_1.byPDU_Status", "eq": 7},
        "actions": [{"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 1}], "nextState": "C"}]},
    {"name": "C", "transitions": []}]})");
  const std::uint64_t evaluations = bench.engine->counters().evaluations;
  bench.bus(fsmtest::PDU_STATUS, 7);  // read by B only
  CHECK_FALSE(bench.step());
  bench.bus(fsmtest::SOC, 5);  // read by A, but the same... first value: a change
  CHECK(bench.step());
  bench.bus(fsmtest::SOC, 5);  // same value, new time stamp: not a change
  CHECK_FALSE(bench.step());
  CHECK(bench.engine->counters().evaluations == evaluations + 1);
  bench.bus(fsmtest::SOC, 20);
  bench.step();  // A -> B (BMS_Control 1), and B's condition already holds: B -> C (BMS_Control 1 again)
  CHECK(bench.state() == "C");
  CHECK(bench.engine->counters().transitions == 2);
  CHECK(bench.commandWrites(fsmtest::BMS_CONTROL) == 1);
}

TEST_CASE("resume after a restart: same state, entry time and for timers, entry actions not re-run") {
  const std::string text = R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": 1}, "nextState": "B"}]},
    {"name": "B", "entry": [{"signal": "Vehicle_Control_Unit.BMS.BMS_Control", "value": 0}], "transitions": [
      {"condition": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "eq": 1, "for": "1s"}, "nextState": "C"},
      {"after": "10s", "nextState": "A"}]},
    {"name": "C", "transitions": []}]})";
  Bench bench;
  bench.start(text);
  bench.command(fsmtest::START_STOP, 1);
  bench.step();
  REQUIRE(bench.state() == "B");
  bench.now = T0 + 200 * MS;
  bench.bus(fsmtest::CONNECTION, 1);
  bench.step();
  const std::uint64_t writes = bench.commandWrites(fsmtest::BMS_CONTROL);

  // "kill": a new engine on the same table
  bench.now = T0 + 700 * MS;
  bench.start(text, fsm::StartMode::Resume);
  CHECK(bench.state() == "B");
  CHECK(bench.engine->enteredNs() == T0);
  CHECK(bench.commandWrites(fsmtest::BMS_CONTROL) == writes);
  REQUIRE_FALSE(bench.engine->outputs().transitions.empty());
  CHECK(bench.engine->outputs().transitions[0].cause.find("resumed after a restart") == 0);
  CHECK(bench.engine->nextDeadlineNs() == T0 + 1'200 * MS);  // the `for` began at T0 + 200 ms
  bench.at(T0 + 1'200 * MS);
  CHECK(bench.state() == "C");

  // another file: starts fresh
  Bench other;
  other.start(text);
  other.command(fsmtest::START_STOP, 1);
  other.step();
  REQUIRE(other.state() == "B");
  other.start(text + " ", fsm::StartMode::Resume);  // whitespace only: the same machine
  CHECK(other.state() == "B");
  other.start(R"({"initialState": "A", "states": [{"name": "A", "transitions": []}, {"name": "B", "transitions": []}]})",
              fsm::StartMode::Resume);
  CHECK(other.state() == "A");
  CHECK(other.engine->outputs().transitions[0].cause.find("another FSM file") != std::string::npos);
}

TEST_CASE("replace keeps the current state by name, or refuses and keeps the old machine") {
  Bench bench;
  bench.start(machineAB(R"({"key": "internal.operator.StartStop", "eq": 1})"));
  bench.command(fsmtest::START_STOP, 1);
  bench.step();
  REQUIRE(bench.state() == "B");
  const auto refused = bench.engine->replace(bench.hhea.good(R"({"initialState": "A", "states": [
      {"name": "A", "transitions": []}]})"),
                                             bench.now, REALTIME);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("'B' does not exist") != std::string::npos);
  CHECK(bench.state() == "B");
  CHECK(bench.engine->machine().states.size() == 2);

  const auto accepted = bench.engine->replace(bench.hhea.good(R"({"initialState": "X", "states": [
      {"name": "X", "transitions": []},
      {"name": "B", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 1}, "nextState": "X"}]}]})"),
                                              bench.now, REALTIME);
  REQUIRE(accepted);
  CHECK(bench.state() == "B");
  CHECK(bench.engine->state() == 1);
  CHECK(bench.status("internal.fsm.state") == 1.0);
  bench.bus(fsmtest::SOC, 5);
  bench.step();
  CHECK(bench.state() == "X");
}

TEST_CASE("a from action commands the source's value when it runs, clamped, and nothing while the source is silent") {
  Bench bench;
  bench.start(machineAB(R"({"key": "internal.operator.StartStop", "eq": 1})", R"(, "actions": [
      {"signal": "Vehicle_Control_Unit.BMS.BMS_Max_Current", "from": "VIC.PropA_C3_PGN61184.IChLimLong"},
      {"signal": "Vehicle_Control_Unit.BMS.BMS_Max_Voltage", "from": "VIC.PropA_C3_PGN61184.UChLimLong"}])"));
  bench.bus("VIC.PropA_C3_PGN61184.IChLimLong", 42.5);  // UChLimLong never received
  bench.command(fsmtest::START_STOP, 1);
  bench.step();
  CHECK(bench.state() == "B");
  CHECK(bench.commanded("Vehicle_Control_Unit.BMS.BMS_Max_Current") == 42.5);
  CHECK_FALSE(bench.commanded("Vehicle_Control_Unit.BMS.BMS_Max_Voltage"));
  std::vector<Error> diagnostics;
  CHECK_FALSE(bench.hhea.compile(machineAB(R"({"key": "internal.operator.StartStop", "eq": 1})",
                                           R"(, "actions": [{"signal": "Vehicle_Control_Unit.BMS.BMS_Max_Current",
                                               "from": "VIC.PropA_C3_PGN61184.IChLimLng", "value": 3}])"),
                                 &diagnostics));
  CHECK(fsmtest::listing(diagnostics).find("not both") != std::string::npos);
  CHECK(fsmtest::listing(diagnostics).find("did you mean") != std::string::npos);
}
