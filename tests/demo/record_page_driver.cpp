// The HMI's Record page without its screen, for first_hour_test.sh: a process set up as
// vcu-hmi's main sets itself up (ShutdownSignals first: SIGTERM and SIGINT blocked, then a
// QGuiApplication, offscreen) runs the page's RecordController on the running stack, as the
// Record button does, and the Statistics tab's TraceStatsModel on what it recorded, as the
// Analyse button does.
//   record_page_driver --config FILE --data-folder DIR --vcu PROGRAM
// stdout: "recording FOLDER" once the controller is Recording; a line on stdin (or its end)
// is the Stop button; then "result: <the page's text>", "statistics: <summary>" and
// "statistics error: <text>" when there is one.
// Exit: 0 the page ended well (Ready, "recorded ...", a log to analyse) and the statistics
// report no malformed line and no step back in time; 1 otherwise; 2 usage error.
#include <unistd.h>

#include <QCoreApplication>
#include <QGuiApplication>
#include <QSocketNotifier>
#include <QTimer>
#include <cstdio>
#include <cstring>
#include <string>

#include "common/stack_connection.hpp"
#include "debug/record_controller.hpp"
#include "openvcu/service/shutdown.hpp"
#include "trace/trace_stats_model.hpp"

namespace {

constexpr int START_TIMEOUT_MS = 15000;

void say(const QString& text) {
  std::printf("%s\n", text.toLocal8Bit().constData());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  auto shutdownResult = openvcu::service::ShutdownSignals::install();  // as vcu-hmi's main, first
  if (!shutdownResult) {
    std::fprintf(stderr, "record_page_driver: error: %s\n", shutdownResult.error().toString().c_str());
    return 1;
  }
  openvcu::hmi::StackSettings settings;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string option = argv[i];
    if (option == "--config") {
      settings.configPath = argv[i + 1];
    } else if (option == "--data-folder") {
      settings.dataFolder = argv[i + 1];
    } else if (option == "--vcu") {
      settings.vcuProgram = argv[i + 1];
    } else {
      std::fprintf(stderr, "record_page_driver: error: unknown option '%s'\n", argv[i]);
      return 2;
    }
  }
  if (argc != 7 || settings.configPath.empty() || settings.dataFolder.empty() || settings.vcuProgram.empty()) {
    std::fprintf(stderr, "usage: record_page_driver --config FILE --data-folder DIR --vcu PROGRAM\n");
    return 2;
  }
  qputenv("QT_QPA_PLATFORM", "offscreen");
  QGuiApplication application(argc, argv);
  auto connection = openvcu::hmi::StackConnection::open(settings);
  if (!connection) {
    std::fprintf(stderr, "record_page_driver: error: %s\n", connection.error().toString().c_str());
    return 1;
  }

  using openvcu::hmi::RecordController;
  RecordController page;
  QTimer startTimeout;
  startTimeout.setSingleShot(true);
  QObject::connect(&startTimeout, &QTimer::timeout, &application, [&] {
    say(QStringLiteral("result: not Recording within 15 s: ") + page.lastResult());
    page.stop();
  });
  QObject::connect(&page, &RecordController::changed, &application, [&] {
    if (page.state() == RecordController::Recording && startTimeout.isActive()) {
      startTimeout.stop();
      say(QStringLiteral("recording ") + page.folder());
    }
  });
  QSocketNotifier stopButton(STDIN_FILENO, QSocketNotifier::Read);
  QObject::connect(&stopButton, &QSocketNotifier::activated, &application, [&] {
    char line[64];
    [[maybe_unused]] const ssize_t ignored = ::read(STDIN_FILENO, line, sizeof line);  // the press, or EOF
    stopButton.setEnabled(false);
    page.stop();
  });
  QObject::connect(&page, &RecordController::finished, &application, [&] { application.quit(); });
  if (const QString refused = page.start(); !refused.isEmpty()) {
    say(QStringLiteral("result: ") + refused);
    return 1;
  }
  startTimeout.start(START_TIMEOUT_MS);
  application.exec();

  say(QStringLiteral("result: ") + page.lastResult());
  bool good = page.status() == openvcu::hmi::ModelStatus::Ready &&
              page.lastResult().startsWith(QStringLiteral("recorded ")) && !page.recordedLogs().isEmpty();
  if (good) {
    openvcu::hmi::TraceStatsModel statistics;
    statistics.compute(page.recordedLogs());
    statistics.waitUntilComputed();
    say(QStringLiteral("statistics: ") + statistics.summary());
    const QString error = statistics.errorString();
    if (!error.isEmpty()) say(QStringLiteral("statistics error: ") + error);
    good = statistics.status() != openvcu::hmi::ModelStatus::Error && !error.contains(QStringLiteral("malformed")) &&
           !error.contains(QStringLiteral("backwards"));
  }
  return good ? 0 : 1;
}
