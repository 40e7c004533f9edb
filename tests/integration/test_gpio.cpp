// vcu-gpio with the simulated chip and the real vcu-fsm on the HHEA configuration, inside the
// sandbox with real LCM and a real signal table:
//   - Start: the FSM commands the Cl15 relay; vcu-gpio switches the line 2 s later (its
//     on-delay); SIGKILLed, it comes back driving the same level without a glitch; SIGTERM
//     drives the safe level; Stop switches the relay off 2 s after the command;
//   - the contactor-fault line driven high on the simulated chip (`vcu signal set
//     internal.gpio.sim.ContactorFault 1`, answered by vcu-gpio) reaches vcu-fsm (a small
//     machine watching it), which enters "Contactor Fault" and raises its fault; `vcu gpio`
//     shows the lines. (The HHEA machine's own case runs in test_hhea.cpp.)

#include <doctest/doctest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/ipc/event_bus.hpp"

namespace {

const std::string FSM = FSM_BINARY;
const std::string GPIO = GPIO_BINARY;

struct Fixture : ConfiguredStack {
  Fixture() : ConfiguredStack(copyHheaConfig(fs::temp_directory_path() / "hhea")) { openTable(); }

  harness::Process& start(const std::string& name, const std::string& binary) { return startService(name, binary); }

  /// Seconds from the relay's command to the level `level` on internal.gpio.Cl15.
  double switchDelay(double level) {
    const auto switched = waitForBus(*table, index("internal.gpio.Cl15"), level, 5s);
    REQUIRE_MESSAGE(switched, "internal.gpio.Cl15 never became " << level);
    const auto command = table->readCommand(index("internal.relay.Cl15"));
    REQUIRE(command);
    REQUIRE(command->value == level);
    return static_cast<double>(switched->timestampNs - command->timestampNs) / 1e9;
  }
};

}  // namespace

TEST_CASE("the Cl15 relay follows the state machine with its 2 s delays and a killed vcu-gpio comes back to the same output") {
  SKIP_UNLESS_ISOLATED();
  Fixture f;
  f.start("fsm", FSM);
  harness::Process& first = f.start("gpio", GPIO);
  REQUIRE(waitForBus(*f.table, f.index("internal.fsm.state"), hheaStateIndex("Standby"), 5s));
  REQUIRE(waitForBus(*f.table, f.index("internal.gpio.Cl15"), 0, 5s));

  f.set("internal.operator.StartStop", "Start");
  const double onDelay = f.switchDelay(1);
  CHECK(onDelay >= 2.0);
  CHECK(onDelay < 2.3);
  CHECK(first.waitForLine("Cl15: output on (commanded on, on-delay 2 s)", 2s));

  // SIGKILL: the table keeps the level; the restarted service requests the line at it
  const auto before = f.table->readBus(f.index("internal.gpio.Cl15"));
  REQUIRE(first.signal(SIGKILL));
  REQUIRE(first.waitForExit(5s));
  harness::Process& second = f.start("gpio", GPIO);
  CHECK(second.waitForLine("Cl15: output sim offset 17 requested, on (resumed: the level driven before the restart)", 5s));
  const auto after = f.table->readBus(f.index("internal.gpio.Cl15"));
  REQUIRE(after);
  CHECK(after->value == 1);
  CHECK(after->updates == before->updates + 1);  // one write (the restart's status), never 0

  f.set("internal.operator.StartStop", "Stop");
  const double offDelay = f.switchDelay(0);
  CHECK(offDelay >= 2.0);
  CHECK(offDelay < 2.3);

  // on again, then SIGTERM: the safe level (off) before the process ends
  f.set("internal.operator.StartStop", "Start");
  REQUIRE(f.switchDelay(1) >= 2.0);
  REQUIRE(f.sut.stop(second));
  const auto safe = f.table->readBus(f.index("internal.gpio.Cl15"));
  REQUIRE(safe);
  CHECK(safe->value == 0);
  CHECK(contains(second.output(), "Cl15: output off (safe state)"));
}

/// A machine that only watches the contactor-fault signal (the HHEA machine needs the
/// simulated vehicle to reach Ready: tests/integration/test_hhea.cpp runs that case).
constexpr const char* FAULT_WATCH = R"({"initialState": "Run", "states": [
  {"name": "Run", "transitions": [{"condition": {"key": "internal.fault.Contactor", "eq": "Fault"}, "nextState": "Contactor Fault"}]},
  {"name": "Contactor Fault", "entry": [{"raise": "contactor_fault", "severity": "error", "text": "contactor-fault input line active"}],
   "transitions": [{"condition": {"key": "internal.fault.Contactor", "eq": "Normal"}, "nextState": "Run"}]}]})";

TEST_CASE("a fault on the contactor-fault input line makes the FSM enter its fault state, and vcu gpio shows the lines") {
  SKIP_UNLESS_ISOLATED();
  Fixture f;
  {
    std::ofstream(f.config.parent_path() / "fsm.json") << FAULT_WATCH;
    // HHEA's DTC map names fault states FAULT_WATCH does not have: this machine has none
    std::ofstream(f.config.parent_path() / "diagnostics.json") << R"({"dtcs": []})";
  }
  auto events = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, "hhea");
  REQUIRE_STATUS(events);
  std::vector<ipc::FaultEvent> faults;
  REQUIRE(events->onFault([&](const ipc::FaultEvent& event) { faults.push_back(event); }));
  f.start("fsm", FSM);
  harness::Process& gpio = f.start("gpio", GPIO);
  REQUIRE(waitForBus(*f.table, f.index("internal.fsm.state"), 0, 5s));  // Run

  const auto refused = f.vcu({"signal", "set", "internal.fault.Contactor", "1"});
  CHECK(contains(refused.out + refused.err, "read from input line ContactorFault"));
  f.set("internal.gpio.sim.ContactorFault", "1");
  CHECK(waitForBus(*f.table, f.index("internal.fault.Contactor"), 1, 2s));
  CHECK(waitForBus(*f.table, f.index("internal.fsm.state"), 1, 2s));  // Contactor Fault
  CHECK(gpio.waitForLine("ContactorFault: input on -> internal.fault.Contactor = 1 (stable for 20 ms)", 2s));
  const auto end = std::chrono::steady_clock::now() + 3s;
  const auto raised = [&] {
    for (const ipc::FaultEvent& fault : faults) {
      if (fault.name == "contactor_fault" && fault.active) return true;
    }
    return false;
  };
  while (!raised() && std::chrono::steady_clock::now() < end) (void)events->handle(100ms);
  CHECK(raised());

  const auto shown = f.vcu({"gpio"});
  CHECK(shown.exitCode() == 0);
  CHECK(contains(shown.out, "Cl15"));
  CHECK(contains(shown.out, "ContactorFault"));
  CHECK(contains(shown.out, "internal.fault.Contactor"));
  CHECK(contains(shown.out, "Fault"));
  INFO(shown.out);
}
