#include "openvcu/service/service.hpp"

#include <unistd.h>

#include <cstdlib>
#include <iostream>

#include "openvcu/check/vehicle_check.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/core/input_file.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace openvcu::service {

namespace {

LoggerOptions loggerOptions(ipc::LogLevel threshold) {
  LoggerOptions options;
  options.threshold = threshold;
  // systemd connects stderr to the journal and says so in JOURNAL_STREAM: the journal adds
  // its own time stamp and program name, and reads the "<N>" priority prefix.
  options.journalFormat = std::getenv("JOURNAL_STREAM") != nullptr;
  return options;
}

}  // namespace

int reportStartupError(const ServiceInfo& info, const Error& error) {
  std::cerr << info.programName() << ": error: " << error.toString() << std::endl;
  // A start-up that a SIGTERM/SIGINT cut short (a long DBC read stops on it) is an orderly
  // stop, not a failure: exit 0 as after any SIGTERM.
  if (input::stopSignalPending()) return static_cast<int>(ExitCode::Ok);
  return static_cast<int>(ExitCode::Failure);
}

Service::Service(ServiceInfo info, ServiceOptions options, ShutdownSignals signals)
    : m_info(std::move(info)),
      m_options(std::move(options)),
      m_program(m_info.programName()),
      m_signals(std::move(signals)),
      m_logger(m_program, loggerOptions(m_options.logLevel)),
      m_notifier(Notifier::fromEnvironment()),
      m_start(std::chrono::steady_clock::now()) {}

Service::~Service() {
  // The loop stops watching the command socket before the handler closes it.
  if (m_commands && m_loop) m_loop->removeFd(m_commands->fd());
  m_commands.reset();
  m_logger.attachEventBus(nullptr);
}

Result<std::unique_ptr<Service>> Service::open(ServiceInfo info, ServiceOptions options) {
  // First, before anything can start a thread (iceoryx, LCM, the Waiter's fd watcher).
  auto signalsResult = ShutdownSignals::install();
  if (!signalsResult) return signalsResult.error();
  std::unique_ptr<Service> service(new Service(std::move(info), std::move(options), std::move(*signalsResult)));
  if (auto started = service->start(); !started) return started.error();
  return service;
}

Status Service::checkWholeVehicle() {
  // The files of the vehicle checked together (docs/config.md, "Whole-vehicle checks"), as
  // `vcu check` does: the first error refuses the start, warnings and notes are logged once.
  std::optional<Error> firstError;
  std::size_t errors = 0;
  for (const Error& diagnostic : check::checkVehicle(m_config, m_catalog)) {
    if (diagnostic.severity == Severity::Error) {
      if (!firstError) firstError = diagnostic;
      ++errors;
    } else if (diagnostic.severity == Severity::Warning) {
      m_logger.warning(diagnostic.toString());
    } else {
      m_logger.info(diagnostic.toString());
    }
  }
  if (!firstError) return {};
  if (errors > 1) {
    firstError->message += " (" + std::to_string(errors - 1) + " more: vcu check --config " + m_options.configPath + ")";
  }
  return *firstError;
}

Status Service::start() {
  // The writer id is part of the contract (config/services.hpp): a known service with
  // another id would make its table writes look like someone else's.
  if (const config::ServiceEntry* known = config::findService(m_info.name);
      known != nullptr && known->writer != m_info.writerId) {
    return Error{"service '" + m_info.name + "' has writer id " + std::to_string(m_info.writerId) +
                 ", config::SERVICES gives it " + std::to_string(known->writer)};
  }
  if (m_info.writerId == 0) return Error{"service '" + m_info.name + "' has writer id 0 (reserved for 'never written')"};
  std::vector<Error> warnings;
  auto configResult = config::loadVehicleConfig(m_options.configPath, &warnings);
  if (!configResult) return configResult.error();
  m_config = std::move(*configResult);
  for (const Error& warning : warnings) m_logger.warning(warning.toString());
  if (!m_options.instance.empty()) {
    if (!config::validInstanceName(m_options.instance)) {
      return Error{"--instance '" + m_options.instance + "': must be 1-32 letters, digits, '-' or '_'"};
    }
    m_config.instance = m_options.instance;
  }

  auto catalogResult = config::buildCatalog(m_config);
  if (!catalogResult) return Error{m_options.configPath + ": " + catalogResult.error().message};
  m_catalog = std::move(*catalogResult);
  if (auto checked = checkWholeVehicle(); !checked) return checked;

  auto tableResult = signals::SignalTable::open(m_catalog, m_config.instance);
  if (!tableResult) return tableResult.error();
  m_table.emplace(std::move(*tableResult));

  auto eventsResult = ipc::EventBus::open(m_config.lcmUrl, m_config.instance);
  if (!eventsResult) return eventsResult.error();
  m_events.emplace(std::move(*eventsResult));
  m_logger.attachEventBus(&*m_events);

  if (m_info.usesFrameStreams) {
    if (auto initialised = ipc::Runtime::init(m_program + "." + m_config.instance, ROUDI_WAIT); !initialised) {
      return initialised.error();
    }
  }

  auto loopResult = Loop::create();
  if (!loopResult) return loopResult.error();
  m_loop.emplace(std::move(*loopResult));
  if (auto added = m_loop->addFd(m_signals.fd(), [this] { onShutdownSignal(); }); !added) return added;
  if (auto added = m_loop->addFd(m_events->fileno(), [this] { m_events->handleAll(); }); !added) return added;

  const std::string slotKey = heartbeatKey(m_info.name);
  const auto maybeSlot = m_catalog.indexOf(slotKey);
  m_heartbeat.emplace(m_program, m_config.instance, &*m_events, &*m_table, maybeSlot, m_info.writerId);
  m_heartbeat->addCounterSource("log_suppressed", [this] { return static_cast<std::int64_t>(m_logger.suppressed()); });
  m_heartbeat->addCounterSource("table_damage", [this] { return m_tableDamage; });
  m_heartbeat->addCounterSource("event_errors", [this] {
    return static_cast<std::int64_t>(m_events->publishFailures() + m_events->decodeErrors() +
                                     m_events->callbackErrors());
  });
  auto heartbeatTimer = PeriodicTimer::create(HEARTBEAT_PERIOD);
  if (!heartbeatTimer) return heartbeatTimer.error();
  m_heartbeatTimer.emplace(std::move(*heartbeatTimer));
  if (auto added = m_loop->addTimer(*m_heartbeatTimer, [this](const TimerTick&) { onHeartbeatTick(); }); !added) {
    return added;
  }
  if (const auto maybeInterval = m_notifier.watchdogInterval()) {
    auto watchdogTimer = PeriodicTimer::create(*maybeInterval);
    if (!watchdogTimer) return watchdogTimer.error();
    m_watchdogTimer.emplace(std::move(*watchdogTimer));
    if (auto added = m_loop->addTimer(*m_watchdogTimer, [this](const TimerTick&) { m_notifier.watchdog(); }); !added) {
      return added;
    }
  }

  const signals::TableInfo tableInfo = m_table->info();
  m_logger.info("started: configuration " + m_config.path + ", instance " + m_config.instance + ", " +
                std::to_string(m_catalog.size()) + " signals, table '" + tableInfo.name + "' " +
                (tableInfo.createdByThisProcess
                     ? "created"
                     : "attached (created by pid " + std::to_string(tableInfo.creatorPid) + ")") +
                ", events " + m_config.lcmUrl);
  if (!maybeSlot) {
    m_logger.warning("no heartbeat slot '" + slotKey + "' in the catalog: heartbeats go to LCM only");
  }
  return {};
}

void Service::setStatus(std::string status) {
  m_notifier.status(status);
  m_heartbeat->setStatus(std::move(status));
}

Status Service::answerCommands(CommandPolicy policy) {
  if (m_commands) return Error{"answerCommands: this service already answers commands"};
  auto handler = std::make_unique<CommandHandler>(m_catalog, *m_table, *m_events, m_program, m_info.writerId,
                                                  std::move(policy), &m_logger);
  if (auto listening = handler->listen(m_config.instance, m_config.commandGroup); !listening) return listening;
  CommandHandler* commands = handler.get();
  if (auto added = m_loop->addFd(handler->fd(), [commands] { commands->onReadable(); }); !added) return added;
  m_commands = std::move(handler);
  m_logger.info("commands on " + m_commands->listener()->path() +
                (m_commands->listener()->groupAccess()
                     ? " (root, this user and group '" + m_config.commandGroup + "')"
                     : " (root and this user only: group '" + m_config.commandGroup + "' does not exist)"));
  m_heartbeat->addCounterSource("commands_accepted",
                                [this] { return static_cast<std::int64_t>(m_commands->accepted()); });
  m_heartbeat->addCounterSource("commands_refused",
                                [this] { return static_cast<std::int64_t>(m_commands->refused()); });
  m_heartbeat->addCounterSource("commands_expired",
                                [this] { return static_cast<std::int64_t>(m_commands->expired()); });
  m_heartbeat->addCounterSource("commands_limited",
                                [this] { return static_cast<std::int64_t>(m_commands->limited()); });
  return {};
}

void Service::markReady() {
  if (m_ready) return;
  m_ready = true;
  if (m_heartbeat->status() == "starting") m_heartbeat->setStatus("ready");
  // Log first: whoever reacts to READY=1 finds the "ready" line already written.
  m_logger.info("ready (pid " + std::to_string(::getpid()) + ", instance " + m_config.instance +
                (m_notifier.enabled() ? ", sending READY=1 to " + m_notifier.socketPath() : std::string()) + ")");
  m_notifier.ready(m_heartbeat->status());
  m_heartbeat->beat();
}

void Service::onHeartbeatTick() {
  // A truncated or overwritten table (docs/design/signal-table.md, "Damage"): the table
  // library has absorbed the bus error and restored the segment; say so once, here.
  if (const auto maybeDamage = m_table->checkAndRepair()) {
    ++m_tableDamage;
    m_logger.error(maybeDamage->describe(m_table->info().name));
  }
  m_heartbeat->beat();
  // Once a second: a RouDi restarted under this process has cut its iceoryx ports off for
  // good (iceoryx 2.0 cannot re-register them), so end with a code the supervisor restarts.
  if (m_info.usesFrameStreams && !m_stopping && ipc::Runtime::roudiReplaced()) {
    m_logger.error("iox-roudi was restarted (" + std::string(ipc::ROUDI_SOCKET_PATH) +
                   " is a new socket): this process's frame streams are cut off; exiting with code " +
                   std::to_string(static_cast<int>(ExitCode::RoudiRestarted)) + " for the supervisor to restart it");
    m_loop->stop(static_cast<int>(ExitCode::RoudiRestarted));
  }
}

void Service::onShutdownSignal() {
  const auto maybeSignal = m_signals.take();
  if (!maybeSignal) return;
  beginStopping("stopping (" + signalName(*maybeSignal) + ")");
  m_loop->stop(static_cast<int>(ExitCode::Ok));
}

void Service::beginStopping(const std::string& reason) {
  if (m_stopping) return;
  m_stopping = true;
  m_logger.info(reason);
  m_notifier.stopping(reason);
  m_heartbeat->setStatus(reason);
  m_heartbeat->beat();  // the last one says why it is the last
}

int Service::run() {
  if (!m_ready && !m_readinessDeferred) markReady();
  const int exitCode = m_loop->run();
  beginStopping("stopping (exit code " + std::to_string(exitCode) + ")");
  return exitCode;
}

void Service::stop(int exitCode) {
  m_loop->stop(exitCode);
}

std::chrono::milliseconds Service::uptime() const noexcept {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - m_start);
}

}  // namespace openvcu::service
