#pragma once
// The ECU Setup tab's model: the transmit schedule can-tx runs, as rows of signals, edited
// through acknowledged commands (docs/design/hmi.md, "ECU Setup").

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <map>
#include <optional>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#endif

namespace openvcu::hmi {

/// The transmit schedule of this VCU as rows of signals with the value commanded and the
/// override. Until vcu-can-tx's live schedule arrives (ipc::TxSchedule on the SCHEDULE
/// channel): the messages its DBC node transmits, the DBC cycle and the J1939-76 pairs of
/// the schedule file; from then on what can-tx actually runs (cycle, enabled, added per
/// message), including messages added at run
/// time, which get rows of their own. Edits are commands to can-tx and the owning services:
/// setCycle (ScheduleCycle), setEnabled (ScheduleEnable), addMessage (ScheduleAdd),
/// setDefault (ScheduleDefault), setOverride / clearOverride; each is checked here first
/// (range, integer ms) and then acknowledged or refused by the stack.
class ScheduleModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString lastResult READ lastResult NOTIFY statusChanged)
 public:
  enum Role {
    MessageRole = Qt::UserRole + 1,
    SignalRole,
    CycleRole,
    PairRole,
    DeltaRole,
    ValueRole,
    OverrideRole,
    OverriddenRole,
    KeyRole,
    RangeRole,
    LiveRole,     ///< cycle and enable come from can-tx's live schedule (else from the DBC)
    EnabledRole,  ///< can-tx sends the message
    AddedRole     ///< added at run time (ScheduleAdd)
  };
  explicit ScheduleModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] QString lastResult() const { return m_lastResult; }
  /// Each returns "" when sent (the outcome follows in lastResult) or the local refusal.
  Q_INVOKABLE QString setCycle(int row, const QString& milliseconds);
  Q_INVOKABLE QString setOverride(int row, const QString& value);
  /// The schedule's value for the signal (sent while nothing commands it): ScheduleDefault.
  Q_INVOKABLE QString setDefault(int row, const QString& value);
  Q_INVOKABLE QString clearOverride(int row);
  /// ScheduleEnable for the row's message.
  Q_INVOKABLE QString setEnabled(int row, bool enabled);
  /// ScheduleAdd: the DBC message `name` joins the schedule, every `milliseconds`.
  Q_INVOKABLE QString addMessage(const QString& name, const QString& milliseconds);
  /// DBC messages on a configured bus that have no rows yet (not safety headers), whose
  /// name contains `filter` (case-insensitive), sorted.
  Q_INVOKABLE QStringList candidates(const QString& filter) const;
  /// The first row of `message`, or -1.
  Q_INVOKABLE int rowOfMessage(const QString& message) const;
  /// Applies vcu-can-tx's live schedule (tests call it directly).
  void applySchedule(const ipc::TxSchedule& live);
 private:
  struct Row {
    std::size_t messageIndex{};
    QString message;
    QString signal;
    QString key;
    std::optional<sig::SignalIndex> index;
    int cycleMs{};
    bool pair{};
    int deltaUs{};
    QString value;
    QString overrideText;
    bool overridden{};
    bool live{};
    bool enabled{true};
    bool added{};
  };
  /// Appends the rows of DBC message `messageIndex` to `rows`.
  void appendRows(std::vector<Row>& rows, std::size_t messageIndex, bool pair, int deltaUs) const;
  void build();
  void refresh();
  QString send(ipc::CommandRequest request, const QString& what);
  /// The number typed for row `row` (a number or a value text), checked against the DBC
  /// range; empty with *refusal set otherwise.
  std::optional<double> checkedValue(int row, const QString& text, QString* refusal) const;
  /// Checks `value` for `row` and sends `kind` with it; `what` has %1 (the signal) and %2
  /// (the value). "" once sent, else the refusal.
  QString sendValue(int row, const QString& value, ipc::CommandKind kind, const QString& what);
  std::vector<Row> m_rows;
  struct Pending {
    int row{};
    int cycleMs{};  ///< > 0: a cycle change to show once accepted
    QString what;
  };
  std::map<qint64, Pending> m_pending;
  QString m_lastResult;
};

}  // namespace openvcu::hmi
