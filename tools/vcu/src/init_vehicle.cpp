// `vcu init`: vehicle.json, gpio.json and simulation.json of the generated folder, and the
// plan helpers every writer shares.
#include <algorithm>
#include <cctype>
#include <string>

#include "init_plan.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/safety.hpp"

namespace openvcu::cli::init {

bool isSafetyHeader(const dbc::Message& message) noexcept {
  return message.extended && j1939::pgnOf(message.id) == j1939::PGN_SAFETY_HEADER;
}

bool markedAsSdm(const dbc::Message& message) noexcept {
  if (!message.extended || message.length != j1939::SAFETY_MESSAGE_LENGTH || isSafetyHeader(message)) return false;
  std::string folded = message.comment;
  std::transform(folded.begin(), folded.end(), folded.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return folded.find("j1939-76 sdm") != std::string::npos;
}

std::size_t busOf(const Plan& plan, const std::string& messageName) noexcept {
  for (std::size_t b = 0; b < plan.buses.size(); ++b) {
    const PlannedBus& bus = plan.buses[b];
    if (bus.allMessages) return b;
    if (std::find(bus.messages.begin(), bus.messages.end(), messageName) != bus.messages.end()) return b;
  }
  return 0;
}

bool timesOut(const dbc::Message& message) noexcept {
  return message.cycleTimeMs.has_value() && message.transmitter != dbc::NO_NODE;
}

std::string firstSignalKey(const dbc::Message& message) {
  for (const dbc::Signal& signal : message.signals) {
    if (signal.decodable()) return message.transmitter + "." + message.name + "." + signal.name;
  }
  return {};
}

namespace {

OrderedJson switchSignal(const char* name, const char* off, const char* on, const char* comment) {
  OrderedJson signal;
  signal["name"] = name;
  signal["values"] = OrderedJson{{"0", off}, {"1", on}};
  signal["comment"] = comment;
  return signal;
}

}  // namespace

OrderedJson vehicleJson(const Plan& plan) {
  OrderedJson root;
  root["comment"] = "Written by `vcu init` for node '" + plan.node +
                    "' (docs/config.md, docs/bring-up.md). Every bus runs on the simulated bus (sim:NAME) so "
                    "`./run.sh --config vehicle.json` starts at once; on the vehicle set each link to socketcan:IFACE.";
  root["instance"] = plan.instance;
  root["node"] = plan.node;
  OrderedJson dbcList = OrderedJson::array();
  for (const PlannedBus& bus : plan.buses) dbcList.push_back(bus.dbcName);
  root["dbc"] = dbcList;
  OrderedJson buses = OrderedJson::array();
  for (const PlannedBus& bus : plan.buses) {
    OrderedJson item;
    item["name"] = bus.name;
    item["link"] = "sim:" + bus.name;
    item["bitrate"] = bus.bitrate;
    if (bus.fd) {
      item["fd"] = true;
      if (bus.dataBitrate) item["dataBitrate"] = *bus.dataBitrate;
    }
    if (bus.allMessages) {
      item["messages"] = "all";
    } else {
      item["messages"] = bus.messages;
    }
    item["comment"] = bus.comment;
    buses.push_back(item);
  }
  root["buses"] = buses;
  OrderedJson internals = OrderedJson::array();
  internals.push_back(switchSignal(
      "operator.Run", "Stop", "Run",
      "operator switch (guessed): Standby -> Running while 1, back to Standby at 0 (fsm.json). Set it with "
      "`vcu signal set internal.operator.Run Run`, the HMI, or wire it to a GPIO input in gpio.json"));
  internals.push_back(switchSignal("operator.FaultReset", "Idle", "Reset",
                                   "operator request: leaves Fault for Standby once no receive timeout is active"));
  internals.push_back(
      switchSignal("lamp.Running", "Off", "On",
                   "commanded by the FSM (1 in Running); drives the GPIO output RunningLamp (gpio.json)"));
  root["internalSignals"] = internals;
  root["schedule"] = "schedule.json";
  root["receive"] = "receive.json";
  root["fsm"] = "fsm.json";
  root["gpio"] = "gpio.json";
  root["simulation"] = "simulation.json";
  return root;
}

OrderedJson gpioJson(const Plan& /*plan*/) {
  OrderedJson root;
  root["comment"] =
      "GPIO map template written by `vcu init` (docs/gpio.md). It runs on the simulated chip (\"backend\": \"sim\"); "
      "on the VCU set \"backend\": \"gpiod\", the chip's device and each line's offset (all guessed here), and give "
      "every output its safe state.";
  root["backend"] = "sim";
  root["chips"] = OrderedJson::array(
      {OrderedJson{{"id", "main"}, {"device", "gpiochip0"}, {"comment", "guessed: the board's first GPIO chip"}}});
  OrderedJson lamp;
  lamp["name"] = "RunningLamp";
  lamp["chip"] = "main";
  lamp["offset"] = 17;
  lamp["direction"] = "output";
  lamp["initial"] = 0;
  lamp["safe"] = 0;
  lamp["signal"] = "lamp.Running";
  lamp["comment"] = "example output (offset guessed): on while the FSM is in Running; replace with your relays";
  root["lines"] = OrderedJson::array({lamp});
  return root;
}

OrderedJson simulationJson(const Plan& plan) {
  OrderedJson root;
  root["comment"] =
      "The generic simulated vehicle (services/ecu-sim/README.md): every message the other nodes of the DBC send "
      "goes out at its GenMsgCycleTime with its GenSigStartValue values, so every receive timeout of '" +
      plan.node +
      "' stays quiet. Add \"rules\", \"follow\" and \"integrate\" to make the nodes answer the VCU's commands, "
      "and \"faults\" for `vcu sim fault`.";
  root["model"] = "generic";
  // The simulator checks the node's J1939-76 pairs as a receiver would (vic_pairs_ok /
  // vic_pairs_refused in its heartbeat): SHM -> SDM within the SRVT, SHMs at most SCT apart.
  OrderedJson safety = OrderedJson::array();
  for (const PlannedTx& tx : plan.transmitted) {
    if (!tx.safety) continue;
    const std::uint32_t cycle = tx.lengthenedToMs ? *tx.lengthenedToMs : *tx.cycleMs;
    safety.push_back(OrderedJson{
        {"message", plan.database.messages[tx.message].name},
        {"srvt", std::to_string(SAFETY_SRVT_MS) + "ms"},
        {"sct", std::to_string(cycle * SAFETY_SCT_CYCLES) + "ms"},
        {"comment", "guessed: SHM -> SDM within " + std::to_string(SAFETY_SRVT_MS) + " ms (the schedule's delta is " +
                        std::to_string(SAFETY_DELTA_US) + " us), an SHM at least every " +
                        std::to_string(SAFETY_SCT_CYCLES) + " cycles; use the receiving node's figures"}});
  }
  if (!safety.empty()) root["safety"] = safety;
  return root;
}

}  // namespace openvcu::cli::init
