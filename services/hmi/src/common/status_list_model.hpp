#pragma once
// The list model base of the HMI's list models that tell their state through one signal:
// `status` (ModelStatus) and `errorString`, both notified by statusChanged().
// @note GUI thread only.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/stack_connection.hpp"
#endif

namespace openvcu::hmi {

/// A QAbstractListModel with the `status` and `errorString` properties; the derived model
/// sets m_status and m_error and emits statusChanged(). Anonymous in QML: only the derived
/// models are created there, and they show these two properties as their own.
class StatusListModel : public QAbstractListModel {
  Q_OBJECT
  QML_ANONYMOUS
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY statusChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY statusChanged)
 public:
  using QAbstractListModel::QAbstractListModel;
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
 Q_SIGNALS:
  void statusChanged();

 protected:
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
};

}  // namespace openvcu::hmi
