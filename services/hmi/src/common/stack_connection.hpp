#pragma once
// The HMI's connection to one stack instance: the configuration and catalog (loaded once),
// the shared-memory signal table (attached when a service has created it, retried once a
// second until then) and the LCM event bus (read through a QSocketNotifier on LCM's fd, so
// events are handled by the Qt event loop without a thread and without polling). Models
// read the table at display rate on `displayTick` and listen to the event signals below.
//
// One instance per process (StackConnection::instance()), created by main (or a test)
// before QML loads; QML reaches it as the singleton `Stack`.
// @note GUI thread only.

#include <QObject>
#include <QQmlEngine>
#include <QSocketNotifier>
#include <QString>
#include <QTimeZone>
#include <QTimer>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"
#endif

namespace openvcu::hmi {

/// The status values every model exposes; QML: ModelStatus.Ready, .Stale, .NotConnected, .Error.
class ModelStatus : public QObject {
  Q_OBJECT
  QML_ELEMENT
  QML_UNCREATABLE("ModelStatus holds the status enum only")
 public:
  enum Value { Ready = 0, Stale = 1, NotConnected = 2, Error = 3 };
  Q_ENUM(Value)
  static Value from(ValueStatus status) noexcept { return static_cast<Value>(status); }
};

/// What the HMI needs to know before it connects.
struct StackSettings {
  std::string configPath;
  std::string dashboardPath;     ///< empty: no dashboard tiles (dials only from defaults)
  std::string lcmUrl;            ///< empty: the configuration's
  std::string instance;          ///< empty: the configuration's
  std::string supervisorConfig;  ///< supervisord file for "restart a service"; empty: not offered
  std::string timeZone;          ///< IANA name for the header clock; empty: the system's
  std::string dataFolder;        ///< exports, recordings and the file browser's start; empty: $HOME/openvcu
  std::string vcuProgram;        ///< the `vcu` the Record button runs; empty: beside vcu-hmi, else PATH
  bool frameStreams{};           ///< subscribe to the raw frames over iceoryx (vcu-hmi: on; tests: off, no RouDi)
  int displayHz{10};             ///< text refresh; plots sample on their own timer
};

/// std::string -> QString (UTF-8), for every model of the HMI.
inline QString toQ(const std::string& text) { return QString::fromStdString(text); }

class StackConnection : public QObject {
  Q_OBJECT
  QML_NAMED_ELEMENT(Stack)
  QML_SINGLETON
  Q_PROPERTY(QString instance READ instanceName CONSTANT)
  Q_PROPERTY(QString configPath READ configPath CONSTANT)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value tableStatus READ tableStatus NOTIFY connectionChanged)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value eventStatus READ eventStatus NOTIFY connectionChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY connectionChanged)
  Q_PROPERTY(QString clockText READ clockText NOTIFY clockChanged)

 public:
  /// Loads the configuration and catalog; errors (bad file) are returned, never thrown.
  static Result<std::unique_ptr<StackConnection>> open(const StackSettings& settings);
  ~StackConnection() override;

  /// The process-wide instance (set by open(), cleared by the destructor).
  static StackConnection* instance() noexcept;
  /// QML singleton factory: the existing instance (owned by C++).
  static StackConnection* create(QQmlEngine* engine, QJSEngine* scriptEngine);

  [[nodiscard]] const config::VehicleConfig& config() const noexcept { return m_config; }
  [[nodiscard]] const sig::Catalog& catalog() const noexcept { return m_catalog; }
  [[nodiscard]] const StackSettings& settings() const noexcept { return m_settings; }
  /// The table, or nullptr while not attached.
  [[nodiscard]] const sig::SignalTable* table() const noexcept { return m_table ? &*m_table : nullptr; }
  /// The event bus, or nullptr while not open.
  [[nodiscard]] ipc::EventBus* events() noexcept { return m_events ? &*m_events : nullptr; }

  [[nodiscard]] QString instanceName() const { return QString::fromStdString(m_config.instance); }
  [[nodiscard]] QString configPath() const { return QString::fromStdString(m_config.path); }
  [[nodiscard]] ModelStatus::Value tableStatus() const noexcept { return m_tableStatus; }
  [[nodiscard]] ModelStatus::Value eventStatus() const noexcept { return m_eventStatus; }
  [[nodiscard]] QString errorString() const { return m_errorString; }
  [[nodiscard]] QString clockText() const { return m_clockText; }

  /// Sends a command through the stack's command sockets (request id, issuer and a deadline
  /// 2 s ahead filled in; a worker thread connects and waits, the GUI never blocks); the
  /// outcome arrives as commandFinished(requestId, accepted, text). The service never
  /// applies it after the deadline, the same instant at which the HMI shows "no answer".
  /// Returns the request id.
  std::int64_t sendCommand(ipc::CommandRequest request);

  /// Dispatches waiting LCM messages now (tests with memq://, which has no readable fd).
  void pumpEvents();
  /// Tries to attach the table / open the bus now (also done once a second).
  void reconnect();

 Q_SIGNALS:
  void connectionChanged();
  void clockChanged();
  /// At display rate: models read the table here.
  void displayTick();
  void heartbeat(const openvcu::ipc::Heartbeat& beat);
  /// vcu-can-tx's live transmit schedule, one part at a time.
  void txSchedule(const openvcu::ipc::TxSchedule& schedule);
  /// vcu-can-tx's view of one J1939 network (one message per bus, each second and on change).
  void j1939Network(const openvcu::ipc::J1939Network& network);
  void logRecord(const openvcu::ipc::LogRecord& record);
  void fsmTransition(const openvcu::ipc::FsmTransition& transition);
  void fault(const openvcu::ipc::FaultEvent& fault);
  void commandFinished(qint64 requestId, bool accepted, const QString& text);

 private:
  StackConnection(StackSettings settings, config::VehicleConfig config, sig::Catalog catalog);
  void openEvents();
  void attachTable();
  void onAck(const ipc::CommandAck& ack);
  void onCommandFailed(std::int64_t requestId, const std::string& reason);
  void commandWorker();
  void expireCommands();
  void everySecond();
  void publishHeartbeat();

  StackSettings m_settings;
  config::VehicleConfig m_config;
  sig::Catalog m_catalog;
  std::optional<sig::SignalTable> m_table;
  std::optional<ipc::EventBus> m_events;
  std::unique_ptr<QSocketNotifier> m_notifier;
  CommandTracker m_commands;
  // Commands go out one at a time on m_commandThread (connect + wait up to the deadline).
  std::mutex m_commandMutex;
  std::condition_variable m_commandWake;
  std::deque<ipc::CommandRequest> m_commandQueue;
  bool m_commandStop{false};
  std::thread m_commandThread;
  QTimer m_displayTimer;
  QTimer m_reconnectTimer;
  ModelStatus::Value m_tableStatus{ModelStatus::NotConnected};
  ModelStatus::Value m_eventStatus{ModelStatus::NotConnected};
  QString m_errorString;
  QString m_clockText;
  QTimeZone m_zone;
  std::optional<sig::SignalIndex> m_heartbeatSlot;
  std::int64_t m_beats{-1};  ///< -1: continue from the table's count at the first beat
  std::int64_t m_startedNs{};
};

}  // namespace openvcu::hmi
