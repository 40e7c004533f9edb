// vcu-hmi: the Qt 6 Quick touchscreen dashboard over a running openvcu stack.
// README.md says what it shows and commands; docs/design/hmi.md how it is built.
#include <QtQml/qqmlextensionplugin.h>

#include <QCommandLineParser>
#include <QGuiApplication>
#include <QQmlApplicationEngine>
#include <QQmlContext>
#include <QQuickWindow>
#include <cstdio>
#include <cstdlib>

#include "hmi_app.hpp"
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
  QGuiApplication application(argc, argv);
  auto appResult = openvcu::hmi::HmiApp::create(*optionsResult);
  if (!appResult) {
    std::fprintf(stderr, "vcu-hmi: error: %s\n", appResult.error().toString().c_str());
    return 1;
  }
  return (*appResult)->run();
}
