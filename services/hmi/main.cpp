// vcu-hmi: the Qt 6 Quick touchscreen dashboard over a running openvcu stack.
// README.md says what it shows and commands; docs/design/hmi.md how it is built.
#include <QtQml/qqmlextensionplugin.h>
#include <linux/close_range.h>
#include <unistd.h>

#include <QCommandLineParser>
#include <QGuiApplication>
#include <QQmlApplicationEngine>
#include <QQmlContext>
#include <QQuickWindow>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "app/hmi_app.hpp"
#include "openvcu/service/options.hpp"
#include "openvcu/service/shutdown.hpp"

Q_IMPORT_QML_PLUGIN(OpenVcu_ModelsPlugin)
Q_IMPORT_QML_PLUGIN(OpenVcu_HmiPlugin)

int main(int argc, char** argv) {
  // Before any thread exists (Qt, LCM): SIGTERM and SIGINT become an fd the event loop reads.
  auto shutdownResult = openvcu::service::ShutdownSignals::install();
  if (!shutdownResult) {
    std::fprintf(stderr, "vcu-hmi: error: %s\n", shutdownResult.error().toString().c_str());
    return 1;
  }
  // Options and configuration are checked before Qt opens a display: --help, usage and
  // configuration errors are one line and an exit code even on a machine without one.
  QCoreApplication::setApplicationName(QStringLiteral("vcu-hmi"));
  QCoreApplication::setApplicationVersion(QStringLiteral(OPENVCU_HMI_VERSION));
  QStringList arguments;
  for (int i = 0; i < argc; ++i) arguments << QString::fromLocal8Bit(argv[i]);
  auto optionsResult = openvcu::hmi::parseCommandLine(arguments);
  if (!optionsResult) {
    std::fprintf(stderr, "vcu-hmi: error: %s\n", optionsResult.error().toString().c_str());
    return 2;
  }
  if (optionsResult->exitNow) return 0;
  if (auto checked = openvcu::hmi::checkBeforeStart(*optionsResult); !checked) {
    std::fprintf(stderr, "vcu-hmi: error: %s\n", checked.error().toString().c_str());
    return 1;
  }
  optionsResult->shutdown = &*shutdownResult;
  // QGuiApplication may take its own options out of argv: keep the arguments for a restart
  std::vector<std::string> original(argv, argv + argc);
  // Qt Quick's software renderer unless --renderer gpu or QT_QUICK_BACKEND says otherwise:
  // without a GPU (Mesa llvmpipe) the graphics API costs 6x the CPU and 2.3x the memory
  // (docs/benchmarks.md "## hmi")
  if (optionsResult->softwareRenderer && qEnvironmentVariableIsEmpty("QT_QUICK_BACKEND")) {
    QQuickWindow::setGraphicsApi(QSGRendererInterface::Software);
  }
  QGuiApplication application(argc, argv);
  auto appResult = openvcu::hmi::HmiApp::create(*optionsResult);
  if (!appResult) {
    std::fprintf(stderr, "vcu-hmi: error: %s\n", appResult.error().toString().c_str());
    return 1;
  }
  std::unique_ptr<openvcu::hmi::HmiApp> app = std::move(*appResult);
  const int code = app->run();
  app.reset();  // models, threads, the event bus and the table go first
  if (code == static_cast<int>(openvcu::service::ExitCode::RoudiRestarted)) {
    // A new iox-roudi: this process's iceoryx ports cannot follow it. Start again in place
    // (same pid for a supervisor); if that fails, the exit code asks a supervisor for it.
    std::printf("vcu-hmi: iox-roudi was restarted: executing vcu-hmi again\n");
    std::fflush(stdout);
    std::vector<char*> args;
    for (std::string& argument : original) args.push_back(argument.data());
    args.push_back(nullptr);
    // Every descriptor but stdin/out/err goes: iceoryx holds a lock on its runtime name's
    // lock file, and the new image registers under the same name.
    ::close_range(3, ~0U, 0);
    ::execv("/proc/self/exe", args.data());
    std::fprintf(stderr, "vcu-hmi: error: cannot execute itself again: %s\n", std::strerror(errno));
  }
  return code;
}
