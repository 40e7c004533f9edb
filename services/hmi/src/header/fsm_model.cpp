#include "header/fsm_model.hpp"

#include "openvcu/core/clock.hpp"

namespace openvcu::hmi {
namespace {

constexpr std::size_t HISTORY = 200;
constexpr std::string_view FSM_PROGRAM = "vcu-fsm";

}  // namespace

FsmModel::FsmModel(QObject* parent)
    : StatusListModel(parent), m_writer({std::string(FSM_PROGRAM)}, display::HEARTBEAT_STALE_NS) {
  // the base's status and errorString are notified with stateChanged(), where this model sets them
  connect(this, &FsmModel::stateChanged, this, &StatusListModel::statusChanged);
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  m_rules = loadRules(m_error);
  m_stateIndex = stack->catalog().indexOf("internal.fsm.state");
  connect(stack, &StackConnection::displayTick, this, &FsmModel::refresh);
  connect(stack, &StackConnection::fsmTransition, this, &FsmModel::addTransition);
  connect(stack, &StackConnection::heartbeat, this, [this](const ipc::Heartbeat& beat) {
    if (beat.service == FSM_PROGRAM) m_writer.onHeartbeat(beat, clock::monotonicNs());
  });
  m_slots.emplace(stack->catalog());
  refresh();
}

int FsmModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_history.size());
}

QVariant FsmModel::data(const QModelIndex& index, int role) const {
  const ipc::FsmTransition* transition = rowAt(m_history, index);
  if (!transition) return {};
  switch (role) {
    case TimeRole:
      return clockText(transition->timestampNs);
    case FromRole:
      return transition->fromState.empty() ? QStringLiteral("(start)") : toQ(transition->fromState);
    case ToRole:
    case Qt::DisplayRole:
      return toQ(transition->toState);
    case CauseRole:
      return toQ(transition->cause);
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
  QString note;
  ModelStatus::Value status = ModelStatus::NotConnected;
  if (!m_error.isEmpty()) status = ModelStatus::Error;
  if (stack && stack->table() && m_stateIndex) {
    if (const auto bus = stack->table()->readBus(*m_stateIndex); bus && bus->updates > 0) {
      name = m_rules ? toQ(m_rules->stateName(bus->value)) : QString::number(bus->value);
      age = durationText(clock::monotonicNs() - bus->timestampNs);
      if (status != ModelStatus::Error)
        status = bus->quality == signals::Quality::Valid ? ModelStatus::Ready : ModelStatus::Stale;
      // the last state of a writer that does not beat is not the current one
      if (m_slots) m_slots->feed(m_writer, *stack->table());
      const std::int64_t now = clock::monotonicNs();
      const ServiceHealth* fsm = m_writer.find(FSM_PROGRAM);
      const Liveness liveness = fsm ? m_writer.livenessOf(*fsm, now) : Liveness::NotHeard;
      if (liveness != Liveness::Beating) {
        const auto silent = m_writer.silentFor(*fsm, now);
        note = QStringLiteral("vcu-fsm ") + toQ(std::string(livenessName(liveness))) +
               (silent ? QStringLiteral(" for ") + durationText(*silent) : QString()) +
               QStringLiteral(": last state, not current");
        if (status != ModelStatus::Error) status = ModelStatus::Stale;
      }
    }
  }
  if (name == m_stateName && age == m_stateAge && note == m_stateNote && status == m_status) return;
  m_stateName = name;
  m_stateAge = age;
  m_stateNote = note;
  m_status = status;
  Q_EMIT stateChanged();
}

}  // namespace openvcu::hmi
