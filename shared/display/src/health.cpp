#include "openvcu/display/health.hpp"

#include <algorithm>

#include "openvcu/config/services.hpp"

namespace openvcu::display {

std::vector<std::string> expectedServices() {
  std::vector<std::string> names;
  for (const std::string_view name : config::SERVICES) {
    if (name == "hmi" || name == "web" || name == "telemetry") continue;  // optional: a VCU may run without them
    names.push_back("vcu-" + std::string(name));
  }
  return names;
}

HealthTracker::HealthTracker(std::vector<std::string> expected, std::int64_t staleAfterNs)
    : m_staleAfterNs(staleAfterNs) {
  for (std::string& name : expected) {
    ServiceHealth service;
    service.name = std::move(name);
    m_services.push_back(std::move(service));
  }
}

bool HealthTracker::onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs) {
  auto it = std::find_if(m_services.begin(), m_services.end(),
                         [&](const ServiceHealth& service) { return service.name == beat.service; });
  const bool added = it == m_services.end();
  if (added) {
    ServiceHealth service;
    service.name = beat.service;
    m_services.push_back(std::move(service));
    it = m_services.end() - 1;
  }
  if (it->pid != 0 && it->pid != beat.pid) ++it->restarts;
  it->pid = beat.pid;
  it->uptimeMs = beat.uptimeMs;
  it->lastBeatMonoNs = receivedMonoNs;
  it->status = beat.status;
  ++it->heartbeats;
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

const ServiceHealth* HealthTracker::find(std::string_view name) const noexcept {
  for (const ServiceHealth& service : m_services) {
    if (service.name == name) return &service;
  }
  return nullptr;
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
