// vcu-gpio's dead-man switch end to end, inside the sandbox with the simulated chip, the real
// vcu-fsm and vcu-gpio on the HHEA configuration (real signal table and LCM): the FSM commands
// the Cl15 relay on, is then frozen with SIGSTOP (a hung service: it neither exits nor beats),
// and vcu-gpio drives Cl15 to its safe level within the writer timeout (schedule.json
// "writers", the one vcu-can-tx uses) plus one 100 ms tick, raising the critical fault
// `writer_lost.fsm`; after SIGCONT the fault clears and Cl15 follows the FSM's command again,
// after its on-delay counted from the writer's return.

#include <doctest/doctest.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/ipc/event_bus.hpp"

namespace {

const std::string FSM = FSM_BINARY;
const std::string GPIO = GPIO_BINARY;

constexpr std::int64_t MS = 1'000'000;
/// config/hhea/schedule.json: "writers": [{"service": "fsm", "timeoutMs": 1500}]
constexpr std::int64_t WRITER_TIMEOUT_NS = 1'500 * MS;
/// The bound the task sets: the timeout plus one 100 ms tick of a periodic watcher.
constexpr std::int64_t TICK_NS = 100 * MS;
/// config/hhea/gpio.json: Cl15 "onDelay": "2s".
constexpr std::int64_t ON_DELAY_NS = 2'000 * MS;

struct Fixture : ConfiguredStack {
  std::optional<ipc::EventBus> events;
  std::vector<ipc::FaultEvent> faults;

  Fixture() : ConfiguredStack(copyHheaConfig(fs::temp_directory_path() / "hhea")) {
    auto opened = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, "hhea");
    REQUIRE_STATUS(opened);
    events.emplace(std::move(*opened));
    REQUIRE(events->onFault([this](const ipc::FaultEvent& event) { faults.push_back(event); }));
  }

  /// The event `writer_lost.fsm` from vcu-gpio with `active`, waited for up to `timeout`.
  std::optional<ipc::FaultEvent> waitForFault(bool active, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      for (const ipc::FaultEvent& fault : faults) {
        if (fault.name == "writer_lost.fsm" && fault.source == "vcu-gpio" && fault.active == active) return fault;
      }
      if (std::chrono::steady_clock::now() >= end) return std::nullopt;
      (void)events->handle(50ms);
    }
  }
};

}  // namespace

TEST_CASE("a hung vcu-fsm drives Cl15 to its safe level within the writer timeout and it follows again once back") {
  SKIP_UNLESS_ISOLATED();
  Fixture f;
  harness::Process& fsm = f.startService("fsm", FSM);
  f.openTable();
  harness::Process& gpio = f.startService("gpio", GPIO);
  CHECK(gpio.waitForLine("watching writer fsm (timeout 1500 ms)", 2s));
  const signals::SignalIndex cl15 = f.index("internal.gpio.Cl15");
  const signals::SignalIndex heartbeat = f.index("internal.service.fsm.heartbeat");
  REQUIRE(waitForBus(*f.table, f.index("internal.fsm.state"), hheaStateIndex("Standby"), 5s));

  f.set("internal.operator.StartStop", "Start");  // Waking: Cl15 commanded on for up to 10 s
  REQUIRE(waitForBus(*f.table, cl15, 1, 5s));

  REQUIRE(fsm.signal(SIGSTOP));
  const std::int64_t stoppedNs = clock::monotonicNs();
  const auto lastBeat = f.table->readBus(heartbeat);
  REQUIRE(lastBeat);
  REQUIRE(lastBeat->updates > 0);

  const auto safe = waitForBus(*f.table, cl15, 0, std::chrono::nanoseconds(WRITER_TIMEOUT_NS + 2'000 * MS));
  REQUIRE_MESSAGE(safe, "Cl15 stayed on with vcu-fsm stopped");
  const std::int64_t sinceBeatNs = safe->timestampNs - lastBeat->timestampNs;
  const std::int64_t sinceStopNs = safe->timestampNs - stoppedNs;
  std::printf("Cl15 at its safe level %.1f ms after vcu-fsm's last heartbeat, %.1f ms after SIGSTOP\n",
              static_cast<double>(sinceBeatNs) / 1e6, static_cast<double>(sinceStopNs) / 1e6);
  CHECK(sinceBeatNs > WRITER_TIMEOUT_NS);  // never before the writer counts as lost
  CHECK(sinceBeatNs <= WRITER_TIMEOUT_NS + TICK_NS);
  CHECK(gpio.waitForLine("Cl15: output off (safe level: writer fsm lost)", 1s));
  const auto raised = f.waitForFault(true, 2s);
  REQUIRE_MESSAGE(raised, "no writer_lost.fsm from vcu-gpio");
  CHECK(raised->severity == ipc::FaultSeverity::Critical);
  CHECK(contains(raised->text, "no heartbeat from fsm for 1500 ms"));
  // the command is still "on": the safe level holds while the writer is lost
  const auto command = f.table->readCommand(f.index("internal.relay.Cl15"));
  REQUIRE(command);
  CHECK(command->value == 1);

  const std::int64_t continuedNs = clock::monotonicNs();
  REQUIRE(fsm.signal(SIGCONT));
  const auto cleared = f.waitForFault(false, 3s);
  CHECK_MESSAGE(cleared, "writer_lost.fsm never cleared after SIGCONT");
  const auto back = waitForBus(*f.table, f.index("internal.gpio.Cl15"), 1, 5s);
  REQUIRE_MESSAGE(back, "Cl15 did not follow the command again once vcu-fsm was back");
  const auto beatAgain = f.table->readBus(heartbeat);
  REQUIRE(beatAgain);
  REQUIRE(beatAgain->updates > lastBeat->updates);
  // the on-delay counts from the writer's return (its first beat after SIGCONT), not from
  // the command's time stamp (older than the delay: it would switch at once)
  std::printf("Cl15 on again %.1f ms after SIGCONT\n", static_cast<double>(back->timestampNs - continuedNs) / 1e6);
  CHECK(back->timestampNs - continuedNs >= ON_DELAY_NS);
  CHECK(gpio.waitForLine("writer fsm back: outputs follow their commands", 1s));
}
