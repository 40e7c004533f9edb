#include "common/stack_connection.hpp"

#include <time.h>
#include <unistd.h>

#include <QDateTime>
#include <QJSEngine>

#include "openvcu/core/clock.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/ipc/command_socket.hpp"

namespace openvcu::hmi {
namespace {

StackConnection* g_instance = nullptr;

/// Who the HMI says it is in commands and heartbeats.
constexpr const char* ISSUER = "vcu-hmi";
/// An operator command not answered within this time is shown as "no answer".
constexpr std::int64_t ACK_TIMEOUT_NS = 2'000'000'000;
/// The HMI's writer id (config/services.hpp).
constexpr signals::WriterId HMI_WRITER = config::writerOf(config::ServiceId::Hmi);

}  // namespace

Result<std::unique_ptr<StackConnection>> StackConnection::open(const StackSettings& settings) {
  auto configResult = config::loadVehicleConfig(settings.configPath);
  if (!configResult) return configResult.error();
  config::VehicleConfig vehicle = std::move(*configResult);
  if (!settings.instance.empty()) {
    if (!config::validInstanceName(settings.instance)) {
      return Error{"--instance '" + settings.instance + "': must be 1-32 letters, digits, '-' or '_'"};
    }
    vehicle.instance = settings.instance;
  }
  if (!settings.lcmUrl.empty()) vehicle.lcmUrl = settings.lcmUrl;
  auto catalogResult = config::buildCatalog(vehicle);
  if (!catalogResult) return Error{settings.configPath + ": " + catalogResult.error().message};
  std::unique_ptr<StackConnection> connection(
      new StackConnection(settings, std::move(vehicle), std::move(*catalogResult)));
  return connection;
}

StackConnection::StackConnection(StackSettings settings, config::VehicleConfig vehicle, signals::Catalog catalog)
    : m_settings(std::move(settings)),
      m_config(std::move(vehicle)),
      m_catalog(std::move(catalog)),
      m_commands(ISSUER, ipc::randomRequestId(), ACK_TIMEOUT_NS) {
  g_instance = this;
  const int hz = m_settings.displayHz > 0 ? m_settings.displayHz : 10;
  m_displayTimer.setInterval(1000 / hz);
  connect(&m_displayTimer, &QTimer::timeout, this, [this] {
    expireCommands();
    Q_EMIT displayTick();
  });
  m_displayTimer.start();
  m_reconnectTimer.setInterval(1000);
  connect(&m_reconnectTimer, &QTimer::timeout, this, &StackConnection::everySecond);
  m_reconnectTimer.start();
  m_startedNs = clock::monotonicNs();
  m_zone = m_settings.timeZone.empty() ? QTimeZone::systemTimeZone()
                                       : QTimeZone(QByteArray::fromStdString(m_settings.timeZone));
  m_heartbeatSlot = m_catalog.indexOf("internal.service.hmi.heartbeat");
  reconnect();
  everySecond();
}

void StackConnection::everySecond() {
  reconnect();
  m_clockText = QDateTime::currentDateTime().toTimeZone(m_zone).toString(QStringLiteral("HH:mm:ss"));
  Q_EMIT clockChanged();
  publishHeartbeat();
}

void StackConnection::publishHeartbeat() {
  if (m_table && m_heartbeatSlot) {
    // the bus plane, like every service (docs/design/service-runtime.md); continues after a restart
    if (m_beats < 0) {
      const auto previous = m_table->readBus(*m_heartbeatSlot);
      m_beats = previous && previous->updates > 0 ? static_cast<std::int64_t>(previous->value) : 0;
    }
    ++m_beats;
    m_table->writeBus(*m_heartbeatSlot, static_cast<double>(m_beats), clock::monotonicNs(), HMI_WRITER,
                      signals::Quality::Valid);
  }
  if (!m_events) return;
  ipc::Heartbeat beat;
  beat.service = ISSUER;
  beat.instance = m_config.instance;
  beat.pid = static_cast<std::int32_t>(::getpid());
  beat.uptimeMs = (clock::monotonicNs() - m_startedNs) / 1'000'000;
  beat.counters = {{"commands_pending", static_cast<std::int64_t>(m_commands.pending())},
                   {"event_errors", static_cast<std::int64_t>(m_events->decodeErrors() + m_events->callbackErrors() +
                                                              m_events->publishFailures())}};
  beat.status = m_table ? "ready" : "waiting for the signal table";
  m_events->publish(beat);
}

StackConnection::~StackConnection() {
  {
    std::lock_guard lock(m_commandMutex);
    m_commandStop = true;
  }
  m_commandWake.notify_all();
  if (m_commandThread.joinable()) m_commandThread.join();  // at most one command's deadline
  m_notifier.reset();
  if (g_instance == this) g_instance = nullptr;
}

StackConnection* StackConnection::instance() noexcept {
  return g_instance;
}

StackConnection* StackConnection::create(QQmlEngine*, QJSEngine*) {
  if (g_instance) QJSEngine::setObjectOwnership(g_instance, QJSEngine::CppOwnership);
  return g_instance;
}

void StackConnection::reconnect() {
  if (!m_events) openEvents();
  if (!m_table) attachTable();
}

void StackConnection::openEvents() {
  auto busResult = ipc::EventBus::open(m_config.lcmUrl, m_config.instance);
  if (!busResult) {
    m_eventStatus = ModelStatus::Error;
    m_errorString = QString::fromStdString(busResult.error().toString());
    Q_EMIT connectionChanged();
    return;
  }
  m_events.emplace(std::move(*busResult));
  ipc::EventBus& bus = *m_events;
  bool subscribed =
      bus.onHeartbeat([this](const ipc::Heartbeat& beat) { Q_EMIT heartbeat(beat); }) &&
      bus.onSchedule([this](const ipc::TxSchedule& schedule) { Q_EMIT txSchedule(schedule); }) &&
      bus.onJ1939Network([this](const ipc::J1939Network& network) { Q_EMIT j1939Network(network); }) &&
      bus.onLog([this](const ipc::LogRecord& record) { Q_EMIT logRecord(record); }) &&
      bus.onFsmTransition([this](const ipc::FsmTransition& transition) { Q_EMIT fsmTransition(transition); }) &&
      bus.onFault([this](const ipc::FaultEvent& event) { Q_EMIT fault(event); });
  // Answers to the HMI's commands come only from the command sockets (commandWorker): an
  // ack on the event bus could be forged by anyone on the host.
  if (!subscribed) {
    m_events.reset();
    m_eventStatus = ModelStatus::Error;
    m_errorString = "cannot subscribe to the event channels of " + QString::fromStdString(m_config.instance);
    Q_EMIT connectionChanged();
    return;
  }
  if (const int fd = bus.fileno(); fd >= 0) {
    m_notifier = std::make_unique<QSocketNotifier>(fd, QSocketNotifier::Read);
    connect(m_notifier.get(), &QSocketNotifier::activated, this, &StackConnection::pumpEvents);
  }
  m_eventStatus = ModelStatus::Ready;
  if (m_tableStatus != ModelStatus::Error) m_errorString.clear();
  Q_EMIT connectionChanged();
}

void StackConnection::attachTable() {
  auto tableResult = signals::SignalTable::open(m_catalog, m_config.instance, signals::OpenMode::AttachOnly);
  if (!tableResult) {
    m_tableStatus = ModelStatus::NotConnected;
    m_errorString = QString::fromStdString(tableResult.error().toString());
    Q_EMIT connectionChanged();
    return;
  }
  m_table.emplace(std::move(*tableResult));
  m_tableStatus = ModelStatus::Ready;
  if (m_eventStatus != ModelStatus::Error) m_errorString.clear();
  Q_EMIT connectionChanged();
}

void StackConnection::pumpEvents() {
  if (m_events) m_events->handleAll();
}

std::int64_t StackConnection::sendCommand(ipc::CommandRequest request) {
  const std::int64_t now = clock::monotonicNs();
  m_commands.prepare(request, now);
  request.timestampNs = 0;
  request.deadlineNs = m_commands.deadlineOf(request.requestId);  // the tracker's timeout, same clock
  const std::int64_t id = request.requestId;
  {
    std::lock_guard lock(m_commandMutex);
    m_commandQueue.push_back(std::move(request));
  }
  if (!m_commandThread.joinable()) m_commandThread = std::thread([this] { commandWorker(); });
  m_commandWake.notify_one();
  return id;
}

void StackConnection::commandWorker() {
  std::unique_lock lock(m_commandMutex);
  while (true) {
    m_commandWake.wait(lock, [this] { return m_commandStop || !m_commandQueue.empty(); });
    if (m_commandStop) return;
    ipc::CommandRequest request = std::move(m_commandQueue.front());
    m_commandQueue.pop_front();
    lock.unlock();
    const std::int64_t id = request.requestId;
    std::optional<ipc::CommandAck> answer;
    std::string failure;
    if (auto client = ipc::CommandClient::connect(m_config.instance); !client) {
      failure = client.error().message;
    } else if (auto sent = client->send(std::move(request), std::chrono::nanoseconds(ACK_TIMEOUT_NS)); !sent) {
      failure = sent.error().message;
    } else {
      answer = *sent;
    }
    // Back to the GUI thread; dropped by Qt if this object is gone by then.
    QMetaObject::invokeMethod(
        this,
        [this, id, answer = std::move(answer), failure = std::move(failure)] {
          if (answer) {
            onAck(*answer);
          } else {
            onCommandFailed(id, failure);
          }
        },
        Qt::QueuedConnection);
    lock.lock();
  }
}

void StackConnection::onCommandFailed(std::int64_t requestId, const std::string& reason) {
  if (m_commands.forget(requestId)) Q_EMIT commandFinished(requestId, false, QString::fromStdString("not applied: " + reason));
}

void StackConnection::onAck(const ipc::CommandAck& ack) {
  if (auto outcome = m_commands.onAck(ack)) {
    Q_EMIT commandFinished(outcome->first, outcome->second.state == CommandOutcome::State::Accepted,
                           QString::fromStdString(outcome->second.text));
  }
}

void StackConnection::expireCommands() {
  if (m_commands.pending() == 0) return;
  for (auto& [id, outcome] : m_commands.expire(clock::monotonicNs())) {
    Q_EMIT commandFinished(id, false, QString::fromStdString(outcome.text));
  }
}

}  // namespace openvcu::hmi
