#pragma once
// The Debug tab's active faults with their reset (FaultModel).
// @note GUI thread only.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "common/model_helpers.hpp"
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#include "openvcu/ipc/events.hpp"
#endif

namespace openvcu::hmi {

/// Active faults from LCM fault events (raised adds, cleared removes), plus the DM1
/// summary of every node from the table (internal.dm1.<Node>.activeDtcs > 0), plus
/// service_silent.<name> (source "heartbeats", CRITICAL) for every service that beat and
/// has not for 2.5 s, unless a fault event of that name (vcu-watchdog's) is listed.
/// `resetFaults()` publishes the operator's FaultReset switch.
class FaultModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(int activeCount READ activeCount NOTIFY countChanged)
  Q_PROPERTY(QString lastResult READ lastResult NOTIFY countChanged)
 public:
  enum Role { NameRole = Qt::UserRole + 1, SourceRole, SeverityRole, TextRole, TimeRole };
  explicit FaultModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] int activeCount() const noexcept { return static_cast<int>(m_faults.size()); }
  [[nodiscard]] QString lastResult() const { return m_lastResult; }
  Q_INVOKABLE QString resetFaults();
  void onFault(const ipc::FaultEvent& event);
  void refresh();
 Q_SIGNALS:
  void countChanged();

 private:
  void refreshSilent();

 private:
  std::vector<ipc::FaultEvent> m_faults;
  std::vector<std::pair<std::string, sig::SignalIndex>> m_dm1;  ///< node -> activeDtcs slot
  HealthTracker m_health;                                       ///< who beats, for the silent faults
  std::optional<HeartbeatSlots> m_slots;
  qint64 m_pendingId{-1};
  QString m_lastResult;
};

}  // namespace openvcu::hmi
