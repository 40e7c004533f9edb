#include "vehicle/operator_model.hpp"

#include "openvcu/config/catalog.hpp"

namespace openvcu::hmi {
namespace {

constexpr std::string_view OPERATOR_PREFIX = "internal.operator.";
constexpr std::string_view FAULT_RESET_KEY = "internal.operator.FaultReset";

}  // namespace

OperatorModel::OperatorModel(QObject* parent) : StatusListModel(parent) {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  m_rules = loadRules(m_error);
  if (!m_error.isEmpty()) m_status = ModelStatus::Error;
  m_stateIndex = stack->catalog().indexOf("internal.fsm.state");
  const signals::Catalog& catalog = stack->catalog();
  for (signals::SignalIndex i = 0; i < catalog.size(); ++i) {
    const signals::SignalInfo& info = catalog[i];
    if (!info.key.starts_with(OPERATOR_PREFIX) || info.key == FAULT_RESET_KEY) continue;
    Row row;
    row.key = toQ(info.key);
    row.index = i;
    row.label = toQ(info.key.substr(OPERATOR_PREFIX.size()));
    if (info.valueTexts.size() >= 2) {
      row.label = toQ(info.valueTexts.back().second);
      row.onValue = static_cast<double>(info.valueTexts.back().first);
      if (row.label == QStringLiteral("Start")) row.label = QStringLiteral("Start / Stop");
    }
    m_rows.push_back(std::move(row));
  }
  connect(stack, &StackConnection::displayTick, this, &OperatorModel::refresh);
  connect(stack, &StackConnection::commandFinished, this, [this](qint64 id, bool, const QString& text) {
    for (std::size_t i = 0; i < m_rows.size(); ++i) {
      if (m_rows[i].pendingId != id) continue;
      m_rows[i].pendingId = -1;
      m_rows[i].result = text;
      Q_EMIT dataChanged(index(static_cast<int>(i)), index(static_cast<int>(i)), {ResultRole, PendingRole});
    }
  });
  refresh();
}

int OperatorModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_rows.size());
}

QVariant OperatorModel::data(const QModelIndex& index, int role) const {
  const Row* row = rowAt(m_rows, index);
  if (!row) return {};
  switch (role) {
    case KeyRole:
      return row->key;
    case LabelRole:
    case Qt::DisplayRole:
      return row->label;
    case OnRole:
      return row->on;
    case StateTextRole:
      return row->stateText;
    case EnabledRole:
      return row->enabled;
    case ResultRole:
      return row->result;
    case PendingRole:
      return row->pendingId >= 0;
    default:
      return {};
  }
}

QHash<int, QByteArray> OperatorModel::roleNames() const {
  return {{KeyRole, "key"},         {LabelRole, "label"},   {OnRole, "on"},          {StateTextRole, "stateText"},
          {EnabledRole, "allowed"}, {ResultRole, "result"}, {PendingRole, "pending"}};
}

int OperatorModel::rowOf(const QString& key) const {
  for (std::size_t i = 0; i < m_rows.size(); ++i) {
    if (m_rows[i].key == key) return static_cast<int>(i);
  }
  return -1;
}

QString OperatorModel::toggle(int row) {
  if (row < 0 || row >= static_cast<int>(m_rows.size())) return QStringLiteral("no such switch");
  Row& entry = m_rows[static_cast<std::size_t>(row)];
  if (!entry.enabled) return QStringLiteral("not allowed in the current state");
  StackConnection* stack = StackConnection::instance();
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::SetSignal;  // as `vcu signal set`: the FSM owns internal.operator.*
  request.key = entry.key.toStdString();
  request.value = entry.on ? 0.0 : entry.onValue;
  request.text = "vcu-hmi operator switch";
  const std::int64_t id = stack->sendCommand(std::move(request));
  if (id < 0) {
    entry.result = QStringLiteral("not sent: no event bus");
    Q_EMIT dataChanged(index(row), index(row), {ResultRole});
    return entry.result;
  }
  entry.pendingId = id;
  entry.result = QStringLiteral("waiting for the answer");
  Q_EMIT dataChanged(index(row), index(row), {ResultRole, PendingRole});
  return {};
}

void OperatorModel::refresh() {
  StackConnection* stack = StackConnection::instance();
  const signals::SignalTable* table = stack ? stack->table() : nullptr;
  ModelStatus::Value status = m_status == ModelStatus::Error ? ModelStatus::Error
                              : table && stack->events()     ? ModelStatus::Ready
                                                             : ModelStatus::NotConnected;
  std::optional<double> state;
  if (table && m_stateIndex) {
    if (const auto bus = table->readBus(*m_stateIndex); bus && bus->updates > 0) state = bus->value;
  }
  for (std::size_t i = 0; i < m_rows.size(); ++i) {
    Row& row = m_rows[i];
    bool on = false;
    QString text = QStringLiteral("--");
    if (table) {
      if (const auto slot = table->read(row.index)) {
        const auto shown = shownValue(stack->catalog()[row.index], *slot);
        on = shown && *shown == row.onValue;
        if (shown) text = toQ(formatValue(stack->catalog()[row.index], *shown, ""));
      }
    }
    // Without the FSM file every switch is offered; the FSM still refuses what it must.
    const bool enabled = table != nullptr && stack->events() != nullptr &&
                         (on || !m_rules || (state && m_rules->stateReads(*state, row.key.toStdString())));
    if (on == row.on && text == row.stateText && enabled == row.enabled) continue;
    row.on = on;
    row.stateText = text;
    row.enabled = enabled;
    Q_EMIT dataChanged(index(static_cast<int>(i)), index(static_cast<int>(i)), {OnRole, StateTextRole, EnabledRole});
  }
  if (status != m_status) {
    m_status = status;
    Q_EMIT statusChanged();
  }
}

}  // namespace openvcu::hmi
