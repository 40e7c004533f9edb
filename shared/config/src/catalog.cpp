#include "openvcu/config/catalog.hpp"

#include <algorithm>
#include <unordered_set>

namespace openvcu::config {

bool sentBy(const dbc::Message& message, std::string_view node) {
  const auto senders = message.transmitters();
  return std::find(senders.begin(), senders.end(), node) != senders.end();
}

signals::SignalDirection directionOf(const VehicleConfig& config, const dbc::Message& message) {
  return sentBy(message, config.node) ? signals::SignalDirection::Transmitted : signals::SignalDirection::Received;
}

std::string signalKey(const dbc::Message& message, const dbc::Signal& signal) {
  return message.transmitter + "." + message.name + "." + signal.name;
}

namespace {

/// A built-in status slot, written by `owner` alone.
signals::SignalInfo internalInfo(std::string name, std::string unit, double minimum, double maximum,
                                 std::string comment, ServiceId owner, bool reported = true) {
  signals::SignalInfo info;
  info.key = std::string(INTERNAL_PREFIX) + name;
  info.unit = std::move(unit);
  info.minimum = minimum;
  info.maximum = maximum;
  info.comment = std::move(comment);
  info.kind = signals::SignalKind::Internal;
  info.direction = signals::SignalDirection::Internal;
  info.owner = writerOf(owner);
  info.reported = reported;
  return info;
}

/// The built-in namespaces of statuses: a declared internal signal in one of them is a
/// status too (its writer is not a service of the stack: a tool's or a test's).
constexpr std::string_view STATUS_NAMESPACES[] = {"fsm.", "service.", "bus.", "dm1.", "gpio."};

/// The owner of a declared internal signal (see the header), or the error naming both
/// claimants.
Result<signals::SignalInfo> declaredInfo(const VehicleConfig& config, const InternalSignal& declared) {
  signals::SignalInfo info = internalInfo(declared.name, declared.unit, declared.minimum, declared.maximum,
                                          declared.comment, ServiceId::Fsm, false);
  for (const auto& description : declared.values) info.valueTexts.emplace_back(description.value, description.text);
  const bool sendGroup = info.key.starts_with(SEND_GROUP_NAMESPACE);
  const GpioLine* input = config.gpio.inputBoundTo(info.key);
  if (sendGroup && input != nullptr) {
    return Error{"'" + info.key + "' has two owners: can-tx (a send group: the namespace " +
                 std::string(SEND_GROUP_NAMESPACE) + ") and gpio (input line '" + input->name +
                 "' is bound to it); bind the line to another signal"};
  }
  if (sendGroup) info.owner = writerOf(ServiceId::CanTx);
  if (input != nullptr) info.owner = writerOf(ServiceId::Gpio);
  for (const std::string_view space : STATUS_NAMESPACES) {
    if (!declared.name.starts_with(space)) continue;
    info.reported = true;
    info.owner = signals::NO_OWNER;
  }
  return info;
}

}  // namespace

std::optional<std::uint8_t> nodeAddress(const dbc::Database& database, const dbc::Node& node) {
  const auto value = database.attribute(node.attributes, "NmStationAddress", dbc::ObjectType::Node);
  if (!value || value->kind != dbc::AttributeValue::Kind::Number) return std::nullopt;
  if (value->number < 0 || value->number > 253) return std::nullopt;  // 254 null, 255 global
  return static_cast<std::uint8_t>(value->number);
}

Result<signals::Catalog> buildCatalog(const VehicleConfig& config) {
  std::vector<signals::SignalInfo> list;
  for (const BusConfig& bus : config.buses) {
    for (const std::size_t messageIndex : bus.messages) {
      const dbc::Message& message = config.database.messages[messageIndex];
      std::unordered_set<std::string> seen;
      for (const dbc::Signal& signal : message.signals) {
        // Not decodable (over 64 bits) or a repeated name (references resolve to the first).
        if (!signal.decodable() || !seen.insert(signal.name).second) continue;
        signals::SignalInfo info;
        info.key = signalKey(message, signal);
        info.unit = signal.unit;
        info.minimum = signal.minimum;
        info.maximum = signal.maximum;
        info.comment = signal.comment;
        info.message = message.name;
        info.bus = bus.name;
        info.kind = signals::SignalKind::Bus;
        info.direction = directionOf(config, message);
        info.owner = writerOf(info.direction == signals::SignalDirection::Transmitted ? ServiceId::CanTx
                                                                                        : ServiceId::CanRx);
        for (const auto& description : signal.valueDescriptions) {
          info.valueTexts.emplace_back(description.value, description.text);
        }
        list.push_back(std::move(info));
      }
    }
  }
  for (const InternalSignal& declared : config.internalSignals) {
    auto info = declaredInfo(config, declared);
    if (!info) return info.error();
    list.push_back(std::move(*info));
  }
  for (const GpioLine& line : config.gpio.lines) {
    const bool output = line.direction == LineDirection::Output;
    auto status = internalInfo("gpio." + line.name, "", 0, 1,
                               std::string(output ? "level vcu-gpio drives on output line " : "level vcu-gpio read on input line ") +
                                   line.name + " (1 = active)",
                               ServiceId::Gpio);
    status.valueTexts = {{0, "inactive"}, {1, "active"}};
    list.push_back(std::move(status));
    if (!output) {
      list.push_back(internalInfo("gpio.sim." + line.name, "", 0, 1,
                                  "electrical level of input line " + line.name + " on the simulated chip (sim backend)",
                                  ServiceId::Gpio, false));
    }
  }
  list.push_back(internalInfo("fsm.state", "", 0, 65535, "index of the FSM's current state (fsm file order)", ServiceId::Fsm));
  list.push_back(internalInfo("fsm.stateSince", "s", 0, 1e12, "CLOCK_REALTIME seconds when the state was entered", ServiceId::Fsm));
  list.push_back(internalInfo("fsm.stateEntered", "s", 0, 1e12,
                              "CLOCK_MONOTONIC seconds when the state was entered (a restarted vcu-fsm resumes `after`)",
                              ServiceId::Fsm));
  list.push_back(internalInfo("fsm.machine", "", 0, 2.9e14, "hash of the FSM file the state belongs to", ServiceId::Fsm));
  list.push_back(internalInfo("fsm.reloads", "", 0, 1e15, "reload commands vcu-fsm received (each wakes its engine)", ServiceId::Fsm));
  for (std::uint32_t timer = 0; timer < FSM_TIMER_SLOTS; ++timer) {
    list.push_back(internalInfo("fsm.timer." + std::to_string(timer), "s", 0, 1e12,
                                "CLOCK_MONOTONIC seconds since which a `for` condition holds; 0: not running", ServiceId::Fsm));
  }
  for (const ServiceEntry& service : SERVICES) {
    list.push_back(internalInfo("service." + std::string(service.name) + ".heartbeat", "", 0, 1.8e19,
                                "heartbeat counter of vcu-" + std::string(service.name), service.id));
  }
  for (const BusConfig& bus : config.buses) {
    list.push_back(internalInfo("bus." + bus.name + ".load", "%", 0, 1000,
                                "bus load over the last second from the wire time of every frame (can-rx)", ServiceId::CanRx));
    auto state = internalInfo("bus." + bus.name + ".state", "", 0, 4, "link and controller state (can-rx)", ServiceId::CanRx);
    state.valueTexts = {{0, "active"}, {1, "warning"}, {2, "passive"}, {3, "bus-off"}, {4, "down"}};
    list.push_back(std::move(state));
  }
  for (const dbc::Node& node : config.database.nodes) {
    if (node.name == config.node || !nodeAddress(config.database, node)) continue;
    const std::string prefix = "dm1." + node.name + ".";
    list.push_back(internalInfo(prefix + "activeDtcs", "", 0, 445, "active DTCs in the node's last DM1 (can-rx)",
                                ServiceId::CanRx));
    for (const char* lamp : {"protectLamp", "amberWarningLamp", "redStopLamp", "malfunctionLamp"}) {
      auto info = internalInfo(prefix + lamp, "", 0, 3, "DM1 lamp status (can-rx)", ServiceId::CanRx);
      info.valueTexts = {{0, "off"}, {1, "on"}, {2, "error"}, {3, "not available"}};
      list.push_back(std::move(info));
    }
    list.push_back(internalInfo(prefix + "firstSpn", "", 0, 524287, "SPN of the first active DTC, 0 when none",
                                ServiceId::CanRx));
    list.push_back(internalInfo(prefix + "firstFmi", "", 0, 31, "FMI of the first active DTC, 0 when none",
                                ServiceId::CanRx));
  }
  return signals::Catalog::create(std::move(list));
}

}  // namespace openvcu::config
