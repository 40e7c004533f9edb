#include "header/fsm_model.hpp"
#include "openvcu/core/clock.hpp"

namespace openvcu::hmi {
namespace {

constexpr std::size_t HISTORY = 200;

}  // namespace

FsmModel::FsmModel(QObject* parent) : StatusListModel(parent) {
  // the base's status and errorString are notified with stateChanged(), where this model sets them
  connect(this, &FsmModel::stateChanged, this, &StatusListModel::statusChanged);
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  m_rules = loadRules(m_error);
  m_stateIndex = stack->catalog().indexOf("internal.fsm.state");
  connect(stack, &StackConnection::displayTick, this, &FsmModel::refresh);
  connect(stack, &StackConnection::fsmTransition, this, &FsmModel::addTransition);
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
  ModelStatus::Value status = ModelStatus::NotConnected;
  if (!m_error.isEmpty()) status = ModelStatus::Error;
  if (stack && stack->table() && m_stateIndex) {
    if (const auto bus = stack->table()->readBus(*m_stateIndex); bus && bus->updates > 0) {
      name = m_rules ? toQ(m_rules->stateName(bus->value)) : QString::number(bus->value);
      age = durationText(clock::monotonicNs() - bus->timestampNs);
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

}  // namespace openvcu::hmi
