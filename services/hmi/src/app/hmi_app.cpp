#include "app/hmi_app.hpp"

#include <QCommandLineParser>
#include <QCoreApplication>
#include <QDir>
#include <QFileInfo>
#include <QImage>
#include <QQmlContext>
#include <QQuickItem>
#include <QQuickWindow>
#include <QSocketNotifier>
#include <cstdio>

#include "openvcu/check/vehicle_check.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/dashboard.hpp"
#include "openvcu/service/notify.hpp"
#include "openvcu/service/shutdown.hpp"

namespace openvcu::hmi {
namespace {

/// The tabs of Main.qml in order; the trace viewer is the sixth page.
const char* const TAB_NAMES[] = {"vehicle", "dashboard", "can-data", "ecu-setup", "debug", "trace"};
constexpr int TAB_COUNT = 6;
/// Screenshots wait this long at most for the stack before taking what there is.
constexpr qint64 SCREENSHOT_WAIT_MS = 15000;
/// ... and then this long for values to arrive and plots to fill.
constexpr qint64 SCREENSHOT_SETTLE_MS = 2500;

void printLine(const QString& line) {
  std::fprintf(stdout, "%s\n", line.toLocal8Bit().constData());
  std::fflush(stdout);
}

}  // namespace

Result<HmiOptions> parseCommandLine(const QStringList& arguments) {
  QCommandLineParser parser;
  parser.setApplicationDescription(
      "vcu-hmi: the touchscreen dashboard of an openvcu stack (vehicle switches, dashboard, CAN data and plots, "
      "ECU setup, debug, trace viewer).");
  parser.addHelpOption();
  parser.addVersionOption();
  const QCommandLineOption config({"c", "config"}, "the vehicle configuration (default: $OPENVCU_CONFIG)", "FILE");
  const QCommandLineOption dashboard("dashboard", "dashboard file: dials and tiles (config/hhea/dashboard.json)",
                                     "FILE");
  const QCommandLineOption instance("instance", "stack instance; overrides the configuration's", "NAME");
  const QCommandLineOption lcmUrl("lcm-url", "event bus URL; overrides the configuration's", "URL");
  const QCommandLineOption supervisor("supervisor-config", "supervisord file, for restarting a service", "FILE");
  const QCommandLineOption dataFolder(
      "data-folder",
      "where exports and recordings (DIR/recordings/<time>) go and the trace viewer's Browse starts (default: "
      "$HOME/openvcu)",
      "DIR");
  const QCommandLineOption vcu("vcu", "the vcu program the Record button runs (default: vcu beside vcu-hmi, else PATH)",
                               "PROGRAM");
  const QCommandLineOption zone("time-zone", "IANA time zone of the header clock (default: the system's)", "ZONE");
  const QCommandLineOption size("size", "window size (default 720x600; 800x480 also fits)", "WxH", "720x600");
  const QCommandLineOption screenshot("screenshot", "save every tab as DIR/tab-N-NAME.png once the stack is attached",
                                      "DIR");
  const QCommandLineOption exitAfter("exit-after-screenshots", "quit once the screenshots are saved");
  const QCommandLineOption fps("report-fps", "print 'fps N' once a second (benchmarks)");
  const QCommandLineOption quitAfter("quit-after", "quit after SECONDS (benchmarks)", "SECONDS");
  const QCommandLineOption plotWindow("plot-window", "the live plot's first window: 10, 30, 60, 300 or 600 s",
                                      "SECONDS", "30");
  const QCommandLineOption canPage("can-page", "CAN Data's first page: plot or frames", "PAGE", "plot");
  const QCommandLineOption trace("trace", "open this log, or the *.log files of this folder, in the Trace tab at start",
                                 "PATH");
  const QCommandLineOption tracePage("trace-page", "the Trace tab's first page: signals or statistics", "PAGE",
                                     "signals");
  const QCommandLineOption noFrames("no-frames", "do not subscribe to raw frames (no iceoryx / iox-roudi)");
  const QCommandLineOption plot("plot", "plot these signals from the start (comma-separated keys)", "KEYS");
  const QCommandLineOption renderer(
      "renderer",
      "software (default: Qt Quick's software renderer, 7 % CPU / 66 MB measured) or gpu (the platform's "
      "graphics API: OpenGL/Vulkan; Mesa llvmpipe without a GPU costs 41 % / 152 MB); QT_QUICK_BACKEND wins",
      "NAME", "software");
  const QCommandLineOption tab(
      "tab", "the tab shown first: 0 Vehicle, 1 Dashboard, 2 CAN Data, 3 ECU Setup, 4 Debug, 5 Trace", "INDEX", "0");
  parser.addOptions({plotWindow, canPage, trace, tracePage});
  parser.addOptions({config, dashboard, instance, lcmUrl, supervisor, dataFolder, vcu, zone, size, screenshot, exitAfter, fps, quitAfter,
                     plot, tab, noFrames, renderer});
  if (!parser.parse(arguments)) return Error{parser.errorText().toStdString()};
  if (parser.isSet(QStringLiteral("help"))) {
    printLine(parser.helpText().replace(QStringLiteral("<executable_name>"), QStringLiteral("vcu-hmi")));
    HmiOptions options;
    options.exitNow = true;
    return options;
  }
  if (parser.isSet(QStringLiteral("version"))) {
    printLine(QCoreApplication::applicationName() + QLatin1Char(' ') + QCoreApplication::applicationVersion());
    HmiOptions options;
    options.exitNow = true;
    return options;
  }
  HmiOptions options;
  options.stack.configPath = parser.value(config).toStdString();
  if (options.stack.configPath.empty()) {
    if (const char* fromEnvironment = std::getenv("OPENVCU_CONFIG")) options.stack.configPath = fromEnvironment;
  }
  if (options.stack.configPath.empty()) return Error{"no configuration: give --config FILE or set OPENVCU_CONFIG"};
  options.stack.dashboardPath = parser.value(dashboard).toStdString();
  if (options.stack.dashboardPath.empty()) {
    // default: dashboard.json beside the vehicle configuration, when there is one
    options.stack.dashboardPath = config::dashboardBeside(options.stack.configPath);
  }
  options.stack.instance = parser.value(instance).toStdString();
  options.stack.lcmUrl = parser.value(lcmUrl).toStdString();
  options.stack.supervisorConfig = parser.value(supervisor).toStdString();
  options.stack.timeZone = parser.value(zone).toStdString();
  options.stack.dataFolder = parser.value(dataFolder).toStdString();
  options.stack.vcuProgram = parser.value(vcu).toStdString();
  if (!options.stack.timeZone.empty() && !QTimeZone(QByteArray::fromStdString(options.stack.timeZone)).isValid()) {
    return Error{"--time-zone '" + options.stack.timeZone +
                 "': unknown time zone (an IANA name, e.g. Europe/Helsinki)"};
  }
  const QStringList parts = parser.value(size).split(QLatin1Char('x'));
  bool widthOk = false;
  bool heightOk = false;
  if (parts.size() == 2) {
    options.width = parts[0].toInt(&widthOk);
    options.height = parts[1].toInt(&heightOk);
  }
  if (!widthOk || !heightOk || options.width < 320 || options.height < 240 || options.width > 8192 ||
      options.height > 8192) {
    return Error{"--size '" + parser.value(size).toStdString() + "': expected WIDTHxHEIGHT, e.g. 720x600"};
  }
  options.stack.frameStreams = !parser.isSet(noFrames);
  if (parser.value(renderer) == QLatin1String("software")) {
    options.softwareRenderer = true;
  } else if (parser.value(renderer) == QLatin1String("gpu")) {
    options.softwareRenderer = false;
  } else {
    return Error{"--renderer '" + parser.value(renderer).toStdString() + "': expected software or gpu"};
  }
  options.screenshotDir = parser.value(screenshot);
  options.exitAfterScreenshots = parser.isSet(exitAfter);
  options.reportFps = parser.isSet(fps);
  if (parser.isSet(quitAfter)) {
    bool ok = false;
    options.quitAfterSeconds = parser.value(quitAfter).toDouble(&ok);
    if (!ok || options.quitAfterSeconds <= 0) return Error{"--quit-after: expected a positive number of seconds"};
  }
  bool tabOk = false;
  options.tab = parser.value(tab).toInt(&tabOk);
  if (!tabOk || options.tab < 0 || options.tab >= TAB_COUNT) return Error{"--tab: expected 0..5"};
  if (parser.isSet(plot)) options.plotKeys = parser.value(plot).split(QLatin1Char(','), Qt::SkipEmptyParts);
  options.plotWindowSeconds = parser.value(plotWindow).toInt();
  if (!QList<int>{10, 30, 60, 300, 600}.contains(options.plotWindowSeconds) ||
      QString::number(options.plotWindowSeconds) != parser.value(plotWindow)) {
    return Error{"--plot-window '" + parser.value(plotWindow).toStdString() + "': expected 10, 30, 60, 300 or 600"};
  }
  if (parser.value(canPage) != QLatin1String("plot") && parser.value(canPage) != QLatin1String("frames")) {
    return Error{"--can-page '" + parser.value(canPage).toStdString() + "': expected plot or frames"};
  }
  options.framesPage = parser.value(canPage) == QLatin1String("frames");
  if (parser.value(tracePage) != QLatin1String("signals") && parser.value(tracePage) != QLatin1String("statistics")) {
    return Error{"--trace-page '" + parser.value(tracePage).toStdString() + "': expected signals or statistics"};
  }
  options.tracePageStatistics = parser.value(tracePage) == QLatin1String("statistics");
  options.tracePath = parser.value(trace);
  if (!options.tracePath.isEmpty()) {
    options.tracePath = QFileInfo(options.tracePath).absoluteFilePath();
    if (!QFileInfo::exists(options.tracePath)) {
      return Error{"--trace '" + parser.value(trace).toStdString() + "': no such file or folder"};
    }
  }
  if (!parser.positionalArguments().isEmpty()) {
    return Error{"unexpected argument '" + parser.positionalArguments().first().toStdString() + "' (see --help)"};
  }
  return options;
}

Status checkBeforeStart(const HmiOptions& options) {
  auto vehicle = config::loadVehicleConfig(options.stack.configPath);
  if (!vehicle) return vehicle.error();
  auto catalog = config::buildCatalog(*vehicle);
  if (!catalog) return Error{options.stack.configPath + ": " + catalog.error().message};
  // the whole-vehicle checks every service runs at start (service::Service::open): an error refuses
  for (const Error& diagnostic : check::checkVehicle(*vehicle, *catalog)) {
    if (diagnostic.severity == Severity::Error) return diagnostic;
  }
  const bool display = !qEnvironmentVariableIsEmpty("DISPLAY") || !qEnvironmentVariableIsEmpty("WAYLAND_DISPLAY") ||
                       !qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM");
  if (!display) {
    return Error{"no display: set DISPLAY (X11), WAYLAND_DISPLAY, or QT_QPA_PLATFORM (e.g. offscreen, eglfs, linuxfb)"};
  }
  return {};
}

Result<std::unique_ptr<HmiApp>> HmiApp::create(const HmiOptions& options) {
  auto stackResult = StackConnection::open(options.stack);
  if (!stackResult) return stackResult.error();
  std::unique_ptr<HmiApp> app(new HmiApp(options, std::move(*stackResult)));
  if (Status loaded = app->load(); !loaded) return loaded.error();
  return app;
}

HmiApp::HmiApp(HmiOptions options, std::unique_ptr<StackConnection> stack)
    : m_options(std::move(options)), m_stack(std::move(stack)), m_health(std::make_unique<HealthModel>()) {}

HmiApp::~HmiApp() {
  // QML objects refer to the stack: destroy the scene first.
  const auto roots = m_engine.rootObjects();
  for (QObject* root : roots) delete root;
}

Status HmiApp::load() {
  m_engine.rootContext()->setContextProperty(QStringLiteral("initialPlotKeys"), m_options.plotKeys);
  m_engine.rootContext()->setContextProperty(QStringLiteral("initialPlotWindow"), m_options.plotWindowSeconds);
  m_engine.rootContext()->setContextProperty(QStringLiteral("initialCanPageFrames"), m_options.framesPage);
  m_engine.rootContext()->setContextProperty(QStringLiteral("initialTracePath"), m_options.tracePath);
  m_engine.rootContext()->setContextProperty(QStringLiteral("initialTraceStatistics"), m_options.tracePageStatistics);
  m_engine.addImportPath(QStringLiteral("qrc:/"));  // the OpenVcu.Hmi module lives at qrc:/OpenVcu/Hmi
  m_engine.load(QUrl(QStringLiteral("qrc:/OpenVcu/Hmi/qml/Main.qml")));
  if (m_engine.rootObjects().isEmpty()) return Error{"the QML user interface did not load (see the messages above)"};
  m_window = qobject_cast<QQuickWindow*>(m_engine.rootObjects().first());
  if (!m_window) return Error{"Main.qml's root is not a window"};
  m_window->resize(m_options.width, m_options.height);
  m_window->setProperty("currentTab", m_options.tab);
  m_window->show();
  connect(m_window, &QQuickWindow::frameSwapped, this, &HmiApp::onFrame);
  m_fpsClock.start();
  if (!m_options.screenshotDir.isEmpty()) {
    if (!QDir().mkpath(m_options.screenshotDir)) {
      return Error{"--screenshot: cannot create '" + m_options.screenshotDir.toStdString() + "'"};
    }
    m_screenshotClock.start();
    m_screenshotTimer.setInterval(250);
    connect(&m_screenshotTimer, &QTimer::timeout, this, &HmiApp::screenshotStep);
    m_screenshotTimer.start();
  }
  if (m_options.shutdown) {
    m_shutdownNotifier = std::make_unique<QSocketNotifier>(m_options.shutdown->fd(), QSocketNotifier::Read);
    connect(m_shutdownNotifier.get(), &QSocketNotifier::activated, this, &HmiApp::onShutdownSignal);
  }
  m_healthTimer.setInterval(1000);
  connect(&m_healthTimer, &QTimer::timeout, this, &HmiApp::reportHealth);
  m_healthTimer.start();
  if (m_options.quitAfterSeconds > 0) {
    QTimer::singleShot(static_cast<int>(m_options.quitAfterSeconds * 1000), qApp, &QCoreApplication::quit);
  }
  return {};
}

int HmiApp::run() {
  return QCoreApplication::exec();
}

void HmiApp::onFrame() {
  if (!m_readySent) {
    m_readySent = true;
    printLine(QStringLiteral("vcu-hmi: ready (pid %1, instance %2, %3x%4)")
                  .arg(QCoreApplication::applicationPid())
                  .arg(m_stack->instanceName())
                  .arg(m_options.width)
                  .arg(m_options.height));
    service::Notifier::fromEnvironment().ready("ready");
  }
  ++m_frames;
  if (m_options.reportFps) {
    // frames actually rendered: the live plot scrolls at SignalPlot::SAMPLE_HZ, so with a
    // plot on screen this is the animating frame rate (capped by that timer and vsync)
    if (m_fpsClock.elapsed() >= 1000) {
      printLine(QStringLiteral("fps %1").arg(
          static_cast<double>(m_frames) * 1000.0 / static_cast<double>(m_fpsClock.elapsed()), 0, 'f', 1));
      m_frames = 0;
      m_fpsClock.restart();
    }
  }
}

void HmiApp::screenshotStep() {
  QObject* root = m_window;
  // stage 0: wait for the stack (table attached and a heartbeat heard) or the time limit
  if (m_screenshotStage == 0) {
    const bool attached = m_stack->table() != nullptr && m_health->status() != ModelStatus::NotConnected;
    if (!attached && m_screenshotClock.elapsed() < SCREENSHOT_WAIT_MS) return;
    m_screenshotStage = 1;
    m_screenshotClock.restart();
    return;
  }
  if (m_screenshotStage == 1) {
    if (m_screenshotClock.elapsed() < SCREENSHOT_SETTLE_MS) return;
    m_screenshotStage = 2;
  }
  // stages 2, 3, ...: even = switch to a tab, odd = grab it (one timer interval later)
  const int step = m_screenshotStage - 2;
  const int tab = step / 2;
  if (tab >= TAB_COUNT) {
    m_screenshotTimer.stop();
    root->setProperty("currentTab", 0);
    printLine(QStringLiteral("screenshots done: %1").arg(m_options.screenshotDir));
    if (m_options.exitAfterScreenshots) QCoreApplication::quit();
    return;
  }
  if (step % 2 == 0) {
    root->setProperty("currentTab", tab);
  } else {
    const QImage image = m_window->grabWindow();
    const QString path =
        QDir(m_options.screenshotDir).filePath(QStringLiteral("tab-%1-%2.png").arg(tab).arg(TAB_NAMES[tab]));
    printLine(image.save(path) ? QStringLiteral("screenshot %1").arg(path)
                               : QStringLiteral("screenshot FAILED %1").arg(path));
  }
  ++m_screenshotStage;
}

void HmiApp::onShutdownSignal() {
  const auto signal = m_options.shutdown->take();
  if (!signal) return;
  const std::string reason = "stopping (" + service::signalName(*signal) + ")";
  printLine(QStringLiteral("vcu-hmi: ") + QString::fromStdString(reason));
  service::Notifier::fromEnvironment().stopping(reason);
  QCoreApplication::quit();
}

void HmiApp::reportHealth() {
  // One line per change of a service's connection: the tests and the journal see them.
  const int rows = m_health->rowCount();
  m_lastConnection.resize(static_cast<std::size_t>(rows), -1);
  for (int row = 0; row < rows; ++row) {
    const QModelIndex index = m_health->index(row);
    const int connection = m_health->data(index, HealthModel::ConnectionRole).toInt();
    if (connection == m_lastConnection[static_cast<std::size_t>(row)]) continue;
    m_lastConnection[static_cast<std::size_t>(row)] = connection;
    printLine(QStringLiteral("service %1: %2")
                  .arg(m_health->data(index, HealthModel::NameRole).toString())
                  .arg(QString::fromStdString(std::string(statusName(static_cast<ValueStatus>(connection))))));
  }
}

}  // namespace openvcu::hmi
