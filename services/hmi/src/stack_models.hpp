#pragma once
// Models fed by the event plane (LCM) and the FSM: the operator switches with their
// acknowledgements (OperatorModel), the FSM state and its transition history (FsmModel),
// service health from heartbeats (HealthModel), the log of every service (LogModel) and
// the active faults (FaultModel). Each has `status` (ModelStatus) and `errorString`.
// @note GUI thread only.

#include <QAbstractListModel>
#include <QObject>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <map>
#include <optional>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "display_logic.hpp"
#include "stack_connection.hpp"
#endif

namespace openvcu::hmi {

/// The operator switches (internal.operator.* with two value texts, except FaultReset):
/// current position from the table, enabled when the FSM's current state reads the switch
/// (a transition may follow) or the switch is on (it can always be switched off), and the
/// answer to the last command. `toggle(row)` publishes an OperatorSwitch command.
class OperatorModel : public QAbstractListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY statusChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY statusChanged)
 public:
  enum Role { KeyRole = Qt::UserRole + 1, LabelRole, OnRole, StateTextRole, EnabledRole, ResultRole, PendingRole };
  explicit OperatorModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  /// Publishes the opposite position of row `row`; "" when sent, else why not.
  Q_INVOKABLE QString toggle(int row);
  /// Row of a key, -1 if none (tests, QML lookups).
  Q_INVOKABLE int rowOf(const QString& key) const;
  void refresh();
 Q_SIGNALS:
  void statusChanged();

 private:
  struct Row {
    QString key;
    QString label;
    sig::SignalIndex index{};
    double onValue{1};
    bool on{};
    QString stateText;
    bool enabled{};
    QString result;
    qint64 pendingId{-1};
  };
  std::vector<Row> m_rows;
  std::optional<FsmRules> m_rules;
  std::optional<sig::SignalIndex> m_stateIndex;
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
};

/// The FSM state (internal.fsm.state by name, since when) and the transitions heard on
/// LCM since the HMI started (newest first).
class FsmModel : public QAbstractListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString stateName READ stateName NOTIFY stateChanged)
  Q_PROPERTY(QString stateAge READ stateAge NOTIFY stateChanged)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY stateChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY stateChanged)
 public:
  enum Role { TimeRole = Qt::UserRole + 1, FromRole, ToRole, CauseRole };
  explicit FsmModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] QString stateName() const { return m_stateName; }
  [[nodiscard]] QString stateAge() const { return m_stateAge; }
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  void addTransition(const ipc::FsmTransition& transition);
  void refresh();
 Q_SIGNALS:
  void stateChanged();

 private:
  std::vector<ipc::FsmTransition> m_history;  ///< newest first, at most HISTORY
  std::optional<FsmRules> m_rules;
  std::optional<sig::SignalIndex> m_stateIndex;
  QString m_stateName{QStringLiteral("--")};
  QString m_stateAge;
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
};

/// One row per service: the configuration's services from the start (NotConnected until
/// heard), then whatever else sends heartbeats. CPU and RSS from /proc for local pids.
/// Aggregate status: Ready when every expected service beats, Stale when one is late,
/// NotConnected when none is heard. `connectionSummary` is for the header.
class HealthModel : public QAbstractListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY statusChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY statusChanged)
  Q_PROPERTY(QString systemText READ systemText NOTIFY statusChanged)
 public:
  enum Role {
    NameRole = Qt::UserRole + 1,
    PidRole,
    UptimeRole,
    RestartsRole,
    AgeRole,
    CpuRole,
    RssRole,
    StatusTextRole,
    ConnectionRole
  };
  explicit HealthModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  /// "up 2 h 4 min, load 0.52, memory 812 / 24105 MB"
  [[nodiscard]] QString systemText() const { return m_systemText; }
  /// The connection status of service `name` ("vcu-fsm"), NotConnected when unknown.
  Q_INVOKABLE int connectionOf(const QString& name) const;
  void onHeartbeat(const ipc::Heartbeat& beat);
  void refresh();
 Q_SIGNALS:
  void statusChanged();

 private:
  struct Cpu {
    std::int64_t ticks{-1};
    std::int64_t atNs{};
    double percent{};
    double rssMb{-1};
  };
  HealthTracker m_tracker;
  std::map<std::string, Cpu> m_cpu;
  int m_tick{};
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
  QString m_systemText;
};

/// The log of every service (LCM log records), newest last, filtered by service and
/// minimum level; `exportTo(path)` writes the filtered lines.
class LogModel : public QAbstractListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString serviceFilter READ serviceFilter WRITE setServiceFilter NOTIFY filterChanged)
  Q_PROPERTY(int minimumLevel READ minimumLevel WRITE setMinimumLevel NOTIFY filterChanged)
  Q_PROPERTY(QStringList services READ services NOTIFY servicesChanged)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY statusChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY statusChanged)
 public:
  enum Role { TimeRole = Qt::UserRole + 1, ServiceRole, LevelRole, LevelNameRole, TextRole };
  static constexpr std::size_t CAPACITY = 5000;
  explicit LogModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] QString serviceFilter() const { return m_service; }
  void setServiceFilter(const QString& service);
  [[nodiscard]] int minimumLevel() const noexcept { return m_minimum; }
  void setMinimumLevel(int level);
  [[nodiscard]] QStringList services() const;
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  /// Writes the shown lines to `path`; "" on success, else the reason.
  Q_INVOKABLE QString exportTo(const QString& path) const;
  void add(const ipc::LogRecord& record);
 Q_SIGNALS:
  void filterChanged();
  void servicesChanged();
  void statusChanged();

 private:
  void reselect();
  LogBuffer m_buffer{CAPACITY};
  std::vector<std::size_t> m_shown;
  QString m_service;
  int m_minimum{0};
  std::size_t m_serviceCount{};
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
};

/// Active faults from LCM fault events (raised adds, cleared removes), plus the DM1
/// summary of every node from the table (internal.dm1.<Node>.activeDtcs > 0).
/// `resetFaults()` publishes the operator's FaultReset switch.
class FaultModel : public QAbstractListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(int activeCount READ activeCount NOTIFY countChanged)
  Q_PROPERTY(QString lastResult READ lastResult NOTIFY countChanged)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY countChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY countChanged)
 public:
  enum Role { NameRole = Qt::UserRole + 1, SourceRole, SeverityRole, TextRole, TimeRole };
  explicit FaultModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] int activeCount() const noexcept { return static_cast<int>(m_faults.size()); }
  [[nodiscard]] QString lastResult() const { return m_lastResult; }
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  Q_INVOKABLE QString resetFaults();
  void onFault(const ipc::FaultEvent& event);
  void refresh();
 Q_SIGNALS:
  void countChanged();

 private:
  std::vector<ipc::FaultEvent> m_faults;
  std::vector<std::pair<std::string, sig::SignalIndex>> m_dm1;  ///< node -> activeDtcs slot
  qint64 m_pendingId{-1};
  QString m_lastResult;
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
};

/// Fixed-argv actions of the Debug tab: restart a service through supervisorctl, reboot
/// and shut down. Never a shell; the argv are built from fixed words plus a service name
/// that must be one of the configuration's services.
class SystemActions : public QObject {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString lastResult READ lastResult NOTIFY finished)
 public:
  explicit SystemActions(QObject* parent = nullptr);
  [[nodiscard]] QString lastResult() const { return m_lastResult; }
  /// The argv that restartService would run (tests, the confirmation dialog).
  Q_INVOKABLE QStringList restartArgv(const QString& service) const;
  Q_INVOKABLE QString restartService(const QString& service);
  /// `what`: "reboot" or "poweroff" (systemctl); anything else is refused.
  Q_INVOKABLE QString power(const QString& what);
 Q_SIGNALS:
  void finished();

 private:
  QString run(const QStringList& argv);
  QString m_lastResult;
};

}  // namespace openvcu::hmi
