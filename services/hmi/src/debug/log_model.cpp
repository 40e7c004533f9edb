#include "debug/log_model.hpp"

#include <QFile>
#include <QTextStream>
#include <algorithm>
#include <fstream>

namespace openvcu::hmi {

LogModel::LogModel(QObject* parent) : StatusListModel(parent) {
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
  return listRowCount(parent, m_shown.size());
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

}  // namespace openvcu::hmi
