#pragma once
// The vcu-hmi process: command line, the stack connection, the QML engine, readiness
// (READY=1 on NOTIFY_SOCKET once the first frame is on screen), the screenshot mode of
// the tests (--screenshot DIR: every tab as PNG once the stack is attached) and the
// frame-rate report of the benchmark (--report-fps).
// @note GUI thread only.

#include <QElapsedTimer>
#include <QObject>
#include <QQmlApplicationEngine>
#include <QString>
#include <QStringList>
#include <QTimer>
#include <memory>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "openvcu/core/result.hpp"
#include "common/stack_connection.hpp"
#include "header/health_model.hpp"
#endif

class QQuickWindow;
class QSocketNotifier;

namespace openvcu::service {
class ShutdownSignals;
}

namespace openvcu::hmi {

struct HmiOptions {
  StackSettings stack;
  int width{720};
  int height{600};
  QString screenshotDir;  ///< empty: no screenshots
  bool exitAfterScreenshots{};
  bool reportFps{};                             ///< one "fps N" line per second on stdout
  double quitAfterSeconds{};                    ///< > 0: quit after this long (benchmarks)
  QStringList plotKeys;                         ///< signals plotted from the start (benchmarks, demos)
  int plotWindowSeconds{30};                    ///< the plot's first window: 10, 30, 60, 300 or 600
  bool framesPage{};                            ///< CAN Data shows the Frames page first
  QString tracePath;                            ///< a log or recording folder the Trace tab opens at start
  bool tracePageStatistics{};                   ///< the Trace tab shows its Statistics page first
  int tab{0};                                   ///< the tab shown first (0 Vehicle ... 5 Trace)
  bool softwareRenderer{true};                  ///< --renderer software (default) or gpu
  bool exitNow{};                               ///< --help / --version were answered
  service::ShutdownSignals* shutdown{nullptr};  ///< SIGTERM/SIGINT as an fd (main installs it)
};

/// Parses the arguments (argv[0] first). Usage errors are returned with a message;
/// --help and --version print and set exitNow.
Result<HmiOptions> parseCommandLine(const QStringList& arguments);

/// What can be checked before Qt opens a display: the configuration loads and builds a
/// catalog, and there is somewhere to draw (DISPLAY, WAYLAND_DISPLAY or QT_QPA_PLATFORM).
Status checkBeforeStart(const HmiOptions& options);

class HmiApp : public QObject {
  Q_OBJECT
 public:
  static Result<std::unique_ptr<HmiApp>> create(const HmiOptions& options);
  ~HmiApp() override;
  /// Runs the Qt event loop; the exit code.
  int run();

 private:
  explicit HmiApp(HmiOptions options, std::unique_ptr<StackConnection> stack);
  Status load();
  void onFrame();
  void screenshotStep();
  void reportHealth();
  void onShutdownSignal();

  HmiOptions m_options;
  std::unique_ptr<StackConnection> m_stack;
  std::unique_ptr<HealthModel> m_health;
  QQmlApplicationEngine m_engine;
  QQuickWindow* m_window{nullptr};
  bool m_readySent{};
  int m_frames{};
  QElapsedTimer m_fpsClock;
  QTimer m_screenshotTimer;
  int m_screenshotStage{};
  QElapsedTimer m_screenshotClock;
  QTimer m_healthTimer;
  std::vector<int> m_lastConnection;
  std::unique_ptr<QSocketNotifier> m_shutdownNotifier;
};

}  // namespace openvcu::hmi
