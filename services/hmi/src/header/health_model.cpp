#include "header/health_model.hpp"

#include <sys/sysinfo.h>
#include <unistd.h>

#include "openvcu/config/catalog.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/service/process_stats.hpp"

namespace openvcu::hmi {
namespace {

constexpr std::int64_t HEARTBEAT_STALE_NS = 2'500'000'000;  // services beat once a second

}  // namespace

HealthModel::HealthModel(QObject* parent)
    : StatusListModel(parent), m_tracker(display::expectedServices(), HEARTBEAT_STALE_NS) {
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::heartbeat, this, &HealthModel::onHeartbeat);
    connect(stack, &StackConnection::displayTick, this, &HealthModel::refresh);
    m_slots.emplace(stack->catalog());
  }
  refresh();
}

int HealthModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_tracker.services().size());
}

QVariant HealthModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount()) return {};
  const ServiceHealth& service = m_tracker.services()[static_cast<std::size_t>(index.row())];
  const auto cpu = m_cpu.find(service.name);
  const std::int64_t now = clock::monotonicNs();
  switch (role) {
    case NameRole:
    case Qt::DisplayRole:
      return toQ(service.name);
    case PidRole:
      return service.pid;
    case UptimeRole:
      return service.heartbeats > 0 ? durationText(service.uptimeMs * 1'000'000) : QStringLiteral("--");
    case RestartsRole:
      return service.restarts;
    case AgeRole:
      return service.lastBeatMonoNs >= 0 ? durationText(now - service.lastBeatMonoNs) : QStringLiteral("never");
    case CpuRole:
      return cpu != m_cpu.end() && cpu->second.ticks >= 0 ? QString::number(cpu->second.percent, 'f', 1)
                                                          : QStringLiteral("-");
    case RssRole:
      return cpu != m_cpu.end() && cpu->second.rssMb >= 0 ? QString::number(cpu->second.rssMb, 'f', 1)
                                                          : QStringLiteral("-");
    case StatusTextRole:
      if (const auto silent = m_tracker.silentFor(service, now)) {
        return toQ(std::string(livenessName(m_tracker.livenessOf(service, now)))) + QStringLiteral(" for ") +
               durationText(*silent) +
               (service.status.empty() ? QString()
                                       : QStringLiteral(" (last: ") + toQ(service.status) + QStringLiteral(")"));
      }
      return toQ(service.status);
    case LivenessRole:
      return toQ(std::string(livenessName(m_tracker.livenessOf(service, now))));
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
          {ConnectionRole, "connection"},
          {LivenessRole, "liveness"}};
}

int HealthModel::connectionOf(const QString& name) const {
  const ServiceHealth* service = m_tracker.find(name.toStdString());
  return static_cast<int>(service ? m_tracker.statusOf(*service, clock::monotonicNs()) : ValueStatus::NotConnected);
}

void HealthModel::onHeartbeat(const ipc::Heartbeat& beat) {
  const int before = rowCount();
  if (m_tracker.onHeartbeat(beat, clock::monotonicNs())) {
    beginInsertRows({}, before, before);
    endInsertRows();
  }
}

void HealthModel::refresh() {
  const std::int64_t now = clock::monotonicNs();
  // the table's heartbeat slots: a service that beats there (or stopped before the HMI started)
  const StackConnection* stack = StackConnection::instance();
  if (m_slots && stack && stack->table()) {
    const int before = rowCount();
    if (m_slots->feed(m_tracker, *stack->table())) {
      beginInsertRows({}, before, rowCount() - 1);
      endInsertRows();
    }
  }
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
                         .arg(durationText(static_cast<std::int64_t>(info.uptime) * 1'000'000'000))
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
    Q_EMIT dataChanged(
        index(0), index(rowCount() - 1),
        {AgeRole, CpuRole, RssRole, ConnectionRole, UptimeRole, PidRole, RestartsRole, StatusTextRole, LivenessRole});
  Q_EMIT statusChanged();
}

}  // namespace openvcu::hmi
