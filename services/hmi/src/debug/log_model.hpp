#pragma once
// The Debug tab's log of every service, filtered and exported (LogModel).
// @note GUI thread only.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "common/model_helpers.hpp"
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#include "openvcu/ipc/events.hpp"
#endif

namespace openvcu::hmi {

/// The log of every service (LCM log records), newest last, filtered by service and
/// minimum level; `exportTo(path)` writes the filtered lines.
class LogModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString serviceFilter READ serviceFilter WRITE setServiceFilter NOTIFY filterChanged)
  Q_PROPERTY(int minimumLevel READ minimumLevel WRITE setMinimumLevel NOTIFY filterChanged)
  Q_PROPERTY(QStringList services READ services NOTIFY servicesChanged)
 public:
  enum Role { TimeRole = Qt::UserRole + 1, ServiceRole, LevelRole, LevelNameRole, TextRole };
  static constexpr std::size_t CAPACITY = 5000;
  explicit LogModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] QString serviceFilter() const { return m_service; }
  void setServiceFilter(const QString& service);
  [[nodiscard]] int minimumLevel() const noexcept { return m_minimum; }
  void setMinimumLevel(int level);
  [[nodiscard]] QStringList services() const;
  /// Writes the shown lines to `path`; "" on success, else the reason.
  Q_INVOKABLE QString exportTo(const QString& path) const;
  void add(const ipc::LogRecord& record);
 Q_SIGNALS:
  void filterChanged();
  void servicesChanged();

 private:
  void reselect();
  LogBuffer m_buffer{CAPACITY};
  std::vector<std::size_t> m_shown;
  QString m_service;
  int m_minimum{0};
  std::size_t m_serviceCount{};
};

}  // namespace openvcu::hmi
