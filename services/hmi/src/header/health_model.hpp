#pragma once
// Service health from heartbeats: the header's dots and the Debug tab's table (HealthModel).
// @note GUI thread only.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <map>
#include <optional>
#include <string>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "common/model_helpers.hpp"
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#include "openvcu/ipc/events.hpp"
#endif

namespace openvcu::hmi {

/// One row per service: the configuration's services from the start (NotConnected until
/// heard), then whatever else beats (LCM heartbeats, or the table's heartbeat slots, which
/// also name services that stopped before the HMI started). A row never disappears; one
/// that beat and has not for 2.5 s says "silent for N s" (liveness "silent" or "stopped").
/// CPU and RSS from /proc for local pids.
/// Aggregate status: Ready when every expected service beats, Stale when one is late,
/// NotConnected when none is heard. `connectionSummary` is for the header.
class HealthModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
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
    ConnectionRole,
    LivenessRole  ///< "beating", "silent", "stopped", "not heard"
  };
  explicit HealthModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  /// "up 2 h 4 min, load 0.52, memory 812 / 24105 MB"
  [[nodiscard]] QString systemText() const { return m_systemText; }
  /// The connection status of service `name` ("vcu-fsm"), NotConnected when unknown.
  Q_INVOKABLE int connectionOf(const QString& name) const;
  void onHeartbeat(const ipc::Heartbeat& beat);
  void refresh();

 private:
  struct Cpu {
    std::int64_t ticks{-1};
    std::int64_t atNs{};
    double percent{};
    double rssMb{-1};
  };
  HealthTracker m_tracker;
  std::optional<HeartbeatSlots> m_slots;
  std::map<std::string, Cpu> m_cpu;
  int m_tick{};
  QString m_systemText;
};

}  // namespace openvcu::hmi
