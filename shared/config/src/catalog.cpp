#include "openvcu/config/catalog.hpp"

#include <unordered_set>

namespace openvcu::config {

std::string signalKey(const dbc::Message& message, const dbc::Signal& signal) {
  return message.transmitter + "." + message.name + "." + signal.name;
}

namespace {

signals::SignalInfo internalInfo(std::string name, std::string unit, double minimum, double maximum,
                                 std::string comment) {
  signals::SignalInfo info;
  info.key = std::string(INTERNAL_PREFIX) + name;
  info.unit = std::move(unit);
  info.minimum = minimum;
  info.maximum = maximum;
  info.comment = std::move(comment);
  info.kind = signals::SignalKind::Internal;
  return info;
}

}  // namespace

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
        for (const auto& description : signal.valueDescriptions) {
          info.valueTexts.emplace_back(description.value, description.text);
        }
        list.push_back(std::move(info));
      }
    }
  }
  for (const InternalSignal& declared : config.internalSignals) {
    signals::SignalInfo info = internalInfo(declared.name, declared.unit, declared.minimum, declared.maximum,
                                            declared.comment);
    for (const auto& description : declared.values) info.valueTexts.emplace_back(description.value, description.text);
    list.push_back(std::move(info));
  }
  list.push_back(internalInfo("fsm.state", "", 0, 65535, "index of the FSM's current state (fsm file order)"));
  list.push_back(internalInfo("fsm.stateSince", "s", 0, 1e12, "CLOCK_REALTIME seconds when the state was entered"));
  for (const std::string_view service : SERVICES) {
    list.push_back(internalInfo("service." + std::string(service) + ".heartbeat", "", 0, 1.8e19,
                                "heartbeat counter of vcu-" + std::string(service)));
  }
  return signals::Catalog::create(std::move(list));
}

}  // namespace openvcu::config
