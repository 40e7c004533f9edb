#include "stack_models.hpp"

#include <sys/sysinfo.h>
#include <unistd.h>

#include <QDateTime>
#include <QFile>
#include <QProcess>
#include <QTextStream>
#include <algorithm>
#include <fstream>
#include <sstream>

#include "openvcu/config/catalog.hpp"
#include "openvcu/service/process_stats.hpp"

namespace openvcu::hmi {
namespace {

constexpr std::int64_t HEARTBEAT_STALE_NS = 2'500'000'000;  // services beat once a second
constexpr std::size_t HISTORY = 200;
constexpr std::string_view OPERATOR_PREFIX = "internal.operator.";
constexpr std::string_view FAULT_RESET_KEY = "internal.operator.FaultReset";

QString duration(std::int64_t nanoseconds) {
  const double seconds = static_cast<double>(nanoseconds) / 1e9;
  if (seconds < 60) return QString::number(seconds, 'f', 1) + QStringLiteral(" s");
  const auto whole = static_cast<qint64>(seconds);
  if (seconds < 3600) return QStringLiteral("%1 min %2 s").arg(whole / 60).arg(whole % 60);
  return QStringLiteral("%1 h %2 min").arg(whole / 3600).arg((whole % 3600) / 60);
}

QString clockText(std::int64_t realtimeNs) {
  return QDateTime::fromMSecsSinceEpoch(realtimeNs / 1'000'000).toString(QStringLiteral("HH:mm:ss.zzz"));
}

std::optional<FsmRules> loadRules(QString& error) {
  StackConnection* stack = StackConnection::instance();
  if (!stack || stack->config().fsmFile.empty()) return std::nullopt;
  auto rules = FsmRules::load(stack->config().fsmFile);
  if (!rules) {
    error = toQ(rules.error().toString());
    return std::nullopt;
  }
  return std::move(*rules);
}

}  // namespace

// ---- OperatorModel ---------------------------------------------------------------------

OperatorModel::OperatorModel(QObject* parent) : QAbstractListModel(parent) {
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
  return parent.isValid() ? 0 : static_cast<int>(m_rows.size());
}

QVariant OperatorModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= static_cast<int>(m_rows.size())) return {};
  const Row& row = m_rows[static_cast<std::size_t>(index.row())];
  switch (role) {
    case KeyRole:
      return row.key;
    case LabelRole:
    case Qt::DisplayRole:
      return row.label;
    case OnRole:
      return row.on;
    case StateTextRole:
      return row.stateText;
    case EnabledRole:
      return row.enabled;
    case ResultRole:
      return row.result;
    case PendingRole:
      return row.pendingId >= 0;
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
        const auto shown = shownValue(*slot);
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

// ---- FsmModel ------------------------------------------------------------------------------

FsmModel::FsmModel(QObject* parent) : QAbstractListModel(parent) {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  m_rules = loadRules(m_error);
  m_stateIndex = stack->catalog().indexOf("internal.fsm.state");
  connect(stack, &StackConnection::displayTick, this, &FsmModel::refresh);
  connect(stack, &StackConnection::fsmTransition, this, &FsmModel::addTransition);
  refresh();
}

int FsmModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(m_history.size());
}

QVariant FsmModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= static_cast<int>(m_history.size())) return {};
  const ipc::FsmTransition& transition = m_history[static_cast<std::size_t>(index.row())];
  switch (role) {
    case TimeRole:
      return clockText(transition.timestampNs);
    case FromRole:
      return transition.fromState.empty() ? QStringLiteral("(start)") : toQ(transition.fromState);
    case ToRole:
    case Qt::DisplayRole:
      return toQ(transition.toState);
    case CauseRole:
      return toQ(transition.cause);
    default:
      return {};
  }
}

QHash<int, QByteArray> FsmModel::roleNames() const {
  return {{TimeRole, "time"}, {FromRole, "fromState"}, {ToRole, "toState"}, {CauseRole, "cause"}};
}

void FsmModel::addTransition(const ipc::FsmTransition& transition) {
  beginInsertRows({}, 0, 0);
  m_history.insert(m_history.begin(), transition);
  endInsertRows();
  if (m_history.size() > HISTORY) {
    const int last = static_cast<int>(m_history.size()) - 1;
    beginRemoveRows({}, last, last);
    m_history.pop_back();
    endRemoveRows();
  }
}

void FsmModel::refresh() {
  StackConnection* stack = StackConnection::instance();
  QString name = QStringLiteral("--");
  QString age;
  ModelStatus::Value status = ModelStatus::NotConnected;
  if (!m_error.isEmpty()) status = ModelStatus::Error;
  if (stack && stack->table() && m_stateIndex) {
    if (const auto bus = stack->table()->readBus(*m_stateIndex); bus && bus->updates > 0) {
      name = m_rules ? toQ(m_rules->stateName(bus->value)) : QString::number(bus->value);
      age = duration(signals::monotonicNowNs() - bus->timestampNs);
      if (status != ModelStatus::Error)
        status = bus->quality == signals::Quality::Valid ? ModelStatus::Ready : ModelStatus::Stale;
    }
  }
  if (name == m_stateName && age == m_stateAge && status == m_status) return;
  m_stateName = name;
  m_stateAge = age;
  m_status = status;
  Q_EMIT stateChanged();
}

// ---- HealthModel -----------------------------------------------------------------------------

namespace {
std::vector<std::string> expectedServices() {
  std::vector<std::string> names;
  for (const std::string_view name : config::SERVICES) {
    if (name == "hmi") continue;
    names.push_back("vcu-" + std::string(name));
  }
  return names;
}
}  // namespace

HealthModel::HealthModel(QObject* parent)
    : QAbstractListModel(parent), m_tracker(expectedServices(), HEARTBEAT_STALE_NS) {
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::heartbeat, this, &HealthModel::onHeartbeat);
    connect(stack, &StackConnection::displayTick, this, &HealthModel::refresh);
  }
  refresh();
}

int HealthModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(m_tracker.services().size());
}

QVariant HealthModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount()) return {};
  const ServiceHealth& service = m_tracker.services()[static_cast<std::size_t>(index.row())];
  const auto cpu = m_cpu.find(service.name);
  const std::int64_t now = signals::monotonicNowNs();
  switch (role) {
    case NameRole:
    case Qt::DisplayRole:
      return toQ(service.name);
    case PidRole:
      return service.pid;
    case UptimeRole:
      return service.heartbeats > 0 ? duration(service.uptimeMs * 1'000'000) : QStringLiteral("--");
    case RestartsRole:
      return service.restarts;
    case AgeRole:
      return service.lastBeatMonoNs >= 0 ? duration(now - service.lastBeatMonoNs) : QStringLiteral("never");
    case CpuRole:
      return cpu != m_cpu.end() && cpu->second.ticks >= 0 ? QString::number(cpu->second.percent, 'f', 1)
                                                          : QStringLiteral("-");
    case RssRole:
      return cpu != m_cpu.end() && cpu->second.rssMb >= 0 ? QString::number(cpu->second.rssMb, 'f', 1)
                                                          : QStringLiteral("-");
    case StatusTextRole:
      return toQ(service.status);
    case ConnectionRole:
      return static_cast<int>(m_tracker.statusOf(service, now));
    default:
      return {};
  }
}

QHash<int, QByteArray> HealthModel::roleNames() const {
  return {{NameRole, "name"},
          {PidRole, "pid"},
          {UptimeRole, "uptime"},
          {RestartsRole, "restarts"},
          {AgeRole, "beatAge"},
          {CpuRole, "cpu"},
          {RssRole, "rss"},
          {StatusTextRole, "statusText"},
          {ConnectionRole, "connection"}};
}

int HealthModel::connectionOf(const QString& name) const {
  const ServiceHealth* service = m_tracker.find(name.toStdString());
  return static_cast<int>(service ? m_tracker.statusOf(*service, signals::monotonicNowNs())
                                  : ValueStatus::NotConnected);
}

void HealthModel::onHeartbeat(const ipc::Heartbeat& beat) {
  const int before = rowCount();
  if (m_tracker.onHeartbeat(beat, signals::monotonicNowNs())) {
    beginInsertRows({}, before, before);
    endInsertRows();
  }
}

void HealthModel::refresh() {
  const std::int64_t now = signals::monotonicNowNs();
  // /proc once a second, not at display rate
  if (++m_tick % 10 == 1) {
    const double ticksPerSecond = service::clockTicksPerSecond();
    for (const ServiceHealth& service : m_tracker.services()) {
      if (service.pid <= 0) continue;
      Cpu& cpu = m_cpu[service.name];
      const std::int64_t ticks = service::processCpuTicks(service.pid);
      if (ticks >= 0 && cpu.ticks >= 0 && now > cpu.atNs) {
        cpu.percent =
            static_cast<double>(ticks - cpu.ticks) / ticksPerSecond / (static_cast<double>(now - cpu.atNs) / 1e9) * 100;
      }
      cpu.ticks = ticks;
      cpu.atNs = now;
      cpu.rssMb = service::processRssMb(service.pid);
    }
    struct sysinfo info {};
    if (::sysinfo(&info) == 0) {
      const double unit = static_cast<double>(info.mem_unit);
      m_systemText = QStringLiteral("system up %1, load %2, memory %3 / %4 MB")
                         .arg(duration(static_cast<std::int64_t>(info.uptime) * 1'000'000'000))
                         .arg(static_cast<double>(info.loads[0]) / 65536.0, 0, 'f', 2)
                         .arg(static_cast<double>(info.totalram - info.freeram) * unit / 1e6, 0, 'f', 0)
                         .arg(static_cast<double>(info.totalram) * unit / 1e6, 0, 'f', 0);
    }
  }
  int ready = 0;
  int late = 0;
  for (const ServiceHealth& service : m_tracker.services()) {
    const ValueStatus status = m_tracker.statusOf(service, now);
    if (status == ValueStatus::Ready) ++ready;
    if (status == ValueStatus::Stale || (status == ValueStatus::NotConnected && service.heartbeats > 0)) ++late;
  }
  ModelStatus::Value status = ready == 0 ? ModelStatus::NotConnected
                              : late > 0 ? ModelStatus::Stale
                                         : ModelStatus::Ready;
  if (ready > 0 && ready < rowCount()) status = ModelStatus::Stale;
  m_status = status;
  if (rowCount() > 0)
    Q_EMIT dataChanged(index(0), index(rowCount() - 1),
                       {AgeRole, CpuRole, RssRole, ConnectionRole, UptimeRole, PidRole, RestartsRole, StatusTextRole});
  Q_EMIT statusChanged();
}

// ---- LogModel --------------------------------------------------------------------------------

LogModel::LogModel(QObject* parent) : QAbstractListModel(parent) {
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::logRecord, this, &LogModel::add);
    m_status = stack->events() ? ModelStatus::Ready : ModelStatus::NotConnected;
    connect(stack, &StackConnection::connectionChanged, this, [this, stack] {
      m_status = stack->events() ? ModelStatus::Ready : ModelStatus::from(ValueStatus::NotConnected);
      m_error = stack->events() ? QString() : stack->errorString();
      Q_EMIT statusChanged();
    });
  }
}

int LogModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(m_shown.size());
}

QVariant LogModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount()) return {};
  const ipc::LogRecord& record = m_buffer.at(m_shown[static_cast<std::size_t>(index.row())]);
  switch (role) {
    case TimeRole:
      return clockText(record.timestampNs);
    case ServiceRole:
      return toQ(record.service);
    case LevelRole:
      return static_cast<int>(record.level);
    case LevelNameRole:
      return toQ(std::string(levelName(record.level)));
    case TextRole:
    case Qt::DisplayRole:
      return toQ(record.text);
    default:
      return {};
  }
}

QHash<int, QByteArray> LogModel::roleNames() const {
  return {{TimeRole, "time"},
          {ServiceRole, "service"},
          {LevelRole, "level"},
          {LevelNameRole, "levelName"},
          {TextRole, "text"}};
}

void LogModel::setServiceFilter(const QString& service) {
  if (service == m_service) return;
  m_service = service;
  reselect();
  Q_EMIT filterChanged();
}

void LogModel::setMinimumLevel(int level) {
  if (level == m_minimum) return;
  m_minimum = std::clamp(level, 0, 5);
  reselect();
  Q_EMIT filterChanged();
}

QStringList LogModel::services() const {
  QStringList names;
  for (const std::string& name : m_buffer.services()) names << toQ(name);
  return names;
}

void LogModel::reselect() {
  beginResetModel();
  m_shown = m_buffer.select(m_service.toStdString(), static_cast<ipc::LogLevel>(m_minimum));
  endResetModel();
}

void LogModel::add(const ipc::LogRecord& record) {
  const bool dropped = m_buffer.add(record);
  const bool shown =
      static_cast<int>(record.level) >= m_minimum && (m_service.isEmpty() || m_service.toStdString() == record.service);
  if (dropped) {
    reselect();  // indices shifted: rare (every CAPACITY records once full), so a reset is fine
  } else if (shown) {
    const int row = rowCount();
    beginInsertRows({}, row, row);
    m_shown.push_back(m_buffer.size() - 1);
    endInsertRows();
  }
  const std::size_t count = m_buffer.services().size();
  if (count != m_serviceCount) {
    m_serviceCount = count;
    Q_EMIT servicesChanged();
  }
}

QString LogModel::exportTo(const QString& path) const {
  QFile file(path);
  if (!file.open(QIODevice::WriteOnly | QIODevice::Truncate | QIODevice::Text)) {
    return path + QStringLiteral(": ") + file.errorString();
  }
  const std::string text = m_buffer.exportText(m_shown);
  if (file.write(text.data(), static_cast<qint64>(text.size())) != static_cast<qint64>(text.size())) {
    return path + QStringLiteral(": ") + file.errorString();
  }
  return {};
}

// ---- FaultModel ------------------------------------------------------------------------------

FaultModel::FaultModel(QObject* parent) : QAbstractListModel(parent) {
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
  connect(stack, &StackConnection::displayTick, this, &FaultModel::refresh);
  connect(stack, &StackConnection::commandFinished, this, [this](qint64 id, bool, const QString& text) {
    if (id != m_pendingId) return;
    m_pendingId = -1;
    m_lastResult = QStringLiteral("fault reset: ") + text;
    Q_EMIT countChanged();
  });
}

int FaultModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(m_faults.size());
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
  if (status != m_status) {
    m_status = status;
    Q_EMIT countChanged();
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

// ---- SystemActions -----------------------------------------------------------------------------

SystemActions::SystemActions(QObject* parent) : QObject(parent) {}

QStringList SystemActions::restartArgv(const QString& service) const {
  StackConnection* stack = StackConnection::instance();
  QString name = service;
  if (name.startsWith(QStringLiteral("vcu-"))) name = name.mid(4);
  bool known = false;
  for (const std::string_view candidate : config::SERVICES) known = known || name == toQ(std::string(candidate));
  if (!known || !stack || stack->settings().supervisorConfig.empty()) return {};
  return {QStringLiteral("supervisorctl"), QStringLiteral("-c"), toQ(stack->settings().supervisorConfig),
          QStringLiteral("restart"), name};
}

QString SystemActions::restartService(const QString& service) {
  const QStringList argv = restartArgv(service);
  if (argv.isEmpty()) {
    m_lastResult =
        QStringLiteral(
            "cannot restart '%1': not a service of this stack, or vcu-hmi was started without --supervisor-config")
            .arg(service);
    Q_EMIT finished();
    return m_lastResult;
  }
  return run(argv);
}

QString SystemActions::power(const QString& what) {
  if (what != QStringLiteral("reboot") && what != QStringLiteral("poweroff")) {
    m_lastResult = QStringLiteral("refused: '%1' is neither reboot nor poweroff").arg(what);
    Q_EMIT finished();
    return m_lastResult;
  }
  return run({QStringLiteral("systemctl"), what});
}

QString SystemActions::run(const QStringList& argv) {
  // A fixed argv through execve (QProcess never starts a shell for a program + arguments).
  auto* process = new QProcess(this);
  connect(process, &QProcess::finished, this, [this, process, argv](int exitCode, QProcess::ExitStatus exitStatus) {
    const QString output = QString::fromLocal8Bit(process->readAll()).trimmed();
    m_lastResult =
        argv.join(QLatin1Char(' ')) +
        (exitStatus == QProcess::NormalExit && exitCode == 0 ? QStringLiteral(": done")
                                                             : QStringLiteral(": failed (exit %1)").arg(exitCode)) +
        (output.isEmpty() ? QString() : QStringLiteral(": ") + output);
    Q_EMIT finished();
    process->deleteLater();
  });
  connect(process, &QProcess::errorOccurred, this, [this, process, argv](QProcess::ProcessError) {
    m_lastResult = argv.join(QLatin1Char(' ')) + QStringLiteral(": ") + process->errorString();
    Q_EMIT finished();
  });
  process->setProcessChannelMode(QProcess::MergedChannels);
  process->start(argv.first(), argv.mid(1));
  m_lastResult = argv.join(QLatin1Char(' ')) + QStringLiteral(": running");
  Q_EMIT finished();
  return {};
}

}  // namespace openvcu::hmi
