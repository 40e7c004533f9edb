#include "debug/record_controller.hpp"

#include <signal.h>

#include <QCoreApplication>
#include <QDateTime>
#include <QDir>
#include <QFileInfo>

#include "common/child_process.hpp"
#include "common/file_browser.hpp"
#include "common/model_helpers.hpp"
#include "trace/trace_stats_model.hpp"

namespace openvcu::hmi {
namespace {

/// vcu record's readiness line on stderr: every link and lcm-logger are up.
constexpr const char* READY_PREFIX = "recording ";

}  // namespace

QString RecordController::defaultProgram() {
  if (StackConnection* stack = StackConnection::instance(); stack && !stack->settings().vcuProgram.empty()) {
    return toQ(stack->settings().vcuProgram);
  }
  const QString beside = QDir(QCoreApplication::applicationDirPath()).filePath(QStringLiteral("vcu"));
  return QFileInfo(beside).isExecutable() ? beside : QStringLiteral("vcu");
}

RecordController::RecordController(QObject* parent) : QObject(parent), m_program(defaultProgram()) {
  m_tick.setInterval(1000);
  connect(&m_tick, &QTimer::timeout, this, &RecordController::changed);
  m_killTimer.setSingleShot(true);
  m_killTimer.setInterval(STOP_TIMEOUT_MS);
  connect(&m_killTimer, &QTimer::timeout, this, [this] {
    if (!m_process) return;
    m_killed = true;
    m_process->kill();
  });
}

RecordController::~RecordController() {
  if (!m_process || m_process->state() == QProcess::NotRunning) return;
  // the HMI ends while recording: end the recording cleanly rather than orphan it
  disconnect(m_process.get(), nullptr, this, nullptr);
  m_process->terminate();
  if (!m_process->waitForFinished(STOP_TIMEOUT_MS)) {
    m_process->kill();
    m_process->waitForFinished(1000);
  }
}

void RecordController::setProgram(const QString& program) {
  if (program == m_program) return;
  m_program = program;
  Q_EMIT changed();
}

QString RecordController::elapsedText() const {
  if ((m_state != Recording && m_state != Stopping) || !m_elapsed.isValid()) return {};
  return durationText(m_elapsed.elapsed() * 1'000'000);
}

QStringList RecordController::recordArgv(const QString& folder) const {
  QStringList argv{m_program, QStringLiteral("record"), folder};
  if (StackConnection* stack = StackConnection::instance()) {
    argv << QStringLiteral("--config") << toQ(stack->settings().configPath);
    if (!stack->settings().instance.empty()) argv << QStringLiteral("--instance") << toQ(stack->settings().instance);
  }
  return argv;
}

QString RecordController::newRecordingFolder() const {
  return QDir(FileBrowserModel::defaultDataFolder())
      .filePath(QStringLiteral("recordings/") +
                QDateTime::currentDateTime().toString(QStringLiteral("yyyyMMdd-hhmmss")));
}

QString RecordController::start(const QString& folder) {
  if (m_state != Idle) return QStringLiteral("a recording is running: stop it first");
  const QString target = folder.isEmpty() ? newRecordingFolder() : folder;
  const QStringList argv = recordArgv(target);
  m_process = std::make_unique<QProcess>();
  m_process->setProcessChannelMode(QProcess::SeparateChannels);
  m_process->setStandardInputFile(QProcess::nullDevice());
  // so that stop()'s SIGTERM reaches vcu record
  startWithNoSignalBlocked(*m_process);
  connect(m_process.get(), &QProcess::readyReadStandardError, this, &RecordController::onStderr);
  connect(m_process.get(), &QProcess::finished, this, &RecordController::onFinished);
  connect(m_process.get(), &QProcess::errorOccurred, this, &RecordController::onError);
  m_folder = target;
  m_stderr.clear();
  m_recordedLogs.clear();
  m_stopRequested = false;
  m_began = false;
  m_killed = false;
  m_elapsed.invalidate();
  m_status = ModelStatus::Ready;
  m_state = Starting;
  m_lastResult = QStringLiteral("starting: ") + argv.join(QLatin1Char(' '));
  // A fixed argv through execve (QProcess never starts a shell for a program + arguments).
  m_process->start(argv.first(), argv.mid(1));
  Q_EMIT changed();
  return {};
}

void RecordController::stop() {
  if (!m_process || m_state == Idle || m_state == Stopping) return;
  m_stopRequested = true;
  m_state = Stopping;
  m_process->terminate();  // SIGTERM: vcu record stops, flushes, ends lcm-logger, prints its summary
  m_killTimer.start();
  Q_EMIT changed();
}

void RecordController::onStderr() {
  const QString text = QString::fromLocal8Bit(m_process->readAllStandardError());
  m_stderr += text;
  if (m_stderr.size() > MAX_STDERR_CHARS) m_stderr = m_stderr.right(MAX_STDERR_CHARS);
  const QString ready = QString::fromLatin1(READY_PREFIX);
  if (m_state == Starting && (m_stderr.startsWith(ready) || m_stderr.contains(QLatin1Char('\n') + ready))) {
    m_state = Recording;
    m_began = true;
    m_elapsed.start();
    m_tick.start();
    m_lastResult = QStringLiteral("recording into ") + m_folder;
    Q_EMIT changed();
  }
}

void RecordController::onFinished(int exitCode, QProcess::ExitStatus exitStatus) {
  m_killTimer.stop();
  m_tick.stop();
  onStderr();  // what is left
  const QString output = QString::fromLocal8Bit(m_process->readAllStandardOutput()).trimmed();
  const QString errors = m_stderr.trimmed();
  const bool ok = exitStatus == QProcess::NormalExit && exitCode == 0;
  if (ok) {
    m_status = ModelStatus::Ready;
    m_recordedLogs = TraceStatsModel::logsInFolder(m_folder);
    m_lastResult = output.isEmpty() ? QStringLiteral("recorded into ") + m_folder : output;
  } else {
    m_status = ModelStatus::Error;
    QString how = QStringLiteral("vcu record failed (exit %1)").arg(exitCode);
    if (exitStatus == QProcess::CrashExit) {
      if (m_killed) {
        how = QStringLiteral("vcu record did not end within %1 s of SIGTERM and was killed; %2 may be incomplete")
                  .arg(QString::number(m_killTimer.interval() / 1000.0), m_folder);
      } else if (m_stopRequested && !m_began) {
        how = QStringLiteral("vcu record stopped before the recording began");
      } else {
        how = QStringLiteral("vcu record was killed");
      }
    }
    m_lastResult = how + (errors.isEmpty() ? QString() : QStringLiteral(": ") + errors);
  }
  m_state = Idle;
  m_process.release()->deleteLater();  // this slot runs inside one of its signals
  Q_EMIT changed();
  Q_EMIT finished();
}

void RecordController::onError(QProcess::ProcessError error) {
  if (error != QProcess::FailedToStart) return;  // the others end in finished()
  m_killTimer.stop();
  m_status = ModelStatus::Error;
  m_lastResult =
      QStringLiteral("cannot start %1: %2 (vcu-hmi --vcu PROGRAM names it)").arg(m_program, m_process->errorString());
  m_state = Idle;
  m_process.release()->deleteLater();
  Q_EMIT changed();
  Q_EMIT finished();
}

}  // namespace openvcu::hmi
