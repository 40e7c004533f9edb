#include "setup/schedule_model.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "common/model_helpers.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/safety.hpp"

namespace openvcu::hmi {
namespace {

/// The cycle typed on the keypad, checked as can-tx checks it (config::checkCycleMs: whole
/// ms from MIN_CYCLE_MS to MAX_CYCLE_MS); empty and *refusal set when it is not.
std::optional<int> typedCycle(const QString& milliseconds, QString* refusal) {
  bool ok = false;
  const int cycle = milliseconds.trimmed().toInt(&ok);
  if (!ok || config::checkCycleMs(cycle)) {
    *refusal = QStringLiteral("cycle must be a whole number of ms in %1..%2")
                   .arg(config::MIN_CYCLE_MS)
                   .arg(config::MAX_CYCLE_MS);
    return std::nullopt;
  }
  return cycle;
}

/// A J1939-76 safety header (PGN 3584): can-tx sends it with its SDM, never on its own.
bool isSafetyHeader(const dbc::Message& message) {
  return message.extended && j1939::pgnOf(message.id) == j1939::PGN_SAFETY_HEADER;
}

}  // namespace

// ---- ScheduleModel ----------------------------------------------------------------------

ScheduleModel::ScheduleModel(QObject* parent) : StatusListModel(parent) {
  build();
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::displayTick, this, &ScheduleModel::refresh);
    connect(stack, &StackConnection::txSchedule, this, &ScheduleModel::applySchedule);
    connect(stack, &StackConnection::commandFinished, this, [this](qint64 id, bool accepted, const QString& text) {
      const auto it = m_pending.find(id);
      if (it == m_pending.end()) return;
      const Pending pending = it->second;
      m_pending.erase(it);
      if (accepted && pending.cycleMs > 0) {
        const QString message = m_rows[static_cast<std::size_t>(pending.row)].message;
        for (std::size_t i = 0; i < m_rows.size(); ++i) {
          if (m_rows[i].message != message) continue;
          m_rows[i].cycleMs = pending.cycleMs;
          Q_EMIT dataChanged(index(static_cast<int>(i)), index(static_cast<int>(i)), {CycleRole});
        }
      }
      m_lastResult = pending.what + QStringLiteral(": ") + text;
      Q_EMIT statusChanged();
    });
  }
}

void ScheduleModel::build() {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  const config::VehicleConfig& vehicle = stack->config();
  std::map<std::string, int> deltaByMessage;
  if (!vehicle.scheduleFile.empty()) {
    auto json = config::readJsonFile(vehicle.scheduleFile);
    if (!json) {
      m_status = ModelStatus::Error;
      m_error = toQ(json.error().toString());
    } else if (json->is_object() && json->contains("messages") && (*json)["messages"].is_object()) {
      for (auto it = (*json)["messages"].begin(); it != (*json)["messages"].end(); ++it) {
        const config::Json& entry = *it;
        if (entry.is_object() && entry.contains("safety") && entry["safety"].is_object() &&
            entry["safety"].contains("deltaUs") && entry["safety"]["deltaUs"].is_number()) {
          deltaByMessage[it.key()] = entry["safety"]["deltaUs"].get<int>();
        }
      }
    }
  }
  for (const config::BusConfig& bus : vehicle.buses) {
    for (const std::size_t messageIndex : bus.messages) {
      const dbc::Message& message = vehicle.database.messages[messageIndex];
      if (!config::sentBy(message, vehicle.node)) continue;
      if (isSafetyHeader(message)) continue;  // sent with its SDM, not scheduled on its own
      const auto delta = deltaByMessage.find(message.name);
      appendRows(m_rows, messageIndex, delta != deltaByMessage.end(),
                 delta != deltaByMessage.end() ? delta->second : 0);
    }
  }
}

void ScheduleModel::appendRows(std::vector<Row>& rows, std::size_t messageIndex, bool pair, int deltaUs) const {
  StackConnection* stack = StackConnection::instance();
  const dbc::Message& message = stack->config().database.messages[messageIndex];
  for (const dbc::Signal& signal : message.signals) {
    Row row;
    row.messageIndex = messageIndex;
    row.message = toQ(message.name);
    row.signal = toQ(signal.name);
    const std::string key = config::signalKey(message, signal);
    row.key = toQ(key);
    row.index = stack->catalog().indexOf(key);
    if (!row.index) continue;
    row.cycleMs = message.cycleTimeMs ? static_cast<int>(*message.cycleTimeMs) : 0;
    row.pair = pair;
    row.deltaUs = deltaUs;
    rows.push_back(std::move(row));
  }
}

void ScheduleModel::applySchedule(const ipc::TxSchedule& live) {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  const dbc::Database& database = stack->config().database;
  for (const ipc::ScheduleEntry& settings : live.entries) {
    const std::string& name = settings.message;
    const dbc::Message* message = database.findMessage(name);
    if (message == nullptr) continue;
    const auto messageIndex = static_cast<std::size_t>(message - database.messages.data());
    const QString qName = toQ(name);
    if (rowOfMessage(qName) < 0) {
      std::vector<Row> rows;
      appendRows(rows, messageIndex, false, 0);
      if (rows.empty()) continue;
      const int first = static_cast<int>(m_rows.size());
      beginInsertRows({}, first, first + static_cast<int>(rows.size()) - 1);
      for (Row& row : rows) m_rows.push_back(std::move(row));
      endInsertRows();
    }
    const int cycleMs = static_cast<int>((settings.cycleUs + 500) / 1000);
    for (std::size_t i = 0; i < m_rows.size(); ++i) {
      Row& row = m_rows[i];
      if (row.messageIndex != messageIndex) continue;
      if (row.live && row.cycleMs == cycleMs && row.enabled == settings.enabled && row.added == settings.added) continue;
      row.live = true;
      row.cycleMs = cycleMs;
      row.enabled = settings.enabled;
      row.added = settings.added;
      Q_EMIT dataChanged(index(static_cast<int>(i)), index(static_cast<int>(i)),
                         {CycleRole, LiveRole, EnabledRole, AddedRole});
    }
  }
}

int ScheduleModel::rowOfMessage(const QString& message) const {
  for (std::size_t i = 0; i < m_rows.size(); ++i) {
    if (m_rows[i].message == message) return static_cast<int>(i);
  }
  return -1;
}

QStringList ScheduleModel::candidates(const QString& filter) const {
  QStringList names;
  StackConnection* stack = StackConnection::instance();
  if (!stack) return names;
  const config::VehicleConfig& vehicle = stack->config();
  for (const config::BusConfig& bus : vehicle.buses) {
    for (const std::size_t messageIndex : bus.messages) {
      const dbc::Message& message = vehicle.database.messages[messageIndex];
      if (message.pseudo || isSafetyHeader(message)) continue;
      const QString name = toQ(message.name);
      if (!filter.isEmpty() && !name.contains(filter, Qt::CaseInsensitive)) continue;
      if (rowOfMessage(name) >= 0 || names.contains(name)) continue;
      names.push_back(name);
    }
  }
  names.sort(Qt::CaseInsensitive);
  return names;
}

QString ScheduleModel::addMessage(const QString& name, const QString& milliseconds) {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return QStringLiteral("not connected");
  const dbc::Message* message = stack->config().database.findMessage(name.trimmed().toStdString());
  if (message == nullptr || message->pseudo) return QStringLiteral("unknown message '%1'").arg(name);
  if (rowOfMessage(toQ(message->name)) >= 0) {
    return QStringLiteral("%1 is already in the schedule").arg(toQ(message->name));
  }
  QString refusal;
  const std::optional<int> maybeCycle = typedCycle(milliseconds, &refusal);
  if (!maybeCycle) return refusal;
  const int cycle = *maybeCycle;
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::ScheduleAdd;
  request.key = message->name;
  request.value = cycle;
  return send(std::move(request), QStringLiteral("add %1 every %2 ms").arg(toQ(message->name)).arg(cycle));
}

QString ScheduleModel::setEnabled(int row, bool enabled) {
  if (row < 0 || row >= static_cast<int>(m_rows.size())) return QStringLiteral("no such row");
  const QString& message = m_rows[static_cast<std::size_t>(row)].message;
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::ScheduleEnable;
  request.key = message.toStdString();
  request.value = enabled ? 1.0 : 0.0;
  return send(std::move(request), QStringLiteral("%1 %2").arg(enabled ? "enable" : "disable", message));
}

int ScheduleModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_rows.size());
}

QVariant ScheduleModel::data(const QModelIndex& index, int role) const {
  const Row* row = rowAt(m_rows, index);
  if (!row) return {};
  switch (role) {
    case MessageRole:
      return row->message;
    case SignalRole:
    case Qt::DisplayRole:
      return row->signal;
    case CycleRole:
      return row->cycleMs;
    case PairRole:
      return row->pair;
    case DeltaRole:
      return row->deltaUs;
    case ValueRole:
      return row->value;
    case OverrideRole:
      return row->overrideText;
    case OverriddenRole:
      return row->overridden;
    case KeyRole:
      return row->key;
    case RangeRole: {
      StackConnection* stack = StackConnection::instance();
      if (!stack || !row->index) return QString();
      const signals::SignalInfo& info = stack->catalog()[*row->index];
      return QStringLiteral("%1 .. %2 %3").arg(info.minimum).arg(info.maximum).arg(toQ(info.unit));
    }
    case LiveRole:
      return row->live;
    case EnabledRole:
      return row->enabled;
    case AddedRole:
      return row->added;
    default:
      return {};
  }
}

QHash<int, QByteArray> ScheduleModel::roleNames() const {
  return {{MessageRole, "message"},
          {SignalRole, "signal"},
          {CycleRole, "cycleMs"},
          {PairRole, "shmPair"},
          {DeltaRole, "deltaUs"},
          {ValueRole, "valueText"},
          {OverrideRole, "overrideText"},
          {OverriddenRole, "overridden"},
          {KeyRole, "key"},
          {RangeRole, "range"},
          {LiveRole, "live"},
          {EnabledRole, "enabled"},
          {AddedRole, "added"}};
}

void ScheduleModel::refresh() {
  StackConnection* stack = StackConnection::instance();
  const ModelStatus::Value status = m_status == ModelStatus::Error               ? ModelStatus::Error
                                    : stack && stack->table() && stack->events() ? ModelStatus::Ready
                                                                                 : ModelStatus::NotConnected;
  if (status != m_status) {
    m_status = status;
    Q_EMIT statusChanged();
  }
  if (!stack || !stack->table()) return;
  for (std::size_t i = 0; i < m_rows.size(); ++i) {
    Row& row = m_rows[i];
    const auto slot = stack->table()->read(*row.index);
    if (!slot) continue;
    const signals::SignalInfo& info = stack->catalog()[*row.index];
    QString value = QStringLiteral("--");
    if (slot->bus.updates > 0) {
      value = toQ(formatValue(info, slot->bus.value, ""));
    } else if (const auto command = signals::effectiveCommand(*slot)) {
      value = toQ(formatValue(info, command->value, ""));
    }
    const bool overridden = slot->override.active;
    const QString overrideText = overridden ? toQ(formatValue(info, slot->override.value, "")) : QString();
    if (value == row.value && overridden == row.overridden && overrideText == row.overrideText) continue;
    row.value = value;
    row.overridden = overridden;
    row.overrideText = overrideText;
    Q_EMIT dataChanged(index(static_cast<int>(i)), index(static_cast<int>(i)),
                       {ValueRole, OverrideRole, OverriddenRole});
  }
}

QString ScheduleModel::send(ipc::CommandRequest request, const QString& what) {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return QStringLiteral("not connected");
  request.text = "vcu-hmi ECU setup";
  const std::int64_t id = stack->sendCommand(std::move(request));
  if (id < 0) return QStringLiteral("not sent: no event bus");
  m_pending[id] = Pending{.row = 0, .cycleMs = 0, .what = what};
  m_lastResult = what + QStringLiteral(": waiting for the answer");
  Q_EMIT statusChanged();
  return {};
}

QString ScheduleModel::setCycle(int row, const QString& milliseconds) {
  if (row < 0 || row >= static_cast<int>(m_rows.size())) return QStringLiteral("no such row");
  QString refusal;
  const std::optional<int> maybeCycle = typedCycle(milliseconds, &refusal);
  if (!maybeCycle) return refusal;
  const int cycle = *maybeCycle;
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::ScheduleCycle;
  request.key = m_rows[static_cast<std::size_t>(row)].message.toStdString();
  request.value = cycle;
  const QString what =
      QStringLiteral("cycle of %1 to %2 ms").arg(m_rows[static_cast<std::size_t>(row)].message).arg(cycle);
  const QString refused = send(std::move(request), what);
  if (refused.isEmpty() && !m_pending.empty()) {
    auto last = std::prev(m_pending.end());
    last->second.row = row;
    last->second.cycleMs = cycle;
  }
  return refused;
}

std::optional<double> ScheduleModel::checkedValue(int row, const QString& text, QString* refusal) const {
  StackConnection* stack = StackConnection::instance();
  if (row < 0 || row >= static_cast<int>(m_rows.size()) || !stack) {
    *refusal = QStringLiteral("no such row");
    return std::nullopt;
  }
  const signals::SignalInfo& info = stack->catalog()[*m_rows[static_cast<std::size_t>(row)].index];
  bool ok = false;
  double number = text.trimmed().toDouble(&ok);
  if (!ok) {
    for (const auto& [raw, name] : info.valueTexts) {
      if (QString::fromStdString(name) == text.trimmed()) {
        number = static_cast<double>(raw);
        ok = true;
      }
    }
  }
  if (!ok || !std::isfinite(number)) {
    *refusal = QStringLiteral("'%1' is not a number").arg(text);
    return std::nullopt;
  }
  if (info.minimum < info.maximum && (number < info.minimum || number > info.maximum)) {
    *refusal = QStringLiteral("%1 is outside the range [%2, %3] %4")
                   .arg(number)
                   .arg(info.minimum)
                   .arg(info.maximum)
                   .arg(toQ(info.unit));
    return std::nullopt;
  }
  return number;
}

QString ScheduleModel::setOverride(int row, const QString& value) {
  return sendValue(row, value, ipc::CommandKind::SetOverride, QStringLiteral("override %1 = %2"));
}

QString ScheduleModel::setDefault(int row, const QString& value) {
  return sendValue(row, value, ipc::CommandKind::ScheduleDefault, QStringLiteral("schedule value of %1 = %2"));
}

QString ScheduleModel::sendValue(int row, const QString& value, ipc::CommandKind kind, const QString& what) {
  QString refusal;
  const auto number = checkedValue(row, value, &refusal);
  if (!number) return refusal;
  const Row& entry = m_rows[static_cast<std::size_t>(row)];
  ipc::CommandRequest request;
  request.kind = kind;
  request.key = entry.key.toStdString();
  request.value = *number;
  return send(std::move(request), what.arg(entry.signal).arg(*number));
}

QString ScheduleModel::clearOverride(int row) {
  if (row < 0 || row >= static_cast<int>(m_rows.size())) return QStringLiteral("no such row");
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::ClearOverride;
  request.key = m_rows[static_cast<std::size_t>(row)].key.toStdString();
  return send(std::move(request),
              QStringLiteral("clear override of %1").arg(m_rows[static_cast<std::size_t>(row)].signal));
}

}  // namespace openvcu::hmi
