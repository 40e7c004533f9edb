#pragma once
// The services' health as heartbeats show it: one row per service, with restarts counted
// from pid changes, a status from the age of the last beat, and the silent services (beat
// before, not now) as faults.
//
// Two planes tell that a service beats: its LCM heartbeat (pid, uptime, status) and its
// heartbeat slot "internal.service.<name>.heartbeat" in the signal table (the time of the
// last beat, also for a service that stopped before the display started). A service that
// beat on either plane and has beaten on neither for longer than the stale limit is silent:
// hung (SIGSTOP, a deadlock, an endless loop), stopped or dead. A display then shows it as
// silent, never its last status as current, and lists the fault service_silent.<name>.
//
//   HealthTracker health(expectedServices(), HEARTBEAT_STALE_NS);
//   HeartbeatSlots slots(catalog);
//   health.onHeartbeat(beat, clock::monotonicNs());         // LCM
//   slots.feed(health, table);                              // the table, before each view
//   health.silentFor(*health.find("vcu-fsm"), now)          // 4.2e9 ns: vcu-fsm is silent

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "openvcu/display/values.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::display {

struct ServiceHealth {
  std::string name;  ///< "vcu-fsm"
  std::int32_t pid{};
  std::int64_t uptimeMs{};
  int restarts{};                   ///< pid changes seen by this tracker
  std::int64_t lastBeatMonoNs{-1};  ///< the newest beat on either plane (CLOCK_MONOTONIC); -1: never
  std::string status;               ///< the last LCM heartbeat's status line ("ready"); empty: none heard
  std::int64_t heartbeats{};        ///< LCM heartbeats heard
};

/// The services every stack runs ("vcu-can-rx", ...: config::SERVICES but the HMI and
/// vcu-web, which a VCU may run without): listed from the start, NotConnected until heard.
[[nodiscard]] std::vector<std::string> expectedServices();

/// Heartbeats come once a second: a service not heard for 2.5 s is Stale and silent (vcu-web's
/// live pages, `vcu status`, `vcu top` and vcu-telemetry's health messages use this; the HMI
/// has its own setting).
inline constexpr std::int64_t HEARTBEAT_STALE_NS = 2'500'000'000;

/// The source of the fault a display derives itself from the heartbeats it sees.
inline constexpr std::string_view SILENT_FAULT_SOURCE = "heartbeats";

/// The fault a display lists for a silent program: faults::serviceSilent (openvcu/config/faults.hpp)
/// of its service, the name vcu-watchdog raises too; a display lists one of the two.
/// "vcu-fsm" -> "service_silent.fsm" (a name without "vcu-" is kept as it is).
[[nodiscard]] std::string silentFaultName(std::string_view program);

/// A fault's severity as the pages and the telemetry messages name it: "info", "warning",
/// "error", "critical".
[[nodiscard]] std::string_view faultSeverityName(ipc::FaultSeverity severity) noexcept;

/// Whether a service is alive as its beats show: Beating (a beat within the stale limit),
/// Silent (beat before, not within it), Stopped (silent, and its last heartbeat said
/// "stopping ..."), NotHeard (never beat on either plane).
enum class Liveness : std::uint8_t { Beating, Silent, Stopped, NotHeard };

/// "beating", "silent", "stopped", "not heard".
[[nodiscard]] std::string_view livenessName(Liveness liveness) noexcept;

/// Heartbeats -> one row per service. The expected services (from the configuration) are
/// listed from the start as NotConnected. Beats older than `staleAfterNs` make a service
/// Stale (and silent); three times that, NotConnected; a service whose status starts with
/// "stopping" is NotConnected. A row never disappears.
/// @note not thread-safe: one thread feeds and reads it.
class HealthTracker {
 public:
  HealthTracker(std::vector<std::string> expected, std::int64_t staleAfterNs);
  /// Returns true when a new service appeared (the row list grew).
  bool onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs);
  /// A beat seen in the table's heartbeat slot of `program` at `beatMonoNs` (the slot's write
  /// time): moves the last beat forward, never back. Returns true when a new service appeared.
  bool onSlotBeat(std::string_view program, std::int64_t beatMonoNs);
  [[nodiscard]] ValueStatus statusOf(const ServiceHealth& service, std::int64_t nowNs) const noexcept;
  [[nodiscard]] Liveness livenessOf(const ServiceHealth& service, std::int64_t nowNs) const noexcept;
  /// How long a silent (or stopped) service has not beaten; empty while it beats or when
  /// it never did.
  [[nodiscard]] std::optional<std::int64_t> silentFor(const ServiceHealth& service, std::int64_t nowNs) const noexcept;
  /// The fault events of every silent service (name service_silent.<name>, source
  /// SILENT_FAULT_SOURCE, CRITICAL, time stamp = the last beat on CLOCK_REALTIME given
  /// `nowRealNs`), in row order.
  [[nodiscard]] std::vector<ipc::FaultEvent> silentFaults(std::int64_t nowMonoNs, std::int64_t nowRealNs) const;
  [[nodiscard]] const std::vector<ServiceHealth>& services() const noexcept { return m_services; }
  [[nodiscard]] const ServiceHealth* find(std::string_view name) const noexcept;
  [[nodiscard]] std::int64_t staleAfterNs() const noexcept { return m_staleAfterNs; }

 private:
  ServiceHealth& row(std::string_view name, bool& added);
  std::vector<ServiceHealth> m_services;
  std::int64_t m_staleAfterNs;
};

/// The heartbeat slots of a catalog ("internal.service.<name>.heartbeat" of every service in
/// config::SERVICES the catalog has), looked up once.
/// @note feed() is noexcept for known rows and allocation-free once every service has a row.
class HeartbeatSlots {
 public:
  explicit HeartbeatSlots(const signals::Catalog& catalog);
  /// Reads each slot's bus plane and passes written ones to `tracker.onSlotBeat`. Returns true
  /// when a row was added.
  bool feed(HealthTracker& tracker, const signals::SignalTable& table) const;

 private:
  std::vector<std::pair<std::string, signals::SignalIndex>> m_slots;  ///< "vcu-fsm", its slot
};

/// Whether the faults `shown` already hold one named `name` (from any source).
[[nodiscard]] bool namesFault(const std::vector<ipc::FaultEvent>& shown, std::string_view name) noexcept;

}  // namespace openvcu::display
