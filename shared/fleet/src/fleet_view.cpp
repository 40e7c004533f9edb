#include "openvcu/fleet/fleet_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace openvcu::fleet {
namespace {

/// Replaces `kept` by `incoming` when that is newer (see the header); true when it did.
template <typename Message>
bool keepNewer(std::optional<Message>& kept, Message incoming) {
  if (kept && incoming.seq <= kept->seq && incoming.unixMs <= kept->unixMs) return false;
  kept = std::move(incoming);
  return true;
}

}  // namespace

Result<bool> FleetView::apply(std::string_view topic, std::string_view payload) {
  const auto name = parseTopic(topic);
  if (!name) return false;
  const auto fail = [&](const Error& error) { return Error{std::string(topic) + ": " + error.message}; };
  // parsed before the vehicle's entry exists: a bad payload leaves the view unchanged
  switch (name->topic) {
    case Topic::Status: {
      auto online = parseStatus(payload);
      if (!online) return fail(online.error());
      VehicleView& vehicle = m_vehicles[name->vehicleId];
      vehicle.vehicleId = name->vehicleId;
      if (vehicle.online == *online) return false;
      vehicle.online = *online;
      return true;
    }
    case Topic::Birth: {
      auto birth = parseBirth(payload);
      if (!birth) return fail(birth.error());
      VehicleView& vehicle = m_vehicles[name->vehicleId];
      vehicle.vehicleId = name->vehicleId;
      vehicle.newestUnixMs = std::max(vehicle.newestUnixMs, birth->unixMs);
      vehicle.birth = std::move(*birth);
      return true;
    }
    case Topic::State: {
      auto state = parseState(payload);
      if (!state) return fail(state.error());
      VehicleView& vehicle = m_vehicles[name->vehicleId];
      vehicle.vehicleId = name->vehicleId;
      vehicle.newestUnixMs = std::max(vehicle.newestUnixMs, state->unixMs);
      return keepNewer(vehicle.state, std::move(*state));
    }
    case Topic::Faults: {
      auto faults = parseFaults(payload);
      if (!faults) return fail(faults.error());
      VehicleView& vehicle = m_vehicles[name->vehicleId];
      vehicle.vehicleId = name->vehicleId;
      vehicle.newestUnixMs = std::max(vehicle.newestUnixMs, faults->unixMs);
      return keepNewer(vehicle.faults, std::move(*faults));
    }
    case Topic::Health: {
      auto health = parseHealth(payload);
      if (!health) return fail(health.error());
      VehicleView& vehicle = m_vehicles[name->vehicleId];
      vehicle.vehicleId = name->vehicleId;
      vehicle.newestUnixMs = std::max(vehicle.newestUnixMs, health->unixMs);
      return keepNewer(vehicle.health, std::move(*health));
    }
    case Topic::Signals: {
      auto signalBatch = parseSignals(payload);
      if (!signalBatch) return fail(signalBatch.error());
      VehicleView& vehicle = m_vehicles[name->vehicleId];
      vehicle.vehicleId = name->vehicleId;
      vehicle.newestUnixMs = std::max(vehicle.newestUnixMs, signalBatch->unixMs);
      bool changed = false;
      for (SignalSample& sample : signalBatch->samples) {
        auto [it, added] = vehicle.signals.try_emplace(sample.name, sample);
        if (!added && sample.unixMs >= it->second.unixMs) {
          changed = changed || it->second.value != sample.value;
          it->second = std::move(sample);
        }
        changed = changed || added;
      }
      return changed;
    }
  }
  return false;
}

const VehicleView* FleetView::find(std::string_view vehicleId) const {
  const auto it = m_vehicles.find(std::string(vehicleId));
  return it == m_vehicles.end() ? nullptr : &it->second;
}

std::int64_t activeFaultCount(const VehicleView& vehicle) noexcept {
  if (!vehicle.faults) return 0;
  return static_cast<std::int64_t>(vehicle.faults->active.size()) + activeDtcCount(vehicle);
}

std::int64_t activeDtcCount(const VehicleView& vehicle) noexcept {
  if (!vehicle.faults) return 0;
  std::int64_t count = 0;
  for (const Dm1Count& node : vehicle.faults->dm1) count += node.activeDtcs;
  return count;
}

std::optional<FaultLevel> worstFaultLevel(const VehicleView& vehicle) noexcept {
  if (!vehicle.faults) return std::nullopt;
  std::optional<FaultLevel> worst;
  for (const ActiveFault& fault : vehicle.faults->active) {
    if (!worst || fault.level > *worst) worst = fault.level;
  }
  return worst;
}

std::string socSignalOf(const VehicleView& vehicle, std::string_view wanted) {
  if (!wanted.empty()) return std::string(wanted);
  if (vehicle.birth) {
    for (const BirthSignal& signal : vehicle.birth->signals) {
      if (signal.name.ends_with("SOC")) return signal.name;
    }
  }
  for (const auto& [name, sample] : vehicle.signals) {
    if (name.ends_with("SOC")) return name;
  }
  return {};
}

std::string formatNumber(double value) {
  if (!std::isfinite(value)) return std::isnan(value) ? "nan" : (value > 0 ? "inf" : "-inf");
  char text[64];
  std::snprintf(text, sizeof text, "%.3f", value);
  std::string out(text);
  while (out.back() == '0') out.pop_back();
  if (out.back() == '.') out.pop_back();
  if (out == "-0") out = "0";
  return out;
}

std::optional<std::string> fleetValue(const VehicleView& vehicle, std::string_view key) {
  if (key == "status") {
    if (!vehicle.online) return std::nullopt;
    return std::string(*vehicle.online ? STATUS_ONLINE : STATUS_OFFLINE);
  }
  if (key == "state") {
    if (!vehicle.state) return std::nullopt;
    return vehicle.state->state;
  }
  if (key == "faults") {
    if (!vehicle.faults) return std::nullopt;
    std::string out = std::to_string(activeFaultCount(vehicle)) + " active";
    if (const auto worst = worstFaultLevel(vehicle)) out += ", worst " + std::string(faultLevelName(*worst));
    std::string list;
    for (const ActiveFault& fault : vehicle.faults->active) {
      list +=
          (list.empty() ? "" : "; ") + fault.source + "/" + fault.name + (fault.text.empty() ? "" : " " + fault.text);
    }
    for (const Dm1Count& node : vehicle.faults->dm1) {
      list += (list.empty() ? "" : "; ") + ("DM1 " + node.node + " " + std::to_string(node.activeDtcs) + " DTC(s)");
    }
    return list.empty() ? out : out + ": " + list;
  }
  if (key == "health") {
    if (!vehicle.health) return std::nullopt;
    const auto ready = std::count_if(vehicle.health->services.begin(), vehicle.health->services.end(),
                                     [](const ServiceState& service) { return service.status == "Ready"; });
    return std::to_string(ready) + "/" + std::to_string(vehicle.health->services.size()) + " services Ready; queue " +
           std::to_string(vehicle.health->queuePending) + " pending, " + std::to_string(vehicle.health->queueDropped) +
           " dropped";
  }
  const auto signal = vehicle.signals.find(std::string(key));
  if (signal == vehicle.signals.end()) return std::nullopt;
  return formatNumber(signal->second.value);
}

}  // namespace openvcu::fleet
