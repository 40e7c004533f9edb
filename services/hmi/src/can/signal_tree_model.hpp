#pragma once
// The CAN Data tab's DBC tree with live values and measured message rates (SignalTreeModel),
// read at display rate (StackConnection's displayTick), never per CAN frame.
// @note GUI thread only.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <optional>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#endif

namespace openvcu::hmi {

/// The DBC tree flattened into rows with a depth (bus 0, node 1, message 2, signal 3) for a
/// ListView: expand/collapse per row, a search that shows matching signals with their
/// parents. Message rows show ID, PGN, DBC cycle and the measured rate (updates of the
/// message's first signal per second); signal rows the current value.
class SignalTreeModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString search READ search WRITE setSearch NOTIFY searchChanged)
 public:
  enum Role {
    DepthRole = Qt::UserRole + 1,
    NameRole,
    DetailRole,
    ValueRole,
    KeyRole,
    ExpandedRole,
    StatusRole,
    CommentRole
  };
  explicit SignalTreeModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] QString search() const { return m_search; }
  void setSearch(const QString& search);
  Q_INVOKABLE void toggle(int row);
  /// Nodes of the whole tree (for tests): buses + nodes + messages + signals.
  [[nodiscard]] std::size_t nodeCount() const noexcept { return m_nodes.size(); }
 Q_SIGNALS:
  void searchChanged();

 private:
  struct Node {
    int depth{};
    int parent{-1};
    QString name;
    QString detail;
    QString key;  ///< signals only
    std::optional<sig::SignalIndex> index;
    bool expanded{};
    bool matches{true};
    // message rows: measured rate
    std::optional<sig::SignalIndex> rateIndex;
    std::uint64_t lastUpdates{};
    std::int64_t lastRateNs{};
    double rateHz{-1};
    QString value;
    ValueStatus status{ValueStatus::NotConnected};
  };
  static Node makeNode(int depth, int parent, QString name, QString detail);
  void build();
  void rebuildVisible();
  void refresh();
  std::vector<Node> m_nodes;
  std::vector<int> m_visible;
  QString m_search;
};

}  // namespace openvcu::hmi
