// Receive supervision on the whole headless HHEA stack in the sandbox (iox-roudi, vcu-can-rx,
// vcu-can-tx, vcu-fsm, vcu-gpio on the simulated chip, vcu-ecu-sim), seen through the LCM
// fault events that vcu-web, the HMI and `vcu top` list:
//   - at rest (Standby, Cl15 off, the VIC asleep) no receive-timeout fault is raised, also
//     after the longest receive timeout of the VIC's messages (3 s) has passed;
//   - after a start and a normal stop the sleeping VIC leaves no active fault either;
//   - a VIC that is expected (Cl15 on) and goes silent still raises rx_timeout within its
//     300 ms timeout plus one tick (config/hhea/receive.json, "expectedWhen").

#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/ipc/event_bus.hpp"

namespace {

using namespace std::chrono_literals;
using namespace openvcu;
using namespace openvcu::integration;
namespace fs = std::filesystem;

const std::string RX_TIMEOUT = "rx_timeout.";
const std::string BATTERY_STATUS_FAULT = "rx_timeout.vehicle.HVESSS1_PGN61590";
/// The longest receive timeout of the VIC's cyclic messages: HVESSD3 and RQST_VIC, 3 x 1000 ms.
constexpr auto LONGEST_VIC_TIMEOUT = 3000ms;
/// HVESSS1's 300 ms timeout, can-rx's look at the wake condition (at most 250 ms), margin for a loaded host.
constexpr auto SILENCE_DETECTION_BOUND = 1500ms;

struct RestStack : ConfiguredStack {
  std::optional<ipc::EventBus> events;
  std::vector<ipc::FaultEvent> faults;

  RestStack() : ConfiguredStack(copyHheaConfig(fs::temp_directory_path() / "hhea")) {
    REQUIRE_STATUS(sut.startRoudi());
    // The event bus first: every fault can-rx raises from its start on is seen.
    auto bus = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, "hhea");
    REQUIRE_STATUS(bus);
    events.emplace(std::move(*bus));
    REQUIRE(events->onFault([this](const ipc::FaultEvent& event) { faults.push_back(event); }));
    // The simulated vehicle first, as on a machine whose always-powered nodes run before the
    // VCU boots: a node that starts after vcu-can-rx is "never received" for a moment.
    const std::vector<std::pair<std::string, std::string>> services{{"ecu-sim", ECU_SIM_BINARY},
                                                                    {"can-rx", CAN_RX_BINARY},
                                                                    {"can-tx", CAN_TX_BINARY},
                                                                    {"fsm", FSM_BINARY},
                                                                    {"gpio", GPIO_BINARY}};
    for (const auto& [name, binary] : services) startService(name, binary);
    openTable();
    REQUIRE(state("Standby", 5s));
  }

  /// Handles LCM events for `duration` (no fixed sleep: the event bus waits).
  void listen(std::chrono::milliseconds duration) {
    const auto end = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < end) (void)events->handle(50ms);
  }
  /// The receive-timeout faults whose last event is active, with their texts.
  std::map<std::string, std::string> activeReceiveFaults() const {
    std::map<std::string, std::string> active;
    for (const ipc::FaultEvent& event : faults) {
      if (event.name.rfind(RX_TIMEOUT, 0) != 0) continue;
      if (event.active) {
        active[event.name] = event.text;
      } else {
        active.erase(event.name);
      }
    }
    return active;
  }
  static std::string describe(const std::map<std::string, std::string>& active) {
    std::string text;
    for (const auto& [name, reason] : active) text += name + ": " + reason + "\n";
    return text;
  }
  bool sawActive(const std::string& name, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      for (const ipc::FaultEvent& event : faults) {
        if (event.name == name && event.active) return true;
      }
      if (std::chrono::steady_clock::now() >= end) return false;
      (void)events->handle(50ms);
    }
  }
  bool state(const std::string& name, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    const signals::SignalIndex slot = index("internal.fsm.state");
    const double wanted = hheaStateIndex(name);
    std::uint32_t epoch = table->changeEpoch();
    for (;;) {
      if (const auto read = table->readBus(slot); read && read->updates > 0 && read->value == wanted) return true;
      const auto left = end - std::chrono::steady_clock::now();
      if (left <= 0ns) return false;
      epoch = table->waitForChange(epoch, std::chrono::duration_cast<std::chrono::nanoseconds>(left));
    }
  }
};

}  // namespace

TEST_CASE("the HHEA stack at rest raises no receive-timeout fault for the sleeping battery") {
  SKIP_UNLESS_ISOLATED();
  RestStack s;
  s.listen(LONGEST_VIC_TIMEOUT + 500ms);
  const auto active = s.activeReceiveFaults();
  CHECK_MESSAGE(active.empty(), RestStack::describe(active));
  // Not even for a moment for the VIC's messages. (A node that is awake may still flicker
  // when a loaded host delays a 10 ms frame past its 30 ms timeout: that is supervision.)
  std::vector<std::string> vicFaults;
  for (const dbc::Message& message : s.vehicle->database.messages) {
    if (config::sentBy(message, "VIC")) vicFaults.push_back("rx_timeout.vehicle." + message.name);
  }
  REQUIRE(vicFaults.size() >= 6);
  for (const ipc::FaultEvent& event : s.faults) {
    const bool vic = std::find(vicFaults.begin(), vicFaults.end(), event.name) != vicFaults.end();
    CHECK_MESSAGE(!vic, event.name << ": " << event.text);
  }
}

TEST_CASE("a woken battery that goes silent raises its receive timeout, and after a normal stop none stays active") {
  SKIP_UNLESS_ISOLATED();
  RestStack s;
  s.set("internal.operator.StartStop", "Start");
  REQUIRE(s.state("Ready", 8s));
  CHECK_MESSAGE(s.activeReceiveFaults().empty(), RestStack::describe(s.activeReceiveFaults()));

  // A normal stop: Cl15 off, the VIC sleeps; nothing stays active at rest.
  s.set("internal.operator.StartStop", "Stop");
  REQUIRE(s.state("Standby", 8s));
  s.listen(LONGEST_VIC_TIMEOUT + 500ms);
  CHECK_MESSAGE(s.activeReceiveFaults().empty(), RestStack::describe(s.activeReceiveFaults()));

  // Awake again, then the VIC goes silent while it is expected: the fault still fires.
  s.set("internal.operator.StartStop", "Start");
  REQUIRE(s.state("Ready", 8s));
  s.listen(500ms);
  CHECK_MESSAGE(s.activeReceiveFaults().empty(), RestStack::describe(s.activeReceiveFaults()));
  const auto silenced = s.vcu({"sim", "fault", "silent.VIC", "on"});
  REQUIRE_MESSAGE(contains(silenced.out, "accepted"), silenced.describe());
  CHECK(s.sawActive(BATTERY_STATUS_FAULT, SILENCE_DETECTION_BOUND));
  (void)s.vcu({"sim", "fault", "silent.VIC", "off"});
}
