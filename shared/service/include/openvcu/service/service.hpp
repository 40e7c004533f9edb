#pragma once
// The runtime every openvcu service stands on: configuration, signal table, event bus,
// logging, heartbeat, readiness, orderly shutdown and the loop, opened in one call so that
// a service's main stays about 40 lines (STYLE.md 1).
//
//   int main(int argc, char** argv) {
//     service::CommandLine commandLine(INFO);
//     if (const auto maybeExit = commandLine.parseOrExit(argc, argv)) return *maybeExit;
//     auto serviceResult = service::Service::open(INFO, commandLine.options());
//     if (!serviceResult) return service::reportStartupError(INFO, serviceResult.error());
//     service::Service& runtime = **serviceResult;
//     if (auto answering = runtime.answerCommands(service::CommandPolicy::byPrefix("internal.")); !answering)
//       return service::reportStartupError(INFO, answering.error());
//     return runtime.run();            // ready, then until SIGTERM/SIGINT: exit code 0
//   }
//
// open() in order: blocks SIGTERM/SIGINT (signalfd; before any thread exists), loads the
// configuration (--instance overrides its instance), builds the catalog, runs the
// whole-vehicle checks (check::checkVehicle: an error refuses, warnings are logged), attaches to (or
// creates) the signal table, opens the event bus at the configuration's LCM URL, registers
// with iox-roudi when the service uses frame streams, and puts the signalfd, the bus and
// the heartbeat timer into the loop. Any failure is one Error whose message says what and
// where ("vehicle.json: /buses/0/link: ..."); main prints it and exits with 1.
//
// Readiness (docs/design/service-runtime.md): run() (or markReady()) sends READY=1 on
// NOTIFY_SOCKET when set, logs "ready", and the heartbeat status becomes "ready". On
// SIGTERM/SIGINT: STOPPING=1, "stopping (SIGTERM)" log and heartbeat, exit code 0.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/service/command_handler.hpp"
#include "openvcu/service/heartbeat.hpp"
#include "openvcu/service/logger.hpp"
#include "openvcu/service/loop.hpp"
#include "openvcu/service/notify.hpp"
#include "openvcu/service/options.hpp"
#include "openvcu/service/shutdown.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::service {

/// How often the heartbeat is sent (both planes).
inline constexpr std::chrono::seconds HEARTBEAT_PERIOD{1};
/// How long open() waits for iox-roudi to answer (services that use frame streams).
inline constexpr std::chrono::seconds ROUDI_WAIT{5};

/// Prints "<program>: error: <message>" on stderr; returns ExitCode::Failure (1).
int reportStartupError(const ServiceInfo& info, const Error& error);

/// @note restricted thread-safe: everything on the thread that called open() and run();
///       logging (log()) and ipc::EventBus::publish from any thread.
class Service {
 public:
  /// Opens everything a service needs (see the file comment). Not movable: the loop's
  /// callbacks refer to it, hence the unique_ptr.
  static Result<std::unique_ptr<Service>> open(ServiceInfo info, ServiceOptions options);

  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;
  ~Service();

  [[nodiscard]] const ServiceInfo& info() const noexcept { return m_info; }
  /// "vcu-fsm": in logs, heartbeats and acks.
  [[nodiscard]] const std::string& program() const noexcept { return m_program; }
  /// The instance in use (--instance, else the configuration's).
  [[nodiscard]] const std::string& instance() const noexcept { return m_config.instance; }
  [[nodiscard]] const config::VehicleConfig& config() const noexcept { return m_config; }
  [[nodiscard]] const signals::Catalog& catalog() const noexcept { return m_catalog; }
  [[nodiscard]] signals::SignalTable& table() noexcept { return *m_table; }
  [[nodiscard]] ipc::EventBus& events() noexcept { return *m_events; }
  [[nodiscard]] Logger& log() noexcept { return m_logger; }
  [[nodiscard]] Loop& loop() noexcept { return *m_loop; }
  [[nodiscard]] HeartbeatPublisher& heartbeat() noexcept { return *m_heartbeat; }
  [[nodiscard]] Notifier& notifier() noexcept { return m_notifier; }

  /// A heartbeat counter (see HeartbeatPublisher::addCounter).
  CounterRef addCounter(std::string name) { return m_heartbeat->addCounter(std::move(name)); }
  /// The heartbeat status (and the supervisor's STATUS=) from now on.
  void setStatus(std::string status);

  /// Answers operator commands for the keys `policy` owns (one CommandHandler per
  /// service; counters "commands_accepted" and "commands_refused" join the heartbeat).
  Status answerCommands(CommandPolicy policy);
  /// The handler created by answerCommands, or nullptr.
  [[nodiscard]] CommandHandler* commands() noexcept { return m_commands.get(); }

  /// run() marks the service ready as it enters the loop, unless this was called: then
  /// the service calls markReady() itself once it really serves (e.g. its buses are open).
  void deferReadiness() noexcept { m_readinessDeferred = true; }
  /// READY=1 on NOTIFY_SOCKET, the log line "ready (...)", heartbeat status "ready" and an
  /// immediate heartbeat. Idempotent.
  void markReady();
  [[nodiscard]] bool ready() const noexcept { return m_ready; }

  /// Runs the loop until SIGTERM/SIGINT or stop(). On the way out: STOPPING=1, log line
  /// and a last heartbeat with status "stopping (SIGTERM)". Returns the exit code: 0 after
  /// a signal, else the one given to stop().
  int run();
  /// Makes run() return `exitCode` (e.g. 1 after a fatal error the service logged).
  void stop(int exitCode);

  /// Uptime since open().
  [[nodiscard]] std::chrono::milliseconds uptime() const noexcept;

 private:
  Service(ServiceInfo info, ServiceOptions options, ShutdownSignals signals);
  Status start();
  Status checkWholeVehicle();
  void onShutdownSignal();
  void onHeartbeatTick();
  void beginStopping(const std::string& reason);

  ServiceInfo m_info;
  ServiceOptions m_options;
  std::string m_program;
  ShutdownSignals m_signals;
  Logger m_logger;
  Notifier m_notifier;
  config::VehicleConfig m_config;
  signals::Catalog m_catalog;
  // Destroyed in reverse: the command handler unsubscribes, then the loop stops watching
  // (and its Waiter's fd thread ends) before the timers, the bus and the table it watched go.
  std::optional<signals::SignalTable> m_table;
  std::optional<ipc::EventBus> m_events;
  std::optional<PeriodicTimer> m_heartbeatTimer;
  std::optional<PeriodicTimer> m_watchdogTimer;
  std::optional<HeartbeatPublisher> m_heartbeat;
  std::optional<Loop> m_loop;
  std::unique_ptr<CommandHandler> m_commands;
  std::chrono::steady_clock::time_point m_start;
  std::string m_stopReason;
  std::int64_t m_tableDamage{0};  ///< damage episodes reported (heartbeat "table_damage")
  bool m_readinessDeferred{false};
  bool m_ready{false};
  bool m_stopping{false};
};

}  // namespace openvcu::service
