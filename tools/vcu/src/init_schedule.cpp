// `vcu init`: schedule.json (every message the node transmits) and receive.json (a timeout
// for every cyclic message it receives), and the bus-load budget of the schedule.
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "init_plan.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/j1939/safety.hpp"

namespace openvcu::cli::init {
namespace {

std::string percent(double share) {
  std::ostringstream text;
  text.setf(std::ios::fixed);
  text.precision(1);
  text << share * 100.0 << " %";
  return text.str();
}

config::BusConfig busConfig(const PlannedBus& bus) {
  config::BusConfig result;
  result.name = bus.name;
  result.bitrate = bus.bitrate;
  if (bus.dataBitrate) result.dataBitrate = *bus.dataBitrate;
  result.fd = bus.fd;
  return result;
}

/// The cyclic frames of one transmitted message as can-tx counts them (an SDM with its SHM).
void addFrames(const Plan& plan, const PlannedTx& tx, std::vector<config::CyclicFrame>& frames) {
  const auto cycle = tx.lengthenedToMs ? tx.lengthenedToMs : tx.cycleMs;
  if (!cycle) return;
  const dbc::Message& message = plan.database.messages[tx.message];
  const auto length = static_cast<std::uint8_t>(std::min<std::uint32_t>(message.length, 64));
  const std::int64_t cycleNs = static_cast<std::int64_t>(*cycle) * 1'000'000;
  frames.push_back({message.id, message.extended, length, cycleNs});
  if (tx.safety) frames.push_back({j1939::safetyHeaderCanId(message.id), true, 8, cycleNs});
}

double busLoad(const Plan& plan, std::size_t bus, const std::vector<const PlannedTx*>& only = {}) {
  std::vector<config::CyclicFrame> frames;
  for (const PlannedTx& tx : plan.transmitted) {
    if (tx.bus != bus) continue;
    if (!only.empty() && std::find(only.begin(), only.end(), &tx) == only.end()) continue;
    addFrames(plan, tx, frames);
  }
  return config::cyclicBusLoad(frames, busConfig(plan.buses[bus]));
}

}  // namespace

void fitBusLoad(Plan& plan) {
  for (std::size_t b = 0; b < plan.buses.size(); ++b) {
    const double before = busLoad(plan, b);
    double load = before;
    while (load > TARGET_BUS_LOAD) {
      PlannedTx* heaviest = nullptr;
      double heaviestLoad = 0.0;
      for (PlannedTx& tx : plan.transmitted) {
        const auto cycle = tx.lengthenedToMs ? tx.lengthenedToMs : tx.cycleMs;
        if (tx.bus != b || !cycle || *cycle * 2 > config::MAX_CYCLE_MS) continue;
        const double share = busLoad(plan, b, {&tx});
        if (share > heaviestLoad) {
          heaviestLoad = share;
          heaviest = &tx;
        }
      }
      if (heaviest == nullptr) break;  // every cycle at its maximum already: can-tx will say so
      heaviest->lengthenedToMs = (heaviest->lengthenedToMs ? *heaviest->lengthenedToMs : *heaviest->cycleMs) * 2;
      load = busLoad(plan, b);
    }
    std::string note = "bus '" + plan.buses[b].name + "': the node's cyclic frames take " + percent(before);
    if (load != before) note += " at the DBC's cycles, " + percent(load) + " after lengthening the heaviest";
    plan.busLoadNotes.push_back(note + " (can-tx refuses more than " + percent(config::MAX_CYCLIC_BUS_LOAD) + ")");
  }
}

OrderedJson scheduleJson(const Plan& plan) {
  OrderedJson root;
  std::string comment =
      "Transmit schedule written by `vcu init` (docs/design/can-tx.md): every message '" + plan.node +
      "' transmits, at its DBC GenMsgCycleTime. Start values are not repeated here: can-tx sends each signal's "
      "GenSigStartValue (else the J1939 not-available fill) until the FSM or an operator commands it; put a "
      "\"values\" object on a message to change them. ";
  for (const std::string& note : plan.busLoadNotes) comment += note + ". ";
  if (!plan.shms.empty()) {
    comment += "The J1939-76 safety headers (";
    for (std::size_t i = 0; i < plan.shms.size(); ++i) {
      comment += (i ? ", " : "") + plan.database.messages[plan.shms[i]].name;
    }
    comment += ") are never scheduled on their own: can-tx sends them before each SDM.";
  } else {
    comment += "No J1939-76 pairs: a message is taken as an SDM when its DBC comment says \"J1939-76 SDM\".";
  }
  root["comment"] = comment;
  root["include"] = "transmitted";
  OrderedJson messages = OrderedJson::object();
  for (const PlannedTx& tx : plan.transmitted) {
    const dbc::Message& message = plan.database.messages[tx.message];
    OrderedJson entry;
    if (!tx.cycleMs) {
      entry["comment"] =
          "no GenMsgCycleTime in the DBC: not cyclic, sent on a J1939 request or when asked (`vcu send`); "
          "give it a \"cycleMs\" to send it cyclically";
    } else if (tx.lengthenedToMs) {
      entry["cycleMs"] = *tx.lengthenedToMs;
      entry["comment"] = "guessed: the DBC says every " + std::to_string(*tx.cycleMs) + " ms, lengthened to " +
                         std::to_string(*tx.lengthenedToMs) +
                         " ms to keep the bus load under can-tx's limit; shorten it if your bus allows";
    } else {
      entry["comment"] = "every " + std::to_string(*tx.cycleMs) + " ms (DBC GenMsgCycleTime)";
    }
    if (!tx.safety && markedAsSdm(message) && tx.cycleMs) {
      entry["comment"] = entry["comment"].get<std::string>() +
                         "; the DBC marks it a J1939-76 SDM, but its cycle is not longer than the SHM -> SDM delta (" +
                         std::to_string(SAFETY_DELTA_US) + " us): sent without its SHM";
    }
    if (tx.safety) {
      entry["safety"] =
          OrderedJson{{"deltaUs", SAFETY_DELTA_US},
                      {"comment",
                       "J1939-76 SDM (the DBC comment says so): its SHM goes first; the delta is guessed, set "
                       "the receiver's SRVT margin"}};
    }
    messages[message.name] = entry;
  }
  root["messages"] = messages;
  return root;
}

OrderedJson receiveJson(const Plan& plan) {
  OrderedJson root;
  root["comment"] =
      "Receive settings written by `vcu init` (services/can-rx/README.md): every cyclic message the other nodes "
      "send times out after " +
      std::to_string(TIMEOUT_FACTOR) + " x its GenMsgCycleTime, at least " + std::to_string(MIN_TIMEOUT_MS) +
      " ms (listed below so each can be changed; 0 = never stale); messages without a cycle "
      "never time out. A timeout makes the message's signals stale, raises rx_timeout.BUS.MESSAGE and sends the "
      "FSM to Fault.";
  root["timeoutFactor"] = TIMEOUT_FACTOR;
  OrderedJson messages = OrderedJson::object();
  for (const std::size_t index : plan.received) {
    const dbc::Message& message = plan.database.messages[index];
    if (!message.cycleTimeMs) continue;
    if (timesOut(message) && firstSignalKey(message).empty()) {
      messages[message.name] = OrderedJson{
          {"timeoutMs", std::max<std::uint64_t>(std::uint64_t{*message.cycleTimeMs} * TIMEOUT_FACTOR, MIN_TIMEOUT_MS)},
          {"comment", "from " + message.transmitter +
                          "; no decodable signal: its timeout raises rx_timeout but the FSM (which reads signals) "
                          "does not see it"}};
      continue;
    }
    if (!timesOut(message)) {
      messages[message.name] =
          OrderedJson{{"timeoutMs", 0},
                      {"comment", "no transmitter in the DBC (Vector__XXX): never stale; name its node to time it"}};
      continue;
    }
    const std::uint64_t factored = std::uint64_t{*message.cycleTimeMs} * TIMEOUT_FACTOR;
    const std::uint64_t timeout =
        std::min<std::uint64_t>(std::max<std::uint64_t>(factored, MIN_TIMEOUT_MS), config::MAX_CYCLE_MS);
    std::string comment = "from " + message.transmitter + ", every " + std::to_string(*message.cycleTimeMs) + " ms";
    if (timeout > factored) {
      comment += "; guessed: " + std::to_string(MIN_TIMEOUT_MS) + " ms, the floor vcu init uses (" +
                 std::to_string(TIMEOUT_FACTOR) + " x cycle would be " + std::to_string(factored) +
                 " ms): set the node's real timeout";
    }
    messages[message.name] = OrderedJson{{"timeoutMs", timeout}, {"comment", comment}};
  }
  root["messages"] = messages;
  return root;
}

}  // namespace openvcu::cli::init
