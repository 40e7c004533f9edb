#include "openvcu/display/health.hpp"

#include <algorithm>

#include "openvcu/config/faults.hpp"
#include "openvcu/config/services.hpp"

namespace openvcu::display {

std::vector<std::string> expectedServices() {
  std::vector<std::string> names;
  for (const std::string_view name : config::SERVICES) {
    // optional: a VCU may run without them (listed once heard)
    if (name == "hmi" || name == "web" || name == "telemetry" || name == "watchdog") continue;
    names.push_back("vcu-" + std::string(name));
  }
  return names;
}

std::string silentFaultName(std::string_view program) {
  constexpr std::string_view PROGRAM_PREFIX = "vcu-";
  if (program.starts_with(PROGRAM_PREFIX)) program.remove_prefix(PROGRAM_PREFIX.size());
  return faults::serviceSilent(program);
}

std::string_view livenessName(Liveness liveness) noexcept {
  switch (liveness) {
    case Liveness::Beating:
      return "beating";
    case Liveness::Silent:
      return "silent";
    case Liveness::Stopped:
      return "stopped";
    default:
      return "not heard";
  }
}

HealthTracker::HealthTracker(std::vector<std::string> expected, std::int64_t staleAfterNs)
    : m_staleAfterNs(staleAfterNs) {
  for (std::string& name : expected) {
    ServiceHealth service;
    service.name = std::move(name);
    m_services.push_back(std::move(service));
  }
}

ServiceHealth& HealthTracker::row(std::string_view name, bool& added) {
  auto it = std::find_if(m_services.begin(), m_services.end(),
                         [&](const ServiceHealth& service) { return service.name == name; });
  added = it == m_services.end();
  if (!added) return *it;
  ServiceHealth service;
  service.name = std::string(name);
  m_services.push_back(std::move(service));
  return m_services.back();
}

bool HealthTracker::onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs) {
  bool added = false;
  ServiceHealth& service = row(beat.service, added);
  if (service.pid != 0 && service.pid != beat.pid) ++service.restarts;
  service.pid = beat.pid;
  service.uptimeMs = beat.uptimeMs;
  service.lastBeatMonoNs = std::max(service.lastBeatMonoNs, receivedMonoNs);
  service.status = beat.status;
  ++service.heartbeats;
  return added;
}

bool HealthTracker::onSlotBeat(std::string_view program, std::int64_t beatMonoNs) {
  bool added = false;
  ServiceHealth& service = row(program, added);
  service.lastBeatMonoNs = std::max(service.lastBeatMonoNs, beatMonoNs);
  return added;
}

ValueStatus HealthTracker::statusOf(const ServiceHealth& service, std::int64_t nowNs) const noexcept {
  if (service.lastBeatMonoNs < 0) return ValueStatus::NotConnected;
  const std::int64_t age = nowNs - service.lastBeatMonoNs;
  if (age > 3 * m_staleAfterNs) return ValueStatus::NotConnected;
  if (age > m_staleAfterNs) return ValueStatus::Stale;
  if (service.status.starts_with("stopping")) return ValueStatus::NotConnected;
  return ValueStatus::Ready;
}

Liveness HealthTracker::livenessOf(const ServiceHealth& service, std::int64_t nowNs) const noexcept {
  if (service.lastBeatMonoNs < 0) return Liveness::NotHeard;
  if (nowNs - service.lastBeatMonoNs <= m_staleAfterNs) return Liveness::Beating;
  return service.status.starts_with("stopping") ? Liveness::Stopped : Liveness::Silent;
}

std::optional<std::int64_t> HealthTracker::silentFor(const ServiceHealth& service, std::int64_t nowNs) const noexcept {
  const Liveness liveness = livenessOf(service, nowNs);
  if (liveness != Liveness::Silent && liveness != Liveness::Stopped) return std::nullopt;
  return nowNs - service.lastBeatMonoNs;
}

std::vector<ipc::FaultEvent> HealthTracker::silentFaults(std::int64_t nowMonoNs, std::int64_t nowRealNs) const {
  std::vector<ipc::FaultEvent> faults;
  for (const ServiceHealth& service : m_services) {
    const auto silent = silentFor(service, nowMonoNs);
    if (!silent) continue;
    const bool stopped = livenessOf(service, nowMonoNs) == Liveness::Stopped;
    std::string text =
        service.name + (stopped ? " stopped beating after \"" + service.status + "\"" : " stopped beating");
    if (!stopped && !service.status.empty()) text += " (last status \"" + service.status + "\")";
    text += ": hung, stopped or dead; what it last wrote is not current";
    faults.push_back(ipc::FaultEvent{.timestampNs = nowRealNs - *silent,
                                     .name = silentFaultName(service.name),
                                     .source = std::string(SILENT_FAULT_SOURCE),
                                     .severity = ipc::FaultSeverity::Critical,
                                     .active = true,
                                     .text = std::move(text)});
  }
  return faults;
}

const ServiceHealth* HealthTracker::find(std::string_view name) const noexcept {
  for (const ServiceHealth& service : m_services) {
    if (service.name == name) return &service;
  }
  return nullptr;
}

HeartbeatSlots::HeartbeatSlots(const signals::Catalog& catalog) {
  for (const std::string_view name : config::SERVICES) {
    if (const auto index = catalog.indexOf("internal.service." + std::string(name) + ".heartbeat")) {
      m_slots.emplace_back("vcu-" + std::string(name), *index);
    }
  }
}

bool HeartbeatSlots::feed(HealthTracker& tracker, const signals::SignalTable& table) const {
  bool added = false;
  for (const auto& [program, index] : m_slots) {
    const auto bus = table.readBus(index);
    if (!bus || bus->updates == 0) continue;
    added = tracker.onSlotBeat(program, bus->timestampNs) || added;
  }
  return added;
}

bool namesFault(const std::vector<ipc::FaultEvent>& shown, std::string_view name) noexcept {
  return std::any_of(shown.begin(), shown.end(), [&](const ipc::FaultEvent& fault) { return fault.name == name; });
}

std::string_view faultSeverityName(ipc::FaultSeverity severity) noexcept {
  switch (severity) {
    case ipc::FaultSeverity::Info:
      return "info";
    case ipc::FaultSeverity::Warning:
      return "warning";
    case ipc::FaultSeverity::Error:
      return "error";
    default:
      return "critical";
  }
}

}  // namespace openvcu::display
