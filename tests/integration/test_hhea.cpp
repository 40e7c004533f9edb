// The thesis' sequences on the whole headless HHEA stack in the sandbox: iox-roudi,
// vcu-can-rx, vcu-can-tx, vcu-fsm, vcu-gpio (simulated chip) and vcu-ecu-sim (the simulated
// vehicle), driven like an operator (`vcu signal set internal.operator.*`, `vcu sim fault`)
// and observed through the signal table (what can-rx decoded, what the FSM and gpio wrote)
// and LCM fault events:
//   - battery start and shutdown, AC and DC charging, charging stopped above SOC 89 %;
//   - every injected fault -> its fault state -> Ready again when cleared and reset;
//   - the HIL table 5.1: low SOC, contactor-fault line, CAN timeout, relay in the run state;
//   - J1939-76 negative case: the simulated VIC refuses the pairs and says why.

#include <doctest/doctest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/ipc/event_bus.hpp"

namespace {

const std::string CONNECTION = "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts";
const std::string SOC = "VIC.HVESSD2_PGN61585.HS_FastUpdSOC";
const char* const INVERTERS[] = {"HVLP_SA71.HS2_Status_Feedback.InverterStatus",
                                 "HVLP_SA72.HS2_Status_Feedback_2.InverterStatus",
                                 "HVLP_SA73.HS2_Status_Feedback_3.InverterStatus",
                                 "HVLP_SA74.HS2_Status_Feedback_4.InverterStatus"};

struct Stack : ConfiguredStack {
  std::optional<ipc::EventBus> events;
  std::vector<ipc::FaultEvent> faults;

  Stack() : ConfiguredStack(copyHheaConfig(fs::temp_directory_path() / "hhea")) {
    REQUIRE_STATUS(sut.startRoudi());
    for (const auto& [name, binary] : std::vector<std::pair<std::string, std::string>>{
             {"can-rx", CAN_RX_BINARY}, {"can-tx", CAN_TX_BINARY}, {"fsm", FSM_BINARY}, {"gpio", GPIO_BINARY},
             {"ecu-sim", ECU_SIM_BINARY}}) {
      startService(name, binary);
    }
    openTable();
    auto bus = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, "hhea");
    REQUIRE_STATUS(bus);
    events.emplace(std::move(*bus));
    REQUIRE(events->onFault([this](const ipc::FaultEvent& event) { faults.push_back(event); }));
    REQUIRE(state("Standby", 5s));
  }

  void fault(const std::string& name, bool on) {
    const auto result = vcu({"sim", "fault", name, on ? "on" : "off"});
    REQUIRE_MESSAGE(contains(result.out, "accepted"), result.describe());
  }
  /// The value the stack sees: the command (override first) when there is one, else the bus plane.
  std::optional<double> value(const std::string& key) const {
    const auto slot = table->read(index(key));
    if (!slot) return std::nullopt;
    if (const auto command = signals::effectiveCommand(*slot)) return command->value;
    if (slot->bus.updates > 0) return slot->bus.value;
    return std::nullopt;
  }
  /// Waits (table change futex) until `test` holds for `key`'s value.
  bool until(const std::string& key, const std::function<bool(double)>& test, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    std::uint32_t epoch = table->changeEpoch();
    for (;;) {
      if (const auto current = value(key); current && test(*current)) return true;
      const auto left = end - std::chrono::steady_clock::now();
      if (left <= 0ns) return false;
      epoch = table->waitForChange(epoch, std::chrono::duration_cast<std::chrono::nanoseconds>(left));
    }
  }
  bool equals(const std::string& key, double expected, std::chrono::milliseconds timeout) {
    return until(key, [expected](double v) { return v == expected; }, timeout);
  }
  bool state(const std::string& name, std::chrono::milliseconds timeout) {
    return equals("internal.fsm.state", hheaStateIndex(name), timeout);
  }
  std::string stateNow() {
    const auto current = value("internal.fsm.state");
    std::ifstream in(fs::path(OPENVCU_SOURCE_DIR) / "config" / "hhea" / "fsm.json");
    const nlohmann::json machine = nlohmann::json::parse(in);
    if (!current) return "?";
    return machine["states"][static_cast<std::size_t>(*current)]["name"].get<std::string>();
  }
  bool sawFault(const std::string& name, const std::string& textPart, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      while (events->handle(0ms) == ipc::HandleResult::Handled) {
      }
      for (const ipc::FaultEvent& event : faults) {
        if (event.name == name && event.active && contains(event.text, textPart)) return true;
      }
      if (std::chrono::steady_clock::now() >= end) return false;
      (void)events->handle(100ms);
    }
  }
  /// Start, then Ready with the battery awake and the relay on.
  void start() {
    set("internal.operator.StartStop", "Start");
    REQUIRE_MESSAGE(state("Ready", 8s), stateNow());
  }
};

}  // namespace

TEST_CASE("battery start: keep-alive, Cl15, Connect Driving, connected, contactors, inverters 6-3-5, and the shutdown in reverse") {
  SKIP_UNLESS_ISOLATED();
  Stack s;
  s.set("internal.operator.StartStop", "Start");
  REQUIRE(s.state("Waking", 3s));
  CHECK(s.equals("internal.tx.keepAlive", 1, 2s));
  CHECK(s.equals("internal.gpio.Cl15", 1, 4s));  // 2 s on-delay; the VIC wakes with it
  CHECK(s.equals(CONNECTION, 0, 3s));              // "Awaiting HV Req"
  REQUIRE_MESSAGE(s.state("Ready", 5s), s.stateNow());

  s.set("internal.operator.ConnectDriving", "1");
  CHECK(s.equals("Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay", 3, 2s));
  REQUIRE_MESSAGE(s.state("Driving", 5s), s.stateNow());
  CHECK(s.equals(CONNECTION, 1, 2s));
  CHECK(s.equals("PDU.PDU_Tx_1.GroupA_Contactors_State", 1, 2s));
  CHECK(s.equals("PDU.PDU_Tx_1.GroupB_Contactors_State", 1, 2s));
  for (const char* inverter : INVERTERS) CHECK_MESSAGE(s.equals(inverter, 10, 5s), inverter);  // enabled
  CHECK(s.equals("Vehicle_Control_Unit.HC1_Demands.ControlWord", 5, 2s));
  CHECK(s.until("VIC.HVESSD1_PGN61584.HS_I", [](double amps) { return amps > 100; }, 3s));  // the load

  s.set("internal.operator.ConnectDriving", "0");
  CHECK(s.state("Disconnecting", 3s));
  CHECK_MESSAGE(s.state("Ready", 5s), s.stateNow());
  CHECK(s.equals(CONNECTION, 0, 2s));
  CHECK(s.equals("PDU.PDU_Tx_1.GroupA_Contactors_State", 0, 2s));
  for (const char* inverter : INVERTERS) CHECK(s.equals(inverter, 8, 2s));

  s.set("internal.operator.StartStop", "Stop");
  CHECK(s.state("Shutting Down", 3s));
  CHECK(s.equals("internal.gpio.Cl15", 0, 5s));  // 2 s off-delay
  CHECK(s.state("Standby", 5s));
  CHECK(s.equals("internal.tx.keepAlive", 0, 2s));
}

TEST_CASE("AC charging: the charger follows BMS_Control and its limits and stops above SOC 89 %, DC charging connects in mode 5") {
  SKIP_UNLESS_ISOLATED();
  Stack s;
  s.start();
  s.set("internal.operator.ACCharging", "1");
  REQUIRE_MESSAGE(s.state("Charging", 5s), s.stateNow());
  CHECK(s.equals(CONNECTION, 5, 2s));
  CHECK(s.equals("VIC.HVESSS1_PGN61590.HS_IntChrgrSts", 1, 2s));
  CHECK(s.equals("Vehicle_Control_Unit.BMS.BMS_Control", 0, 2s));
  // the VIC's limits (PropA_C3: 700 V, 50 A in simulation.json) forwarded to the charger
  CHECK(s.equals("Vehicle_Control_Unit.BMS.BMS_Max_Current", 50, 2s));
  CHECK(s.equals("Vehicle_Control_Unit.BMS.BMS_Max_Voltage", 700, 2s));
  // the charger delivers them, less the DC-DC's share of the pack current
  CHECK(s.until("OBC.OBC.OBC_Output_Current", [](double amps) { return amps > 49 && amps <= 50; }, 3s));
  const double before = *s.value(SOC);
  CHECK(s.until(SOC, [before](double soc) { return soc > before; }, 5s));  // charging raises the SOC

  s.fault("soc_high", true);  // 90 %
  CHECK(s.equals("Vehicle_Control_Unit.BMS.BMS_Control", 1, 3s));  // the FSM stops the charger
  CHECK(s.equals("OBC.OBC.OBC_Output_Current", 0, 3s));

  s.set("internal.operator.ACCharging", "0");
  CHECK_MESSAGE(s.state("Ready", 5s), s.stateNow());
  s.fault("soc_high", false);
  s.set("internal.operator.DCCharging", "1");
  CHECK(s.equals("Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay", 5, 2s));
  CHECK_MESSAGE(s.state("Charging", 5s), s.stateNow());
  CHECK(s.equals(CONNECTION, 5, 2s));
}

TEST_CASE("every injected fault leads to its fault state, and back to Ready once cleared and reset") {
  SKIP_UNLESS_ISOLATED();
  Stack s;
  s.start();
  struct Case {
    const char* fault;
    const char* state;
  };
  for (const Case& c : {Case{"battery", "Battery Fault"}, Case{"isolation", "Battery Fault"}, Case{"pdu", "PDU Fault"},
                        Case{"hvlp", "HVLP Inverter Fault"}, Case{"hvlp_shutdown", "HVLP Inverter Fault"},
                        Case{"editron", "Editron Inverter Fault"}, Case{"obc", "OBC Fault"},
                        Case{"silent.VIC", "Battery Timeout"}}) {
    INFO(std::string(c.fault));
    s.fault(c.fault, true);
    CHECK_MESSAGE(s.state(c.state, 6s), s.stateNow());
    s.fault(c.fault, false);
    s.set("internal.operator.FaultReset", "1");
    CHECK_MESSAGE(s.state("Ready", 6s), s.stateNow());
    CHECK(s.equals("internal.operator.FaultReset", 0, 2s));  // the reset was consumed
  }
  const auto unknown = s.vcu({"sim", "fault", "batery", "on"});
  CHECK(contains(unknown.out + unknown.err, "unknown fault 'batery'"));
}

TEST_CASE("the thesis' HIL cases: low SOC, the contactor-fault line, no battery frames for 3 s, the relay in the run state") {
  SKIP_UNLESS_ISOLATED();
  Stack s;
  s.start();
  CHECK(s.equals("internal.gpio.Cl15", 1, 1s));  // relay on in the run state

  s.fault("soc_low", true);  // 15 %
  CHECK_MESSAGE(s.state("Charge Required", 4s), s.stateNow());
  CHECK(s.sawFault("soc_low", "SOC below 20 %", 2s));
  s.fault("soc_low", false);
  CHECK_MESSAGE(s.state("Ready", 4s), s.stateNow());

  s.set("internal.gpio.sim.ContactorFault", "1");
  CHECK_MESSAGE(s.state("Contactor Fault", 3s), s.stateNow());
  s.set("internal.gpio.sim.ContactorFault", "0");
  s.set("internal.operator.FaultReset", "1");
  CHECK_MESSAGE(s.state("Ready", 4s), s.stateNow());

  s.fault("silent.VIC", true);
  CHECK_MESSAGE(s.state("Battery Timeout", 6s), s.stateNow());
  CHECK(s.sawFault("battery_timeout", "no HVESSS1 from the VIC for 3 s", 2s));
  s.fault("silent.VIC", false);
}

TEST_CASE("a wrong SHM expectation makes the simulated VIC refuse every J1939-76 pair, stay disconnected and say why") {
  SKIP_UNLESS_ISOLATED();
  Stack s;
  s.start();
  s.fault("shm_expectation", true);
  s.set("internal.operator.ConnectDriving", "1");
  CHECK(s.state("Connecting Driving", 3s));
  CHECK(s.sawFault("sim.vic_safety", "refuses the VCU's J1939-76 pairs: CrcMismatch", 3s));
  CHECK_FALSE(s.equals(CONNECTION, 1, 2s));  // never connects
  CHECK(s.stateNow() == "Connecting Driving");
  s.fault("shm_expectation", false);
  CHECK_MESSAGE(s.state("Driving", 5s), s.stateNow());  // good pairs again: it connects
}
