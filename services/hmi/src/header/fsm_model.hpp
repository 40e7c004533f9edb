#pragma once
// The FSM state shown in the header and its transition history on the Debug tab (FsmModel).
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
#include "openvcu/ipc/events.hpp"
#endif

namespace openvcu::hmi {

/// The FSM state (internal.fsm.state by name, since when) and the transitions heard on
/// LCM since the HMI started (newest first). The state is vcu-fsm's: while vcu-fsm does not
/// beat (LCM heartbeat or its table slot, 2.5 s), the model is Stale and `stateNote` says
/// "vcu-fsm silent for 4 s: last state, not current" (empty while it beats).
class FsmModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString stateName READ stateName NOTIFY stateChanged)
  Q_PROPERTY(QString stateAge READ stateAge NOTIFY stateChanged)
  Q_PROPERTY(QString stateNote READ stateNote NOTIFY stateChanged)
 public:
  enum Role { TimeRole = Qt::UserRole + 1, FromRole, ToRole, CauseRole };
  explicit FsmModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] QString stateName() const { return m_stateName; }
  [[nodiscard]] QString stateAge() const { return m_stateAge; }
  [[nodiscard]] QString stateNote() const { return m_stateNote; }
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
  QString m_stateNote;
  HealthTracker m_writer;  ///< vcu-fsm's liveness
  std::optional<HeartbeatSlots> m_slots;
};

}  // namespace openvcu::hmi
