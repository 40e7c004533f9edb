// bench_hmi_plots: the live plot as Qt Charts or as the HMI's SignalPlot, same window
// (720x600), 4 signals, 60 points per second each, a 30 s window; frames rendered per
// second, CPU and RSS of this process. Decides docs/design/hmi.md's plot choice.
//   tests/harness/run_isolated.sh --keep $PWD -- build/bench/bench_hmi_plots charts|custom [SECONDS]
// "custom" creates a private signal table (instance "plotbench"): run it in the sandbox.
#include <QtQml/qqmlextensionplugin.h>
#include <sys/resource.h>
#include <unistd.h>

#include <QApplication>
#include <QElapsedTimer>
#include <QQmlApplicationEngine>
#include <QQmlContext>
#include <QQuickItem>
#include <QQuickView>
#include <QTimer>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <vector>

#include "openvcu/core/clock.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/signals/table.hpp"
#include "common/stack_connection.hpp"

Q_IMPORT_QML_PLUGIN(OpenVcu_ModelsPlugin)

namespace {

double cpuSeconds() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1e6;
}

double rssMb() {
  std::ifstream in("/proc/self/statm");
  long pages = 0;
  long resident = 0;
  in >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / 1e6;
}

}  // namespace

int main(int argc, char** argv) {
  QApplication application(argc, argv);  // Qt Charts needs QApplication; both modes use it
  const QStringList arguments = application.arguments();
  const bool charts = arguments.size() > 1 && arguments[1] == QStringLiteral("charts");
  const double seconds = arguments.size() > 2 ? arguments[2].toDouble() : 20.0;
  const QStringList keys = {"VIC.HVESSD1_PGN61584.HS_ULvl", "VIC.HVESSD1_PGN61584.HS_I",
                            "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "VIC.HVESSHIST_PGN64606.HS_StofHealth"};
  std::unique_ptr<openvcu::hmi::StackConnection> stack;
  std::optional<openvcu::signals::SignalTable> table;
  std::vector<openvcu::signals::SignalIndex> slots;
  QTimer writer;
  if (!charts) {
    openvcu::hmi::StackSettings settings;
    settings.configPath = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
    settings.instance = "plotbench";
    settings.lcmUrl = "memq://";
    auto vehicle = openvcu::config::loadVehicleConfig(settings.configPath);
    if (!vehicle) return std::fprintf(stderr, "%s\n", vehicle.error().toString().c_str()), 1;
    vehicle->instance = settings.instance;
    auto catalog = openvcu::config::buildCatalog(*vehicle);
    if (!catalog) return 1;
    auto opened = openvcu::signals::SignalTable::open(*catalog, settings.instance);
    if (!opened) return std::fprintf(stderr, "%s\n", opened.error().toString().c_str()), 1;
    table.emplace(std::move(*opened));
    for (const QString& key : keys) slots.push_back(*catalog->indexOf(key.toStdString()));
    auto connection = openvcu::hmi::StackConnection::open(settings);
    if (!connection) return 1;
    stack = std::move(*connection);
    writer.setInterval(16);
    QObject::connect(&writer, &QTimer::timeout, [&] {
      const double t = static_cast<double>(openvcu::clock::monotonicNs()) / 1e9;
      for (std::size_t i = 0; i < slots.size(); ++i) {
        table->writeBus(slots[i], 500 + 100 * std::sin(t * static_cast<double>(i + 1)),
                        openvcu::clock::monotonicNs(), 0xF3, openvcu::signals::Quality::Valid);
      }
    });
    writer.start();
  }
  QQuickView view;
  view.engine()->addImportPath(QStringLiteral("qrc:/"));
  view.rootContext()->setContextProperty(QStringLiteral("benchKeys"), keys);
  view.setSource(QUrl::fromLocalFile(QStringLiteral(OPENVCU_SOURCE_DIR "/bench/hmi/") +
                                     (charts ? QStringLiteral("plot_charts.qml") : QStringLiteral("plot_custom.qml"))));
  if (view.status() != QQuickView::Ready) return 1;
  view.resize(720, 600);
  view.show();
  int frames = 0;
  QObject::connect(&view, &QQuickWindow::frameSwapped, [&] { ++frames; });
  double cpuStart = 0;
  QElapsedTimer clock;
  QTimer::singleShot(3000, [&] {  // warm-up: the window fills
    frames = 0;
    cpuStart = cpuSeconds();
    clock.start();
  });
  QTimer::singleShot(static_cast<int>((3 + seconds) * 1000), [&] {
    const double elapsed = static_cast<double>(clock.elapsed()) / 1000.0;
    std::printf("%-7s %s: %.1f fps, CPU %.1f %%, RSS %.1f MB (%.0f s)\n", charts ? "charts" : "custom",
                qgetenv("QT_QPA_PLATFORM").constData(), frames / elapsed, 100 * (cpuSeconds() - cpuStart) / elapsed,
                rssMb(), elapsed);
    QCoreApplication::quit();
  });
  return QApplication::exec();
}
