#pragma once
// The Debug tab's fixed-argv actions: restart a service, reboot, shut down (SystemActions).
// @note GUI thread only.

#include <QObject>
#include <QQmlEngine>
#include <QString>
#include <QStringList>

namespace openvcu::hmi {

/// Fixed-argv actions of the Debug tab: restart a service through supervisorctl, reboot
/// and shut down. Never a shell; the argv are built from fixed words plus a service name
/// that must be one of the configuration's services.
class SystemActions : public QObject {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString lastResult READ lastResult NOTIFY finished)
 public:
  explicit SystemActions(QObject* parent = nullptr);
  [[nodiscard]] QString lastResult() const { return m_lastResult; }
  /// The argv that restartService would run (tests, the confirmation dialog).
  Q_INVOKABLE QStringList restartArgv(const QString& service) const;
  Q_INVOKABLE QString restartService(const QString& service);
  /// `what`: "reboot" or "poweroff" (systemctl); anything else is refused.
  Q_INVOKABLE QString power(const QString& what);
  /// Starts `argv` (a fixed program and arguments, no shell, no signal blocked in the
  /// child); lastResult says "running", then its exit and output. Not for QML.
  QString run(const QStringList& argv);
 Q_SIGNALS:
  void finished();

 private:
  QString m_lastResult;
};

}  // namespace openvcu::hmi
