// `vcu init`: fsm.json (Standby / Running / Fault on the operator switches and every
// receive timeout) and dashboard.json (the machine's state, the switches, the buses and the
// received signals grouped by the node that sends them).
#include <algorithm>
#include <string>
#include <vector>

#include "init_plan.hpp"

namespace openvcu::cli::init {
namespace {

constexpr const char* RUN_KEY = "internal.operator.Run";
constexpr const char* RESET_KEY = "internal.operator.FaultReset";
constexpr const char* LAMP_KEY = "internal.lamp.Running";
constexpr const char* FAULT_NAME = "vehicle.fault";

/// One `quality stale` condition per received message that times out (its first signal).
OrderedJson staleConditions(const Plan& plan) {
  OrderedJson list = OrderedJson::array();
  for (const std::size_t index : plan.received) {
    const dbc::Message& message = plan.database.messages[index];
    if (!timesOut(message)) continue;
    const std::string key = firstSignalKey(message);
    if (key.empty()) continue;
    list.push_back(
        OrderedJson{{"key", key}, {"quality", "stale"}, {"comment", message.name + " timed out (receive.json)"}});
  }
  return list;
}

OrderedJson lamp(int value) {
  return OrderedJson{{"signal", LAMP_KEY}, {"value", value}};
}

OrderedJson toFault(const OrderedJson& stale) {
  return OrderedJson{
      {"comment", "a received message timed out"}, {"condition", OrderedJson{{"any", stale}}}, {"nextState", "Fault"}};
}

}  // namespace

OrderedJson fsmJson(const Plan& plan) {
  const OrderedJson stale = staleConditions(plan);
  OrderedJson root;
  std::string comment =
      "State machine written by `vcu init` (docs/fsm.md): Standby until the operator's Run switch, Running while "
      "it stays on, Fault when any received message times out (" +
      std::to_string(stale.size()) +
      " timeouts, one per cyclic message, from receive.json); FaultReset returns to Standby once none is active "
      "and Fault has lasted 1 s. A Stop in Running wins over a timeout in the same instant (Standby then goes "
      "to Fault). "
      "Add the commands of '" +
      plan.node + "' (signals it transmits) to each state's entry: safe values in Standby and Fault.";
  if (stale.empty()) comment += " The DBC gives no received message a cycle, so nothing leads to Fault yet.";
  root["comment"] = comment;
  root["initialState"] = "Standby";
  OrderedJson states = OrderedJson::array();

  // The operator's transitions come first and Fault is left only after a dwell ("after"):
  // the FSM checker then proves the Standby <-> Running cycle from the switch alone and
  // needs no search over the qualities of the (possibly hundreds of) timeout signals.
  OrderedJson standbyTransitions = OrderedJson::array();
  standbyTransitions.push_back(OrderedJson{{"comment", "operator Run"},
                                           {"condition", OrderedJson{{"key", RUN_KEY}, {"eq", "Run"}}},
                                           {"nextState", "Running"}});
  if (!stale.empty()) standbyTransitions.push_back(toFault(stale));
  states.push_back(OrderedJson{{"name", "Standby"},
                               {"comment", "the machine is off: the schedule runs with the DBC start values"},
                               {"entry", OrderedJson::array({lamp(0)})},
                               {"transitions", standbyTransitions}});

  OrderedJson runningTransitions = OrderedJson::array();
  runningTransitions.push_back(OrderedJson{{"comment", "operator Stop"},
                                           {"condition", OrderedJson{{"key", RUN_KEY}, {"eq", "Stop"}}},
                                           {"nextState", "Standby"}});
  if (!stale.empty()) runningTransitions.push_back(toFault(stale));
  states.push_back(OrderedJson{{"name", "Running"},
                               {"comment", "the operator asked to run: put the node's run commands here"},
                               {"entry", OrderedJson::array({lamp(1)})},
                               {"transitions", runningTransitions}});

  OrderedJson resetCondition = OrderedJson{{"key", RESET_KEY}, {"eq", "Reset"}};
  if (!stale.empty()) {
    resetCondition =
        OrderedJson{{"all", OrderedJson::array({resetCondition, OrderedJson{{"not", OrderedJson{{"any", stale}}}}})}};
  }
  states.push_back(OrderedJson{
      {"name", "Fault"},
      {"comment", "latched until the operator resets it with no timeout active"},
      {"entry", OrderedJson::array({lamp(0), OrderedJson{{"raise", FAULT_NAME},
                                                         {"severity", "error"},
                                                         {"text", "a received message timed out"}}})},
      {"exit", OrderedJson::array({OrderedJson{{"clear", FAULT_NAME}}})},
      {"transitions",
       OrderedJson::array({OrderedJson{{"comment", "operator FaultReset, no timeout active, at least 1 s in Fault"},
                                       {"condition", resetCondition},
                                       {"after", "1s"},
                                       {"nextState", "Standby"}}})}});
  root["states"] = states;
  return root;
}

OrderedJson dashboardJson(const Plan& plan) {
  OrderedJson root;
  root["comment"] =
      "HMI dashboard written by `vcu init` (services/hmi/README.md): the status table shows the machine, the "
      "operator switches and the buses; the grid shows up to " +
      std::to_string(DASHBOARD_SIGNALS_PER_NODE) +
      " received signals per sending node, grouped by node (labels 'Node Signal'). Pick the dials "
      "(\"dials\": voltage, current) and the header (\"header\": soc) from your DBC.";
  OrderedJson status = OrderedJson::array({"internal.fsm.state", RUN_KEY, RESET_KEY, LAMP_KEY});
  for (const PlannedBus& bus : plan.buses) {
    status.push_back("internal.bus." + bus.name + ".state");
    status.push_back("internal.bus." + bus.name + ".load");
  }
  root["status"] = status;
  root["staleAfterMs"] = 2000;
  // Nodes in the order their first received message appears in the DBC.
  std::vector<std::string> nodes;
  for (const std::size_t index : plan.received) {
    const std::string& node = plan.database.messages[index].transmitter;
    if (std::find(nodes.begin(), nodes.end(), node) == nodes.end()) nodes.push_back(node);
  }
  OrderedJson items = OrderedJson::array();
  for (const std::string& node : nodes) {
    std::size_t shown = 0;
    std::size_t total = 0;
    const std::size_t first = items.size();
    for (const std::size_t index : plan.received) {
      const dbc::Message& message = plan.database.messages[index];
      if (message.transmitter != node) continue;
      for (const dbc::Signal& signal : message.signals) {
        if (!signal.decodable()) continue;
        ++total;
        if (shown == DASHBOARD_SIGNALS_PER_NODE) continue;
        ++shown;
        const bool whole = signal.factor == 1.0 && signal.offset == 0.0 && signal.valueType == dbc::ValueType::Integer;
        items.push_back(OrderedJson{{"key", message.transmitter + "." + message.name + "." + signal.name},
                                    {"label", node + " " + signal.name},
                                    {"format", whole ? "%.0f" : "%.1f"}});
      }
    }
    if (items.size() > first) {
      items[first]["comment"] = node + ": " + std::to_string(shown) + " of its " + std::to_string(total) +
                                " received signals (the first ones in the DBC); add or replace keys as needed";
    }
  }
  root["items"] = items;
  return root;
}

}  // namespace openvcu::cli::init
