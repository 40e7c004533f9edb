#pragma once
// The services' health as heartbeats show it: one row per service, with restarts counted
// from pid changes and a status from the age of the last beat.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/display/values.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::display {

struct ServiceHealth {
  std::string name;  ///< "vcu-fsm"
  std::int32_t pid{};
  std::int64_t uptimeMs{};
  int restarts{};                   ///< pid changes seen by this tracker
  std::int64_t lastBeatMonoNs{-1};  ///< when the last heartbeat arrived (receiver clock); -1: never
  std::string status;
  std::int64_t heartbeats{};
};

/// The services every stack runs ("vcu-can-rx", ...: config::SERVICES but the HMI and
/// vcu-web, which a VCU may run without): listed from the start, NotConnected until heard.
[[nodiscard]] std::vector<std::string> expectedServices();

/// Heartbeats come once a second: a service not heard for 2.5 s is Stale (vcu-web's live
/// pages and vcu-telemetry's health messages use this; the HMI has its own setting).
inline constexpr std::int64_t HEARTBEAT_STALE_NS = 2'500'000'000;

/// A fault's severity as the pages and the telemetry messages name it: "info", "warning",
/// "error", "critical".
[[nodiscard]] std::string_view faultSeverityName(ipc::FaultSeverity severity) noexcept;

/// Heartbeats -> one row per service. The expected services (from the configuration) are
/// listed from the start as NotConnected. Beats older than `staleAfterNs` make a service
/// Stale; three times that, NotConnected; a service whose status starts with "stopping"
/// is NotConnected.
/// @note not thread-safe: one thread feeds and reads it.
class HealthTracker {
 public:
  HealthTracker(std::vector<std::string> expected, std::int64_t staleAfterNs);
  /// Returns true when a new service appeared (the row list grew).
  bool onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs);
  [[nodiscard]] ValueStatus statusOf(const ServiceHealth& service, std::int64_t nowNs) const noexcept;
  [[nodiscard]] const std::vector<ServiceHealth>& services() const noexcept { return m_services; }
  [[nodiscard]] const ServiceHealth* find(std::string_view name) const noexcept;

 private:
  std::vector<ServiceHealth> m_services;
  std::int64_t m_staleAfterNs;
};

}  // namespace openvcu::display
