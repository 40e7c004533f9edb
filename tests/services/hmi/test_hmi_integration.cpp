// vcu-hmi on the whole simulated HHEA stack in the sandbox (issue 10): iox-roudi, vcu-can-rx,
// vcu-can-tx, vcu-fsm, vcu-gpio, vcu-ecu-sim and vcu-hmi.
//   - under Xvfb (its own display inside the sandbox), the vehicle driven to Driving: every
//     tab saved as PNG in the build folder and checked for being non-trivial (size, number
//     of distinct colours);
//   - offscreen: every other service and iox-roudi SIGKILLed, the HMI lives on and reports
//     them late; RouDi and the FSM restarted, the FSM reported Ready again;
//   - in process: the HMI's own models on the real stack: the Start switch accepted by
//     vcu-fsm and the state changing, raw frames both ways over iceoryx; a refused command
//     shows vcu-fsm's reason; the ECU setup's cycle change and override accepted by can-tx;
//     the Record button running the real `vcu record` on the stack, stopped by SIGTERM, and
//     the Statistics page's model on what it recorded (issue 21), with SIGTERM and SIGINT
//     blocked as vcu-hmi's main blocks them: the recording ends well and reads without a
//     skipped line or a step back in time.
#include <doctest/doctest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <QElapsedTimer>
#include <QFileInfo>
#include <QGuiApplication>
#include <QImage>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QTest>
#include <QVariantMap>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "can/frame_trace_model.hpp"
#include "common/stack_connection.hpp"
#include "debug/record_controller.hpp"
#include "header/fsm_model.hpp"
#include "hmi_test_support.hpp"
#include "integration_support.hpp"
#include "setup/schedule_model.hpp"
#include "trace/trace_stats_model.hpp"
#include "vehicle/operator_model.hpp"

namespace harness = openvcu::harness;
namespace fs = std::filesystem;
using namespace openvcu::integration;
using namespace std::chrono_literals;

namespace {

const std::vector<std::pair<std::string, std::string>> SERVICES = {{"can-rx", CAN_RX_BINARY},
                                                                   {"can-tx", CAN_TX_BINARY},
                                                                   {"fsm", FSM_BINARY},
                                                                   {"gpio", GPIO_BINARY},
                                                                   {"ecu-sim", ECU_SIM_BINARY}};
const char* const TABS[] = {"tab-0-vehicle.png",   "tab-1-dashboard.png", "tab-2-can-data.png",
                            "tab-3-ecu-setup.png", "tab-4-debug.png",     "tab-5-trace.png"};
/// A screenshot with fewer distinct colours than this is a blank or a plain error screen.
constexpr std::size_t MIN_COLOURS = 24;
constexpr qint64 MIN_PNG_BYTES = 8 * 1024;

struct HmiStack : ConfiguredStack {
  std::vector<harness::Process*> services;
  HmiStack() : ConfiguredStack(copyHheaConfig(fs::temp_directory_path() / "hhea")) {
    REQUIRE_STATUS(sut.startRoudi());
    for (const auto& [name, binary] : SERVICES) services.push_back(&startService(name, binary));
    ::mkdir("/tmp/xdg", 0700);
  }
  harness::Process& startHmi(std::vector<std::string> extraArguments, std::vector<std::string> environment) {
    std::vector<std::string> argv{HMI_BINARY, "--config", config.string(), "--dashboard", HMI_DASHBOARD};
    argv.insert(argv.end(), extraArguments.begin(), extraArguments.end());
    environment.emplace_back("XDG_RUNTIME_DIR=/tmp/xdg");
    auto process = sut.start(harness::ProcessSpec{
        .name = "hmi", .argv = argv, .environment = environment, .notifyReadiness = true, .captureOutput = true});
    REQUIRE_STATUS(process);
    return **process;
  }
};

/// SIGTERM and SIGINT blocked in this thread for the scope, as vcu-hmi's main blocks them
/// (service::ShutdownSignals) before Qt starts; children of this thread inherit the mask.
class BlockedStopSignals {
 public:
  BlockedStopSignals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    ::pthread_sigmask(SIG_BLOCK, &set, &m_previous);
  }
  BlockedStopSignals(const BlockedStopSignals&) = delete;
  BlockedStopSignals& operator=(const BlockedStopSignals&) = delete;
  ~BlockedStopSignals() { ::pthread_sigmask(SIG_SETMASK, &m_previous, nullptr); }

 private:
  sigset_t m_previous{};
};

/// The pids of this process's children running `name` (/proc/PID/stat: "pid (comm) state ppid").
std::vector<pid_t> childrenNamed(const std::string& name) {
  std::vector<pid_t> found;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string pidText = entry.path().filename().string();
    if (pidText.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const std::size_t open = line.find('(');
    const std::size_t close = line.rfind(')');
    if (open == std::string::npos || close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state = 0;
    pid_t parent = 0;
    rest >> state >> parent;
    if (parent == ::getpid() && line.substr(open + 1, close - open - 1) == name) found.push_back(std::stoi(pidText));
  }
  return found;
}

/// The threads of `pid` that block SIGTERM or SIGINT (SigBlk of /proc/PID/task/TID/status).
std::vector<std::string> threadsBlockingStopSignals(pid_t pid) {
  constexpr unsigned long long STOP_BITS = (1ull << (SIGTERM - 1)) | (1ull << (SIGINT - 1));
  std::vector<std::string> blocking;
  std::error_code error;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", error)) {
    std::ifstream status(task.path() / "status");
    for (std::string line; std::getline(status, line);) {
      if (line.rfind("SigBlk:", 0) == 0 && (std::stoull(line.substr(7), nullptr, 16) & STOP_BITS) != 0) {
        blocking.push_back(task.path().filename().string());
      }
    }
  }
  return blocking;
}

std::size_t distinctColours(const QImage& image) {
  std::set<QRgb> colours;
  for (int y = 0; y < image.height(); y += 2) {
    for (int x = 0; x < image.width(); x += 2) colours.insert(image.pixel(x, y));
  }
  return colours.size();
}

}  // namespace

TEST_CASE("vcu-hmi under Xvfb with the whole stack saves a non-trivial screenshot of every tab") {
  SKIP_UNLESS_ISOLATED();
  // scripts/install-deps.sh installs Xvfb: without it this test fails rather than passing unrun
  REQUIRE_MESSAGE(fs::exists("/usr/bin/Xvfb"), "Xvfb is not installed (scripts/install-deps.sh installs xvfb)");
  HmiStack s;
  // -displayfd: Xvfb picks a free display and writes its number when it accepts clients
  auto xvfb = s.sut.start(harness::ProcessSpec{
      .name = "xvfb",
      .argv = {"/usr/bin/Xvfb", "-displayfd", "1", "-screen", "0", "1024x768x24", "-nolisten", "tcp"},
      .captureOutput = true});
  REQUIRE_STATUS(xvfb);
  std::optional<std::string> display;
  for (int line = 0; line < 20 && !display; ++line) {  // warnings may come first
    const auto text = (*xvfb)->readLine(10s);
    REQUIRE_MESSAGE(text, "Xvfb did not report its display");
    if (!text->empty() && text->find_first_not_of("0123456789") == std::string::npos) display = text;
  }
  REQUIRE(display);
  // drive the vehicle first, so that the screens show live values (Start, then Connect Driving)
  s.openTable();
  s.set("internal.operator.StartStop", "Start");
  REQUIRE(waitForBus(*s.table, s.index("internal.fsm.state"), hheaStateIndex("Ready"), 10s));
  s.set("internal.operator.ConnectDriving", "1");
  REQUIRE(waitForBus(*s.table, s.index("internal.fsm.state"), hheaStateIndex("Driving"), 10s));
  fs::remove_all(HMI_SCREENSHOT_DIR);
  harness::Process& hmi = s.startHmi(
      {"--screenshot", HMI_SCREENSHOT_DIR, "--plot", "VIC.HVESSD1_PGN61584.HS_ULvl,VIC.HVESSD1_PGN61584.HS_I"},
      {"DISPLAY=:" + *display, "QT_QPA_PLATFORM=xcb"});
  REQUIRE_MESSAGE(hmi.waitForLine("service vcu-fsm: Ready", 15s), "the HMI never heard vcu-fsm");
  REQUIRE_MESSAGE(hmi.waitForLine("screenshots done", 40s), "no screenshots");
  for (const char* tab : TABS) {
    const fs::path file = fs::path(HMI_SCREENSHOT_DIR) / tab;
    REQUIRE_MESSAGE(fs::exists(file), file.string());
    CHECK_MESSAGE(static_cast<qint64>(fs::file_size(file)) >= MIN_PNG_BYTES, file.string());
    const QImage image(QString::fromStdString(file.string()));
    REQUIRE_MESSAGE(!image.isNull(), file.string());
    CHECK(image.width() == 720);
    CHECK(image.height() == 600);
    const std::size_t colours = distinctColours(image);
    CHECK_MESSAGE(colours >= MIN_COLOURS, file.string() << ": " << colours << " colours");
  }
  // the live plot really draws: pixels of both series' colours in the plot area of the CAN
  // Data tab (right half, above the legend; a renderer that skips the lines leaves none)
  const QImage canData(QString::fromStdString((fs::path(HMI_SCREENSHOT_DIR) / "tab-2-can-data.png").string()));
  for (const QRgb series : {qRgb(0x42, 0xa5, 0xf5), qRgb(0xff, 0xa7, 0x26)}) {
    int pixels = 0;
    for (int y = 200; y < std::min(510, canData.height()); ++y) {
      for (int x = 330; x < canData.width(); ++x) pixels += (canData.pixel(x, y) & 0xFFFFFFu) == (series & 0xFFFFFFu);
    }
    CHECK_MESSAGE(pixels >= 20,
                  "plot line of colour " << std::hex << series << ": " << std::dec << pixels << " pixels");
  }
  CHECK(hmi.running());

  // the 800x480 panel: a second HMI on the same stack, every tab at that size
  const fs::path small = fs::path(HMI_SCREENSHOT_DIR) / "800x480";
  harness::Process& second =
      s.startHmi({"--size", "800x480", "--screenshot", small.string(), "--exit-after-screenshots"},
                 {"DISPLAY=:" + *display, "QT_QPA_PLATFORM=xcb"});
  REQUIRE_MESSAGE(second.waitForLine("screenshots done", 40s), "no 800x480 screenshots");
  for (const char* tab : TABS) {
    const QImage image(QString::fromStdString((small / tab).string()));
    REQUIRE_MESSAGE(!image.isNull(), (small / tab).string());
    CHECK(image.width() == 800);
    CHECK(image.height() == 480);
    CHECK_MESSAGE(distinctColours(image) >= MIN_COLOURS, (small / tab).string());
  }
}

TEST_CASE(
    "vcu-hmi survives the death of every other service and of iox-roudi, reports them late and sees the FSM return") {
  SKIP_UNLESS_ISOLATED();
  HmiStack s;
  harness::Process& hmi = s.startHmi({}, {"QT_QPA_PLATFORM=offscreen"});
  REQUIRE_MESSAGE(hmi.waitForLine("service vcu-fsm: Ready", 15s), "the HMI never heard vcu-fsm");
  REQUIRE(hmi.waitForLine("service vcu-ecu-sim: Ready", 10s));
  for (harness::Process* process : s.services) {
    REQUIRE(process->signal(SIGKILL));
    REQUIRE(process->waitForExit(5s));
  }
  REQUIRE(s.sut.roudi() != nullptr);
  REQUIRE(s.sut.roudi()->signal(SIGKILL));  // iox-roudi too: the HMI's frame streams lose it
  REQUIRE(s.sut.roudi()->waitForExit(5s));
  CHECK_MESSAGE(hmi.waitForLine("service vcu-fsm: Stale", 10s), "the HMI did not notice vcu-fsm's silence");
  CHECK(hmi.running());
  REQUIRE_STATUS(s.sut.startRoudi());
  s.startService("fsm-restarted", FSM_BINARY);
  CHECK_MESSAGE(hmi.waitForLine("service vcu-fsm: Ready", 10s), "the HMI did not see vcu-fsm return");
  CHECK(hmi.running());
}

TEST_CASE(
    "the HMI's operator switch starts the real FSM, shows its acceptance and the new state, and shows a refusal's "
    "reason") {
  SKIP_UNLESS_ISOLATED();
  HmiStack s;
  openvcu::hmi::test::ensureApplication("test_integration_hmi");
  openvcu::hmi::StackSettings settings;
  settings.configPath = s.config.string();
  settings.frameStreams = true;
  auto connection = openvcu::hmi::StackConnection::open(settings);
  REQUIRE_STATUS(connection);
  openvcu::hmi::FrameTraceModel frames;
  openvcu::hmi::OperatorModel operators;
  openvcu::hmi::FsmModel fsm;
  const int start = operators.rowOf("internal.operator.StartStop");
  const int drive = operators.rowOf("internal.operator.ConnectDriving");
  REQUIRE(start >= 0);
  REQUIRE(drive >= 0);
  const auto role = [&](int row, int which) { return operators.data(operators.index(row), which); };
  REQUIRE_MESSAGE(
      QTest::qWaitFor([&] { return role(start, openvcu::hmi::OperatorModel::EnabledRole).toBool(); }, 10000),
      "Start never offered");
  CHECK(fsm.stateName() == "Standby");
  CHECK_FALSE(role(drive, openvcu::hmi::OperatorModel::EnabledRole).toBool());  // Standby does not read it
  CHECK(operators.toggle(start).isEmpty());
  CHECK_MESSAGE(
      QTest::qWaitFor(
          [&] { return role(start, openvcu::hmi::OperatorModel::ResultRole).toString() == "accepted by vcu-fsm"; },
          5000),
      role(start, openvcu::hmi::OperatorModel::ResultRole).toString().toStdString());
  CHECK_MESSAGE(QTest::qWaitFor([&] { return fsm.stateName() == "Waking" || fsm.stateName() == "Ready"; }, 5000),
                fsm.stateName().toStdString());
  CHECK(QTest::qWaitFor([&] { return fsm.rowCount() > 0; }, 3000));  // the transition heard on LCM
  // raw frames over iceoryx: received (the simulated vehicle) and sent (can-tx's keep-alive group)
  const auto sawDirection = [&](const char* direction) {
    for (int row = 0; row < frames.rowCount(); ++row) {
      if (frames.data(frames.index(row), openvcu::hmi::FrameTraceModel::DirectionRole).toString() == direction)
        return true;
    }
    return false;
  };
  CHECK_MESSAGE(QTest::qWaitFor([&] { return sawDirection("Rx") && sawDirection("Tx"); }, 5000),
                frames.errorString().toStdString());
  CHECK(frames.status() == openvcu::hmi::ModelStatus::Ready);

  QSignalSpy finished((*connection).get(), &openvcu::hmi::StackConnection::commandFinished);
  openvcu::ipc::CommandRequest stateRequest;  // the FSM state is a status: refused
  stateRequest.kind = openvcu::ipc::CommandKind::SetSignal;
  stateRequest.key = "internal.fsm.state";
  stateRequest.value = 1;
  const std::int64_t id = (*connection)->sendCommand(stateRequest);
  REQUIRE(id > 0);
  REQUIRE(QTest::qWaitFor([&] { return finished.count() > 0; }, 5000));
  CHECK(finished.at(0).at(0).toLongLong() == id);
  CHECK_FALSE(finished.at(0).at(1).toBool());
  CHECK_MESSAGE(finished.at(0).at(2).toString().startsWith("refused by vcu-fsm: "),
                finished.at(0).at(2).toString().toStdString());
}

TEST_CASE(
    "the ECU setup changes a cycle, sets and clears an override, adds and disables a message on the running can-tx "
    "without a restart") {
  SKIP_UNLESS_ISOLATED();
  HmiStack s;
  openvcu::hmi::test::ensureApplication("test_integration_hmi");
  openvcu::hmi::StackSettings settings;
  settings.configPath = s.config.string();
  auto connection = openvcu::hmi::StackConnection::open(settings);
  REQUIRE_STATUS(connection);
  openvcu::hmi::ScheduleModel sut;
  int row = -1;
  for (int i = 0; i < sut.rowCount(); ++i) {
    if (sut.data(sut.index(i), openvcu::hmi::ScheduleModel::KeyRole).toString() ==
        "Vehicle_Control_Unit.HC1_Demands.ControlWord") {
      row = i;
    }
  }
  REQUIRE(row >= 0);
  REQUIRE(QTest::qWaitFor([&] { return sut.status() == openvcu::hmi::ModelStatus::Ready; }, 10000));
  const auto answered = [&] { return !sut.lastResult().contains("waiting"); };
  CHECK(sut.setCycle(row, "50").isEmpty());
  REQUIRE(QTest::qWaitFor(answered, 5000));
  CHECK_MESSAGE(sut.lastResult().contains("accepted by vcu-can-tx"), sut.lastResult().toStdString());
  CHECK(sut.data(sut.index(row), openvcu::hmi::ScheduleModel::CycleRole).toInt() == 50);
  CHECK(sut.setOverride(row, "5").isEmpty());
  REQUIRE(QTest::qWaitFor(answered, 5000));
  CHECK_MESSAGE(sut.lastResult().contains("accepted"), sut.lastResult().toStdString());
  CHECK(QTest::qWaitFor([&] { return sut.data(sut.index(row), openvcu::hmi::ScheduleModel::OverriddenRole).toBool(); },
                        3000));
  CHECK(sut.clearOverride(row).isEmpty());
  REQUIRE(QTest::qWaitFor(answered, 5000));
  CHECK(QTest::qWaitFor([&] { return !sut.data(sut.index(row), openvcu::hmi::ScheduleModel::OverriddenRole).toBool(); },
                        3000));

  // the table shows what can-tx runs (its heartbeat), and a message added here gets rows
  using Role = openvcu::hmi::ScheduleModel::Role;
  CHECK(QTest::qWaitFor([&] { return sut.data(sut.index(row), Role::LiveRole).toBool(); }, 5000));
  CHECK(sut.data(sut.index(row), Role::CycleRole).toInt() == 50);
  const int before = sut.rowCount();
  CHECK(sut.addMessage("HVESSD3_PGN61586", "40").isEmpty());
  REQUIRE(QTest::qWaitFor(answered, 5000));
  CHECK_MESSAGE(sut.lastResult().contains("accepted by vcu-can-tx"), sut.lastResult().toStdString());
  REQUIRE(QTest::qWaitFor([&] { return sut.rowOfMessage("HVESSD3_PGN61586") >= 0; }, 5000));
  const int added = sut.rowOfMessage("HVESSD3_PGN61586");
  CHECK(added >= before);
  CHECK(sut.data(sut.index(added), Role::AddedRole).toBool());
  CHECK(sut.data(sut.index(added), Role::CycleRole).toInt() == 40);
  CHECK(sut.data(sut.index(added), Role::EnabledRole).toBool());
  CHECK(sut.setEnabled(added, false).isEmpty());
  REQUIRE(QTest::qWaitFor(answered, 5000));
  CHECK(QTest::qWaitFor([&] { return !sut.data(sut.index(added), Role::EnabledRole).toBool(); }, 5000));
}

TEST_CASE(
    "the Record button in a process that blocks SIGTERM and SIGINT, as vcu-hmi does, records the running stack until "
    "Stop, ends well, and the recording reads without a skipped line or a step back in time") {
  SKIP_UNLESS_ISOLATED();
  HmiStack s;
  openvcu::hmi::test::ensureApplication("test_integration_hmi");
  const BlockedStopSignals blocked;  // what vcu-hmi's main does before Qt starts
  QTemporaryDir data;
  openvcu::hmi::StackSettings settings;
  settings.configPath = s.config.string();
  settings.dataFolder = data.path().toStdString();
  settings.vcuProgram = VCU_BINARY;
  auto connection = openvcu::hmi::StackConnection::open(settings);
  REQUIRE_STATUS(connection);
  using openvcu::hmi::RecordController;
  RecordController sut;
  CHECK(sut.start().isEmpty());
  REQUIRE_MESSAGE(QTest::qWaitFor([&] { return sut.state() != RecordController::Starting; }, 15000),
                  sut.lastResult().toStdString());
  REQUIRE_MESSAGE(sut.state() == RecordController::Recording, sut.lastResult().toStdString());
  CHECK(sut.folder().startsWith(data.path() + "/recordings/"));
  // vcu record and every thread it started take SIGTERM (none inherited the HMI's mask)
  const std::vector<pid_t> recorders = childrenNamed("vcu");
  REQUIRE(recorders.size() == 1);
  const std::vector<std::string> blocking = threadsBlockingStopSignals(recorders.front());
  CHECK_MESSAGE(blocking.empty(), blocking.size() << " thread(s) of vcu record block SIGTERM/SIGINT");
  QTest::qWait(2000);  // the simulated vehicle sends meanwhile
  CHECK_FALSE(sut.elapsedText().isEmpty());
  // it ends on the SIGTERM, long before the controller's SIGKILL deadline
  constexpr qint64 STOPPED_WITHIN_MS = 5000;
  static_assert(STOPPED_WITHIN_MS < RecordController::STOP_TIMEOUT_MS);
  QElapsedTimer stopping;
  stopping.start();
  sut.stop();
  CHECK(sut.state() == RecordController::Stopping);
  REQUIRE(
      QTest::qWaitFor([&] { return sut.state() == RecordController::Idle; }, RecordController::STOP_TIMEOUT_MS + 5000));
  CHECK_MESSAGE(stopping.elapsed() < STOPPED_WITHIN_MS, "vcu record took " << stopping.elapsed() << " ms to stop");
  CHECK_MESSAGE(sut.status() == openvcu::hmi::ModelStatus::Ready, sut.lastResult().toStdString());
  CHECK_MESSAGE(sut.lastResult().startsWith("recorded "), sut.lastResult().toStdString());  // vcu record's summary
  REQUIRE(sut.recordedLogs().size() >= 1);  // what the Analyse button offers
  CHECK(sut.recordedLogs().contains(sut.folder() + "/vehicle.log"));
  CHECK(QFileInfo(sut.folder() + "/events.lcmlog").size() > 0);

  openvcu::hmi::TraceStatsModel stats;  // the configuration of the stack: names and expected cycles
  stats.compute(sut.recordedLogs());
  stats.waitUntilComputed();
  MESSAGE("statistics: " << stats.summary().toStdString() << " / " << stats.errorString().toStdString());
  CHECK_MESSAGE(stats.status() != openvcu::hmi::ModelStatus::Error, stats.errorString().toStdString());
  CHECK_MESSAGE(!stats.errorString().contains("malformed"), stats.errorString().toStdString());
  CHECK_MESSAGE(!stats.errorString().contains("backwards"), stats.errorString().toStdString());
  REQUIRE(stats.buses().size() >= 1);
  CHECK(stats.buses()[0].toMap()["bus"].toString() == "vehicle");
  CHECK(stats.buses()[0].toMap()["loadMeanPct"].toDouble() > 0);
  CHECK(stats.rowCount() > 3);
  CHECK(stats.nodes()->rowCount() >= 2);  // the VCU (can-tx) and the simulated ECUs
  bool named = false;
  for (int row = 0; row < stats.rowCount(); ++row) {
    named = named || !stats.data(stats.index(row), openvcu::hmi::TraceStatsModel::NameRole).toString().isEmpty();
  }
  CHECK(named);
}
