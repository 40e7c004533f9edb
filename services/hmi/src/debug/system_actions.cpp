#include "debug/system_actions.hpp"

#include <QProcess>

#include "common/child_process.hpp"
#include "common/stack_connection.hpp"
#include "openvcu/config/catalog.hpp"

namespace openvcu::hmi {

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
  startWithNoSignalBlocked(*process);
  process->start(argv.first(), argv.mid(1));
  m_lastResult = argv.join(QLatin1Char(' ')) + QStringLiteral(": running");
  Q_EMIT finished();
  return {};
}

}  // namespace openvcu::hmi
