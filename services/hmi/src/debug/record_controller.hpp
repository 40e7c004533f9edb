#pragma once
// RecordController: the Debug tab's Record button (issue 21, the thesis' dashboard "data
// logging"). Starts `vcu record <data folder>/recordings/<yyyyMMdd-hhmmss> --config FILE`
// as a child process from an argument list (QProcess, never a shell), shows the folder and
// the elapsed time while it records, stops it with SIGTERM (vcu record ends the recording
// cleanly on SIGINT and SIGTERM and prints its summary), and afterwards offers the folder's
// *.log files for the Trace tab. A failing `vcu record` shows its exit code and stderr.
// vcu record starts with every signal unblocked (vcu-hmi itself blocks SIGTERM and SIGINT
// and reads them through a signalfd; a child would inherit that mask and never see Stop).
//
//   RecordController { id: recorder }
//   TouchButton { text: recorder.active ? "Stop" : "Record"; onClicked: recorder.active ? recorder.stop() :
//   recorder.start() } Text { text: recorder.folder + "  " + recorder.elapsedText } TouchButton { visible:
//   recorder.recordedLogs.length > 0; onClicked: analyse(recorder.recordedLogs) }
//
// The program: --vcu PROGRAM of vcu-hmi, else `vcu` beside the vcu-hmi executable, else `vcu`
// from PATH. The configuration and instance: those the HMI runs with.
// @note GUI thread only.

#include <QElapsedTimer>
#include <QObject>
#include <QProcess>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <QTimer>
#include <memory>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/stack_connection.hpp"
#endif

namespace openvcu::hmi {

class RecordController : public QObject {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(State state READ state NOTIFY changed)
  Q_PROPERTY(bool active READ active NOTIFY changed)
  Q_PROPERTY(QString folder READ folder NOTIFY changed)
  Q_PROPERTY(QString elapsedText READ elapsedText NOTIFY changed)
  Q_PROPERTY(QString lastResult READ lastResult NOTIFY changed)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY changed)
  Q_PROPERTY(QStringList recordedLogs READ recordedLogs NOTIFY changed)
  Q_PROPERTY(QString program READ program WRITE setProgram NOTIFY changed)
 public:
  /// Idle: nothing running. Starting: vcu record runs but has not said "recording" yet.
  /// Recording: it records. Stopping: SIGTERM sent, waiting for its summary.
  enum State { Idle, Starting, Recording, Stopping };
  Q_ENUM(State)
  /// After SIGTERM vcu record gets this long (it gives lcm-logger up to 2 x 3 s) before SIGKILL.
  static constexpr int STOP_TIMEOUT_MS = 10000;
  /// The tail of vcu record's stderr kept for the error text.
  static constexpr qsizetype MAX_STDERR_CHARS = 4000;

  explicit RecordController(QObject* parent = nullptr);
  ~RecordController() override;

  [[nodiscard]] State state() const noexcept { return m_state; }
  [[nodiscard]] bool active() const noexcept { return m_state != Idle; }
  [[nodiscard]] QString folder() const { return m_folder; }
  [[nodiscard]] QString elapsedText() const;
  [[nodiscard]] QString lastResult() const { return m_lastResult; }
  /// Ready: idle or recording, the last recording ended well; Error: it failed.
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  /// The *.log files of the last recording that ended well (empty before and after a failure).
  [[nodiscard]] QStringList recordedLogs() const { return m_recordedLogs; }
  [[nodiscard]] QString program() const { return m_program; }
  void setProgram(const QString& program);

  /// The argv that start() runs for `folder` (program first).
  Q_INVOKABLE QStringList recordArgv(const QString& folder) const;
  /// <data folder>/recordings/<yyyyMMdd-hhmmss> for now (not created: vcu record creates it).
  Q_INVOKABLE QString newRecordingFolder() const;
  /// Starts recording into newRecordingFolder() (or `folder` when given); "" or why not.
  Q_INVOKABLE QString start(const QString& folder = {});
  /// Asks a running recording to stop (SIGTERM); SIGKILL after the stop timeout.
  Q_INVOKABLE void stop();
  /// How long stop() waits before SIGKILL (default STOP_TIMEOUT_MS).
  void setStopTimeout(int milliseconds) { m_killTimer.setInterval(milliseconds); }
  /// `vcu` beside the running executable when it exists, else "vcu" (PATH).
  static QString defaultProgram();

 Q_SIGNALS:
  void changed();
  /// vcu record has ended (well or not); lastResult says how.
  void finished();

 private:
  void onStderr();
  void onFinished(int exitCode, QProcess::ExitStatus exitStatus);
  void onError(QProcess::ProcessError error);

  std::unique_ptr<QProcess> m_process;
  State m_state{Idle};
  QString m_folder;
  QString m_lastResult;
  QString m_stderr;
  QString m_program;
  QStringList m_recordedLogs;
  ModelStatus::Value m_status{ModelStatus::Ready};
  bool m_stopRequested{};
  bool m_began{};   ///< vcu record said "recording"
  bool m_killed{};  ///< it did not end within the stop timeout of SIGTERM: SIGKILL sent
  QElapsedTimer m_elapsed;
  QTimer m_tick;
  QTimer m_killTimer;
};

}  // namespace openvcu::hmi
