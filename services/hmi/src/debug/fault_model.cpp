#include "debug/fault_model.hpp"

#include <algorithm>

#include "openvcu/config/catalog.hpp"
#include "openvcu/core/clock.hpp"

namespace openvcu::hmi {
namespace {

constexpr std::string_view FAULT_RESET_KEY = "internal.operator.FaultReset";

}  // namespace

FaultModel::FaultModel(QObject* parent)
    : StatusListModel(parent), m_health(display::expectedServices(), display::HEARTBEAT_STALE_NS) {
  // the base's status and errorString are notified with countChanged(), where this model sets them
  connect(this, &FaultModel::countChanged, this, &StatusListModel::statusChanged);
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  const signals::Catalog& catalog = stack->catalog();
  for (signals::SignalIndex i = 0; i < catalog.size(); ++i) {
    const std::string& key = catalog[i].key;
    if (key.starts_with("internal.dm1.") && key.ends_with(".activeDtcs")) {
      m_dm1.emplace_back(key.substr(13, key.size() - 13 - 11), i);
    }
  }
  connect(stack, &StackConnection::fault, this, &FaultModel::onFault);
  connect(stack, &StackConnection::heartbeat, this,
          [this](const ipc::Heartbeat& beat) { m_health.onHeartbeat(beat, clock::monotonicNs()); });
  m_slots.emplace(catalog);
  connect(stack, &StackConnection::displayTick, this, &FaultModel::refresh);
  connect(stack, &StackConnection::commandFinished, this, [this](qint64 id, bool, const QString& text) {
    if (id != m_pendingId) return;
    m_pendingId = -1;
    m_lastResult = QStringLiteral("fault reset: ") + text;
    Q_EMIT countChanged();
  });
}

int FaultModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_faults.size());
}

QVariant FaultModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount()) return {};
  const ipc::FaultEvent& fault = m_faults[static_cast<std::size_t>(index.row())];
  switch (role) {
    case NameRole:
    case Qt::DisplayRole:
      return toQ(fault.name);
    case SourceRole:
      return toQ(fault.source);
    case SeverityRole:
      return static_cast<int>(fault.severity);
    case TextRole:
      return toQ(fault.text);
    case TimeRole:
      return clockText(fault.timestampNs);
    default:
      return {};
  }
}

QHash<int, QByteArray> FaultModel::roleNames() const {
  return {
      {NameRole, "name"}, {SourceRole, "source"}, {SeverityRole, "severity"}, {TextRole, "text"}, {TimeRole, "time"}};
}

void FaultModel::onFault(const ipc::FaultEvent& event) {
  const auto it = std::find_if(m_faults.begin(), m_faults.end(), [&](const ipc::FaultEvent& known) {
    return known.name == event.name && known.source == event.source;
  });
  if (event.active) {
    if (it != m_faults.end()) {
      *it = event;
      const int row = static_cast<int>(it - m_faults.begin());
      Q_EMIT dataChanged(index(row), index(row));
    } else {
      beginInsertRows({}, rowCount(), rowCount());
      m_faults.push_back(event);
      endInsertRows();
    }
  } else if (it != m_faults.end()) {
    const int row = static_cast<int>(it - m_faults.begin());
    beginRemoveRows({}, row, row);
    m_faults.erase(it);
    endRemoveRows();
  }
  Q_EMIT countChanged();
}

void FaultModel::refresh() {
  StackConnection* stack = StackConnection::instance();
  const ModelStatus::Value status = stack && stack->events() ? ModelStatus::Ready : ModelStatus::NotConnected;
  // DM1 summaries from the table: a node with active DTCs is a fault row of its own.
  if (stack && stack->table()) {
    for (const auto& [node, slot] : m_dm1) {
      const auto bus = stack->table()->readBus(slot);
      if (!bus || bus->updates == 0) continue;
      const bool active = bus->value > 0;
      const std::string name = "dm1." + node;
      const bool known = std::any_of(m_faults.begin(), m_faults.end(), [&](const ipc::FaultEvent& fault) {
        return fault.name == name && fault.source == "DM1";
      });
      if (active == known) continue;
      ipc::FaultEvent event{
          .timestampNs = QDateTime::currentMSecsSinceEpoch() * 1'000'000,
          .name = name,
          .source = "DM1",
          .severity = ipc::FaultSeverity::Error,
          .active = active,
          .text = std::to_string(static_cast<long long>(bus->value)) + " active DTC(s) (J1939-73 DM1)"};
      onFault(event);
    }
  }
  refreshSilent();
  if (status != m_status) {
    m_status = status;
    Q_EMIT countChanged();
  }
}

void FaultModel::refreshSilent() {
  StackConnection* stack = StackConnection::instance();
  if (m_slots && stack && stack->table()) m_slots->feed(m_health, *stack->table());
  const std::vector<ipc::FaultEvent> silent =
      m_health.silentFaults(clock::monotonicNs(), QDateTime::currentMSecsSinceEpoch() * 1'000'000);
  // ours end when the service beats again, or give way to a fault event of the same name
  for (std::size_t i = m_faults.size(); i-- > 0;) {
    const ipc::FaultEvent& fault = m_faults[i];
    if (fault.source != display::SILENT_FAULT_SOURCE) continue;
    const bool namedByEvent = std::any_of(m_faults.begin(), m_faults.end(), [&](const ipc::FaultEvent& other) {
      return other.name == fault.name && other.source != display::SILENT_FAULT_SOURCE;
    });
    if (namedByEvent || !display::namesFault(silent, fault.name)) {
      ipc::FaultEvent cleared = fault;
      cleared.active = false;
      onFault(cleared);
    }
  }
  for (const ipc::FaultEvent& fault : silent) {
    if (!display::namesFault(m_faults, fault.name)) onFault(fault);
  }
}

QString FaultModel::resetFaults() {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return QStringLiteral("not connected");
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::SetSignal;
  request.key = std::string(FAULT_RESET_KEY);
  request.value = 1;
  request.text = "vcu-hmi fault reset";
  m_pendingId = stack->sendCommand(std::move(request));
  m_lastResult = m_pendingId < 0 ? QStringLiteral("fault reset not sent: no event bus")
                                 : QStringLiteral("fault reset: waiting for the answer");
  Q_EMIT countChanged();
  return m_pendingId < 0 ? m_lastResult : QString();
}

}  // namespace openvcu::hmi
