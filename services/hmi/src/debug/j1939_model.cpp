#include "debug/j1939_model.hpp"

#include "common/model_helpers.hpp"
#include "openvcu/core/clock.hpp"

namespace openvcu::hmi {
namespace {

/// The configuration's buses with a "j1939" object: listed before can-tx reports them.
std::vector<std::string> expectedBuses() {
  std::vector<std::string> names;
  if (StackConnection* stack = StackConnection::instance()) {
    for (const config::BusConfig& bus : stack->config().buses) {
      if (bus.j1939) names.push_back(bus.name);
    }
  }
  return names;
}

DbcNodeNames dbcNodes() {
  StackConnection* stack = StackConnection::instance();
  return stack ? dbcNodesByAddress(stack->config().database) : DbcNodeNames{};
}

}  // namespace

J1939Model::J1939Model(QObject* parent)
    : StatusListModel(parent), m_networks(expectedBuses(), dbcNodes(), J1939_STALE_AFTER_NS) {
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::j1939Network, this,
            [this](const ipc::J1939Network& network) { applyNetwork(network, clock::monotonicNs()); });
    connect(stack, &StackConnection::displayTick, this, [this] { refresh(clock::monotonicNs()); });
  }
  refresh(clock::monotonicNs());
}

void J1939Model::applyNetwork(const ipc::J1939Network& network, std::int64_t receivedMonoNs) {
  m_networks.onNetwork(network, receivedMonoNs);
  m_dirty = true;
}

void J1939Model::refresh(std::int64_t nowNs) {
  StackConnection* stack = StackConnection::instance();
  const ModelStatus::Value status = stack && stack->events() ? ModelStatus::from(m_networks.overall(nowNs))
                                                             : ModelStatus::NotConnected;
  if (status != m_status) {
    m_status = status;
    Q_EMIT statusChanged();
  }
  // rows again only when a view arrived or a bus's freshness changed (no work per tick else)
  bool changed = m_dirty || m_shownStatus.size() != m_networks.busCount();
  m_shownStatus.resize(m_networks.busCount(), ValueStatus::Error);
  for (std::size_t i = 0; i < m_networks.busCount(); ++i) {
    const ValueStatus busStatus = m_networks.statusOf(i, nowNs);
    if (busStatus != m_shownStatus[i]) changed = true;
    m_shownStatus[i] = busStatus;
  }
  if (!changed) return;
  m_dirty = false;
  showRows(m_networks.rows(nowNs));
}

void J1939Model::showRows(std::vector<J1939Row> rows) {
  // the rows that differ lie between a common head and a common tail: change, remove or
  // insert only those (a list scrolled by the operator stays where it is)
  const std::size_t oldCount = m_rows.size();
  const std::size_t newCount = rows.size();
  std::size_t head = 0;
  while (head < oldCount && head < newCount && m_rows[head] == rows[head]) ++head;
  std::size_t tail = 0;
  while (tail < oldCount - head && tail < newCount - head && m_rows[oldCount - 1 - tail] == rows[newCount - 1 - tail]) {
    ++tail;
  }
  const std::size_t oldMiddle = oldCount - head - tail;
  const std::size_t newMiddle = newCount - head - tail;
  const std::size_t common = std::min(oldMiddle, newMiddle);
  const int first = static_cast<int>(head);
  if (oldMiddle > newMiddle) {
    beginRemoveRows({}, first + static_cast<int>(common), first + static_cast<int>(oldMiddle) - 1);
    m_rows.erase(m_rows.begin() + static_cast<std::ptrdiff_t>(head + common),
                 m_rows.begin() + static_cast<std::ptrdiff_t>(head + oldMiddle));
    endRemoveRows();
  } else if (newMiddle > oldMiddle) {
    beginInsertRows({}, first + static_cast<int>(common), first + static_cast<int>(newMiddle) - 1);
    m_rows.insert(m_rows.begin() + static_cast<std::ptrdiff_t>(head + common),
                  rows.begin() + static_cast<std::ptrdiff_t>(head + common),
                  rows.begin() + static_cast<std::ptrdiff_t>(head + newMiddle));
    endInsertRows();
  }
  for (std::size_t i = head; i < head + common; ++i) m_rows[i] = std::move(rows[i]);
  if (common > 0) Q_EMIT dataChanged(index(first), index(first + static_cast<int>(common) - 1));
}

int J1939Model::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_rows.size());
}

QVariant J1939Model::data(const QModelIndex& index, int role) const {
  const J1939Row* row = rowAt(m_rows, index);
  if (!row) return {};
  switch (role) {
    case KindRole:
      return static_cast<int>(row->kind);
    case BusRole:
      return toQ(row->bus);
    case BusStatusRole:
      return static_cast<int>(ModelStatus::from(row->busStatus));
    case AddressRole:
      return toQ(row->address);
    case NameRole:
      return toQ(row->name);
    case LabelRole:
    case Qt::DisplayRole:
      return toQ(row->label);
    case SpnRole:
      return static_cast<uint>(row->spn);
    case FmiRole:
      return static_cast<int>(row->fmi);
    case OccurrencesRole:
      return static_cast<int>(row->occurrences);
    case ActiveRole:
      return row->active;
    case AlertRole:
      return row->alert;
    default:
      return {};
  }
}

QHash<int, QByteArray> J1939Model::roleNames() const {
  return {{KindRole, "kind"},     {BusRole, "bus"},   {BusStatusRole, "busStatus"},
          {AddressRole, "address"}, {NameRole, "nodeName"}, {LabelRole, "label"},
          {SpnRole, "spn"},       {FmiRole, "fmi"},   {OccurrencesRole, "occurrences"},
          {ActiveRole, "active"}, {AlertRole, "alert"}};
}

}  // namespace openvcu::hmi
