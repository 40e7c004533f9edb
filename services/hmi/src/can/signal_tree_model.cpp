#include "can/signal_tree_model.hpp"

#include <algorithm>
#include <cmath>

#include "common/model_helpers.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/j1939/id.hpp"

namespace openvcu::hmi {

SignalTreeModel::SignalTreeModel(QObject* parent) : StatusListModel(parent) {
  build();
  rebuildVisible();
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::displayTick, this, &SignalTreeModel::refresh);
  }
}

SignalTreeModel::Node SignalTreeModel::makeNode(int depth, int parent, QString name, QString detail) {
  Node node;
  node.depth = depth;
  node.parent = parent;
  node.name = std::move(name);
  node.detail = std::move(detail);
  return node;
}

void SignalTreeModel::build() {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  const config::VehicleConfig& vehicle = stack->config();
  for (const config::BusConfig& bus : vehicle.buses) {
    const int busNode = static_cast<int>(m_nodes.size());
    m_nodes.push_back(makeNode(0, -1, toQ(bus.name), toQ(bus.link.toString())));
    m_nodes.back().expanded = true;
    std::map<std::string, std::vector<std::size_t>> byNode;
    for (const std::size_t messageIndex : bus.messages) {
      const dbc::Message& message = vehicle.database.messages[messageIndex];
      byNode[message.transmitter].push_back(messageIndex);
    }
    for (const auto& [nodeName, messages] : byNode) {
      const int nodeRow = static_cast<int>(m_nodes.size());
      m_nodes.push_back(makeNode(1, busNode, toQ(nodeName), QStringLiteral("%1 messages").arg(messages.size())));
      for (const std::size_t messageIndex : messages) {
        const dbc::Message& message = vehicle.database.messages[messageIndex];
        QString detail = hexText(message.id, message.extended ? 8 : 3);
        if (message.isJ1939()) detail += QStringLiteral("  PGN %1").arg(j1939::pgnOf(message.id));
        detail += message.cycleTimeMs ? QStringLiteral("  cycle %1 ms").arg(*message.cycleTimeMs)
                                      : QStringLiteral("  no cycle");
        const int messageRow = static_cast<int>(m_nodes.size());
        m_nodes.push_back(makeNode(2, nodeRow, toQ(message.name), detail));
        for (const dbc::Signal& signal : message.signals) {
          const std::string key = config::signalKey(message, signal);
          const auto index = stack->catalog().indexOf(key);
          if (!index) continue;
          if (!m_nodes[static_cast<std::size_t>(messageRow)].rateIndex)
            m_nodes[static_cast<std::size_t>(messageRow)].rateIndex = index;
          m_nodes.push_back(makeNode(3, messageRow, toQ(signal.name), toQ(signal.unit)));
          m_nodes.back().key = toQ(key);
          m_nodes.back().index = index;
        }
      }
    }
  }
  m_status = ModelStatus::NotConnected;
}

void SignalTreeModel::rebuildVisible() {
  beginResetModel();
  m_visible.clear();
  const bool searching = !m_search.isEmpty();
  if (searching) {
    for (Node& node : m_nodes) node.matches = false;
    for (std::size_t i = 0; i < m_nodes.size(); ++i) {
      Node& node = m_nodes[i];
      if (node.name.contains(m_search, Qt::CaseInsensitive) || node.key.contains(m_search, Qt::CaseInsensitive)) {
        node.matches = true;
        for (int parent = node.parent; parent >= 0; parent = m_nodes[static_cast<std::size_t>(parent)].parent) {
          m_nodes[static_cast<std::size_t>(parent)].matches = true;
        }
      }
    }
  }
  for (std::size_t i = 0; i < m_nodes.size(); ++i) {
    const Node& node = m_nodes[i];
    if (searching) {
      if (node.matches) m_visible.push_back(static_cast<int>(i));
      continue;
    }
    bool shown = true;
    for (int parent = node.parent; parent >= 0; parent = m_nodes[static_cast<std::size_t>(parent)].parent) {
      if (!m_nodes[static_cast<std::size_t>(parent)].expanded) {
        shown = false;
        break;
      }
    }
    if (shown) m_visible.push_back(static_cast<int>(i));
  }
  endResetModel();
}

void SignalTreeModel::setSearch(const QString& search) {
  if (search == m_search) return;
  m_search = search;
  Q_EMIT searchChanged();
  rebuildVisible();
}

void SignalTreeModel::toggle(int row) {
  if (row < 0 || row >= static_cast<int>(m_visible.size())) return;
  Node& node = m_nodes[static_cast<std::size_t>(m_visible[static_cast<std::size_t>(row)])];
  if (node.depth == 3) return;
  node.expanded = !node.expanded;
  rebuildVisible();
}

int SignalTreeModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_visible.size());
}

QVariant SignalTreeModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= static_cast<int>(m_visible.size())) return {};
  const Node& node = m_nodes[static_cast<std::size_t>(m_visible[static_cast<std::size_t>(index.row())])];
  switch (role) {
    case DepthRole:
      return node.depth;
    case NameRole:
    case Qt::DisplayRole:
      return node.name;
    case DetailRole:
      if (node.depth == 2 && node.rateHz >= 0)
        return node.detail + QStringLiteral("  measured %1 Hz").arg(node.rateHz, 0, 'f', 1);
      return node.detail;
    case ValueRole:
      return node.value;
    case KeyRole:
      return node.key;
    case ExpandedRole:
      return node.expanded;
    case StatusRole:
      return static_cast<int>(node.status);
    case CommentRole: {
      StackConnection* stack = StackConnection::instance();
      return stack && node.index ? toQ(stack->catalog()[*node.index].comment) : QString();
    }
    default:
      return {};
  }
}

QHash<int, QByteArray> SignalTreeModel::roleNames() const {
  return {{DepthRole, "depth"}, {NameRole, "name"},         {DetailRole, "detail"},      {ValueRole, "valueText"},
          {KeyRole, "key"},     {ExpandedRole, "expanded"}, {StatusRole, "valueStatus"}, {CommentRole, "comment"}};
}

void SignalTreeModel::refresh() {
  StackConnection* stack = StackConnection::instance();
  const ModelStatus::Value status = stack && stack->table() ? ModelStatus::Ready : ModelStatus::NotConnected;
  if (status != m_status) {
    m_status = status;
    Q_EMIT statusChanged();
  }
  if (!stack || !stack->table()) return;
  const std::int64_t now = clock::monotonicNs();
  // Only the visible rows are read: the tree may hold thousands of signals.
  for (std::size_t row = 0; row < m_visible.size(); ++row) {
    Node& node = m_nodes[static_cast<std::size_t>(m_visible[row])];
    bool changed = false;
    if (node.depth == 3 && node.index) {
      const auto slot = stack->table()->read(*node.index);
      if (!slot) continue;
      const ValueStatus valueStatus = classify(*slot, now, staleAfterFor(stack->catalog()[*node.index], 2'000'000'000));
      QString text = QStringLiteral("--");
      if (const auto shown = shownValue(stack->catalog()[*node.index], *slot)) {
        text = toQ(formatValue(stack->catalog()[*node.index], *shown, ""));
      }
      changed = text != node.value || valueStatus != node.status;
      node.value = text;
      node.status = valueStatus;
    } else if (node.depth == 2 && node.rateIndex) {
      const auto bus = stack->table()->readBus(*node.rateIndex);
      if (!bus) continue;
      if (node.lastRateNs == 0) {
        node.lastRateNs = now;
        node.lastUpdates = bus->updates;
      } else if (now - node.lastRateNs >= 1'000'000'000) {
        const double rate =
            static_cast<double>(bus->updates - node.lastUpdates) * 1e9 / static_cast<double>(now - node.lastRateNs);
        changed = std::fabs(rate - node.rateHz) > 0.05;
        node.rateHz = rate;
        node.lastRateNs = now;
        node.lastUpdates = bus->updates;
      }
    }
    if (changed) {
      const QModelIndex at = index(static_cast<int>(row));
      Q_EMIT dataChanged(at, at, {ValueRole, StatusRole, DetailRole});
    }
  }
}

}  // namespace openvcu::hmi
