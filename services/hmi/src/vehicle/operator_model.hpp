#pragma once
// The Vehicle tab's operator switches with their acknowledgements (OperatorModel).
// @note GUI thread only.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <optional>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "common/model_helpers.hpp"
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#endif

namespace openvcu::hmi {

/// The operator switches (internal.operator.* with two value texts, except FaultReset):
/// current position from the table, enabled when the FSM's current state reads the switch
/// (a transition may follow) or the switch is on (it can always be switched off), and the
/// answer to the last command. `toggle(row)` publishes an OperatorSwitch command.
class OperatorModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
 public:
  enum Role { KeyRole = Qt::UserRole + 1, LabelRole, OnRole, StateTextRole, EnabledRole, ResultRole, PendingRole };
  explicit OperatorModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  /// Publishes the opposite position of row `row`; "" when sent, else why not.
  Q_INVOKABLE QString toggle(int row);
  /// Row of a key, -1 if none (tests, QML lookups).
  Q_INVOKABLE int rowOf(const QString& key) const;
  void refresh();
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
};

}  // namespace openvcu::hmi
