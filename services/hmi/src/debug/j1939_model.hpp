#pragma once
// The Debug tab's J1939 page: vcu-can-tx's view of each J1939 network (the VCU's address
// claim, the other nodes, its DTCs and DM1 lamps) as rows; the logic is J1939Networks.
// @note GUI thread only.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#include "debug/j1939_networks.hpp"
#endif

namespace openvcu::hmi {

/// One row per line of `vcu j1939`, per bus (latest view wins; a bus not heard for 3 s is
/// Stale, its last view still shown). Status: Ready when every bus is fresh, Stale when one
/// is not, NotConnected without the event bus or before any view.
class J1939Model : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
 public:
  /// J1939Row::Kind for QML: J1939Model.Claim, .Node, .Dtc, .Lamps, .Note.
  enum Kind { Claim = 0, Node, Dtc, Lamps, Note };
  Q_ENUM(Kind)
  enum Role {
    KindRole = Qt::UserRole + 1,
    BusRole,
    BusStatusRole,  ///< ModelStatus of the row's bus
    AddressRole,
    NameRole,
    LabelRole,
    SpnRole,
    FmiRole,
    OccurrencesRole,
    ActiveRole,
    AlertRole
  };
  explicit J1939Model(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  /// A view received at `receivedMonoNs` (the stack's signal and the tests call it).
  void applyNetwork(const ipc::J1939Network& network, std::int64_t receivedMonoNs);
  /// Shows the views and their freshness at `nowNs` (each display tick; tests set the clock).
  void refresh(std::int64_t nowNs);

 private:
  /// Replaces the rows by `rows`, telling the views only what changed.
  void showRows(std::vector<J1939Row> rows);
  J1939Networks m_networks;
  std::vector<J1939Row> m_rows;
  std::vector<ValueStatus> m_shownStatus;  ///< per bus, as last shown
  bool m_dirty{true};
};

}  // namespace openvcu::hmi
