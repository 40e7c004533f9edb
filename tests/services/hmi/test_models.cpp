// The Qt models on the in-process event bus (memq://): no shared memory, RouDi or network.
// The signal table is never created here (a private instance name), so every model shows
// what it shows without a running stack. Issue 10.
#include <doctest/doctest.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <QDir>
#include <QGuiApplication>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <atomic>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "app/hmi_app.hpp"
#include "can/frame_trace_model.hpp"
#include "can/signal_plot.hpp"
#include "can/signal_tree_model.hpp"
#include "common/file_browser.hpp"
#include "common/stack_connection.hpp"
#include "dashboard/dashboard_models.hpp"
#include "debug/fault_model.hpp"
#include "debug/log_model.hpp"
#include "debug/system_actions.hpp"
#include "header/fsm_model.hpp"
#include "header/health_model.hpp"
#include "hmi_test_support.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "setup/schedule_model.hpp"
#include "trace/trace_model.hpp"
#include "trace/trace_timeline.hpp"
#include "vehicle/operator_model.hpp"

using namespace openvcu;
using namespace openvcu::hmi;

namespace {

/// A stack connection on memq:// with an instance no table exists for.
std::unique_ptr<StackConnection> openStack(const std::string& dashboard = {}, const std::string& supervisor = {},
                                           const std::string& dataFolder = {}) {
  test::ensureApplication("test_hmi_models");
  StackSettings settings = test::memqSettings("hmi-unit");
  settings.dashboardPath = dashboard;
  settings.supervisorConfig = supervisor;
  settings.dataFolder = dataFolder;
  auto opened = StackConnection::open(settings);
  REQUIRE_MESSAGE(opened, opened.error().toString());
  return std::move(*opened);
}

/// A real command socket (ipc::CommandListener, in a private temporary folder) standing in
/// for the stack's services: it records every request and answers with `answer`.
class FakeCommandService {
 public:
  explicit FakeCommandService(const StackConnection& stack, std::string responder) : m_responder(std::move(responder)) {
    static QTemporaryDir root;
    ::setenv(ipc::COMMAND_ROOT_ENV, root.path().toStdString().c_str(), 1);
    ipc::CommandListener::Options options;
    options.instance = stack.config().instance;
    options.program = m_responder;
    auto listener = ipc::CommandListener::open(options);
    REQUIRE_MESSAGE(listener, listener.error().toString());
    m_listener.emplace(std::move(*listener));
    m_thread = std::thread([this] { serve(); });
  }
  FakeCommandService(const FakeCommandService&) = delete;
  FakeCommandService& operator=(const FakeCommandService&) = delete;
  ~FakeCommandService() {
    m_stop = true;
    m_thread.join();
  }
  /// Answer the next requests accepted (empty reason) or refused with `reason`.
  void answer(bool accepted, std::string reason = {}) {
    std::lock_guard lock(m_mutex);
    m_accepted = accepted;
    m_reason = std::move(reason);
  }
  std::vector<ipc::CommandRequest> requests() {
    std::lock_guard lock(m_mutex);
    return m_requests;
  }

 private:
  void serve() {
    std::vector<ipc::ReceivedCommand> batch;
    while (!m_stop) {
      pollfd pfd{m_listener->fd(), POLLIN, 0};
      if (::poll(&pfd, 1, 20) <= 0) continue;
      batch.clear();
      m_listener->poll(batch);
      for (const ipc::ReceivedCommand& received : batch) {
        std::lock_guard lock(m_mutex);
        m_requests.push_back(received.request);
        (void)m_listener->reply(received.connection,
                                ipc::CommandAck{0, received.request.requestId, received.request.issuer, m_responder,
                                                m_accepted, m_reason, true});
      }
    }
  }
  std::string m_responder;
  std::optional<ipc::CommandListener> m_listener;
  std::mutex m_mutex;
  std::vector<ipc::CommandRequest> m_requests;
  bool m_accepted{true};
  std::string m_reason;
  std::atomic<bool> m_stop{false};
  std::thread m_thread;
};

/// Handles Qt events until `done()` (at most 5 s).
template <typename Done>
bool deliverUntil(Done done) {
  for (int i = 0; i < 500 && !done(); ++i) {
    QCoreApplication::processEvents();
    ::usleep(10'000);
  }
  return done();
}

void deliver(StackConnection& stack) {
  stack.pumpEvents();
  QCoreApplication::processEvents();
}

}  // namespace

TEST_CASE("a missing or broken configuration is refused with a clear error, not a crash") {
  test::ensureApplication("test_hmi_models");
  StackSettings settings;
  settings.configPath = "/nonexistent/vehicle.json";
  const auto sut = StackConnection::open(settings);
  REQUIRE_FALSE(sut);
  CHECK(sut.error().toString().find("/nonexistent/vehicle.json") != std::string::npos);
  settings.configPath = test::HHEA_CONFIG;
  settings.instance = "bad name!";
  CHECK_FALSE(StackConnection::open(settings));
}

TEST_CASE("without a signal table the models say NotConnected and every switch is disabled") {
  auto stack = openStack();
  CHECK(stack->tableStatus() == ModelStatus::NotConnected);
  CHECK(stack->eventStatus() == ModelStatus::Ready);
  OperatorModel sut;
  CHECK(sut.rowCount() == 5);  // StartStop, ConnectDriving, ACCharging, DCCharging, Crash (not FaultReset)
  const int start = sut.rowOf("internal.operator.StartStop");
  REQUIRE(start >= 0);
  CHECK_FALSE(sut.data(sut.index(start), OperatorModel::EnabledRole).toBool());
  CHECK(sut.toggle(start) == "not allowed in the current state");
  CHECK(sut.status() == ModelStatus::NotConnected);
  SignalValue soc;
  soc.setKey("VIC.HVESSD2_PGN61585.HS_FastUpdSOC");
  CHECK(soc.status() == ModelStatus::NotConnected);
  CHECK(soc.text() == "--");
  soc.setKey("VIC.HVESSD2_PGN61585.HS_FastUpdSoc");
  CHECK(soc.status() == ModelStatus::Error);
  CHECK(soc.errorString().contains("did you mean"));
}

TEST_CASE("log records, heartbeats, FSM transitions and faults from the bus reach their models") {
  auto stack = openStack();
  LogModel logs;
  HealthModel health;
  FsmModel fsm;
  FaultModel faults;
  ipc::EventBus& bus = *stack->events();
  bus.publish(ipc::LogRecord{.service = "vcu-fsm", .level = ipc::LogLevel::Warning, .text = "state Fault"});
  bus.publish(ipc::LogRecord{.service = "vcu-can-rx", .level = ipc::LogLevel::Info, .text = "ready"});
  bus.publish(ipc::Heartbeat{
      .service = "vcu-fsm", .instance = "x", .pid = ::getpid(), .uptimeMs = 1000, .counters = {}, .status = "ready"});
  bus.publish(ipc::FsmTransition{.fromState = "Standby", .toState = "Waking", .cause = "operator Start"});
  bus.publish(
      ipc::FaultEvent{.name = "timeout.VIC", .source = "vcu-can-rx", .active = true, .text = "no frame for 1 s"});
  deliver(*stack);
  CHECK(logs.rowCount() == 2);
  logs.setServiceFilter("vcu-fsm");
  CHECK(logs.rowCount() == 1);
  logs.setServiceFilter("");
  logs.setMinimumLevel(static_cast<int>(ipc::LogLevel::Warning));
  REQUIRE(logs.rowCount() == 1);
  CHECK(logs.data(logs.index(0), LogModel::TextRole).toString() == "state Fault");
  CHECK(health.connectionOf("vcu-fsm") == static_cast<int>(ValueStatus::Ready));
  CHECK(health.connectionOf("vcu-can-tx") == static_cast<int>(ValueStatus::NotConnected));
  REQUIRE(fsm.rowCount() == 1);
  CHECK(fsm.data(fsm.index(0), FsmModel::ToRole).toString() == "Waking");
  CHECK(faults.activeCount() == 1);
  bus.publish(ipc::FaultEvent{.name = "timeout.VIC", .source = "vcu-can-rx", .active = false, .text = {}});
  deliver(*stack);
  CHECK(faults.activeCount() == 0);
  QTemporaryDir folder;
  const QString exported = folder.filePath("log.txt");
  CHECK(logs.exportTo(exported).isEmpty());
  CHECK(logs.exportTo("/nonexistent/dir/log.txt").contains("/nonexistent/dir/log.txt"));
}

TEST_CASE("a schedule change is checked here, sent as ScheduleCycle and shown once acknowledged") {
  auto stack = openStack();
  ScheduleModel sut;
  REQUIRE(sut.rowCount() > 0);
  const QString message = sut.data(sut.index(0), ScheduleModel::MessageRole).toString();
  CHECK(sut.setCycle(0, "abc") == "cycle must be a whole number of ms in 1..3600000");
  CHECK(sut.setCycle(0, "0") == "cycle must be a whole number of ms in 1..3600000");
  CHECK(sut.setOverride(0, "1e9").contains("outside the range"));
  CHECK(sut.setDefault(0, "1e9").contains("outside the range"));
  CHECK(sut.setDefault(0, "abc").contains("is not a number"));
  CHECK(sut.setDefault(-1, "1") == "no such row");
  FakeCommandService canTx(*stack, "vcu-can-tx");
  CHECK(sut.setCycle(0, "50").isEmpty());
  REQUIRE(deliverUntil([&] { return sut.data(sut.index(0), ScheduleModel::CycleRole).toInt() == 50; }));
  const auto seen = canTx.requests();
  REQUIRE(seen.size() == 1);
  CHECK(seen[0].kind == ipc::CommandKind::ScheduleCycle);
  CHECK(seen[0].key == message.toStdString());
  CHECK(seen[0].value == 50);
  CHECK(seen[0].issuer == "vcu-hmi");
  CHECK(seen[0].deadlineNs > 0);
  CHECK(sut.lastResult().contains("accepted by vcu-can-tx"));
}

TEST_CASE("the schedule table follows can-tx's live schedule and a message is added with ScheduleAdd") {
  auto stack = openStack();
  ScheduleModel sut;
  const int ccvs = sut.rowOfMessage("CCVS1_PGN65265");
  REQUIRE(ccvs >= 0);
  CHECK(sut.rowOfMessage("SHM_VCU_to_VIC") < 0);                              // goes out with its SDM, not on its own
  CHECK(sut.data(sut.index(ccvs), ScheduleModel::CycleRole).toInt() == 100);  // the DBC's
  CHECK_FALSE(sut.data(sut.index(ccvs), ScheduleModel::LiveRole).toBool());
  const QStringList candidates = sut.candidates("hvessd");
  CHECK(candidates.contains("HVESSD2_PGN61585"));
  CHECK_FALSE(sut.candidates("").contains("CCVS1_PGN65265"));  // has rows already
  CHECK_FALSE(sut.candidates("").contains("SHM_VCU_to_VIC"));
  CHECK(sut.addMessage("HVESSD2_PGN61586", "100").contains("unknown message"));
  CHECK(sut.addMessage("CCVS1_PGN65265", "100").contains("already in the schedule"));
  CHECK(sut.addMessage("HVESSD2_PGN61585", "0").contains("1..3600000"));
  FakeCommandService canTx(*stack, "vcu-can-tx");
  CHECK(sut.addMessage("HVESSD2_PGN61585", "40").isEmpty());
  REQUIRE(deliverUntil([&] { return canTx.requests().size() == 1; }));
  CHECK(canTx.requests()[0].kind == ipc::CommandKind::ScheduleAdd);
  CHECK(canTx.requests()[0].key == "HVESSD2_PGN61585");
  CHECK(canTx.requests()[0].value == 40);
  CHECK(sut.setEnabled(ccvs, false).isEmpty());
  REQUIRE(deliverUntil([&] { return canTx.requests().size() == 2; }));
  CHECK(canTx.requests()[1].kind == ipc::CommandKind::ScheduleEnable);
  CHECK(canTx.requests()[1].value == 0);

  // can-tx's live schedule: CCVS1 at 50 ms and disabled, HVESSD2 added at 40 ms
  const int before = sut.rowCount();
  stack->events()->publish(
      ipc::TxSchedule{.service = "vcu-can-tx",
                      .instance = "x",
                      .pid = 1,
                      .entries = {{"CCVS1_PGN65265", 50'000, false, false}, {"HVESSD2_PGN61585", 40'000, true, true}}});
  deliver(*stack);
  CHECK(sut.data(sut.index(ccvs), ScheduleModel::CycleRole).toInt() == 50);
  CHECK(sut.data(sut.index(ccvs), ScheduleModel::LiveRole).toBool());
  CHECK_FALSE(sut.data(sut.index(ccvs), ScheduleModel::EnabledRole).toBool());
  const int added = sut.rowOfMessage("HVESSD2_PGN61585");
  REQUIRE(added >= before);
  CHECK(sut.rowCount() == before + 3);  // its three signals
  CHECK(sut.data(sut.index(added), ScheduleModel::AddedRole).toBool());
  CHECK(sut.data(sut.index(added), ScheduleModel::CycleRole).toInt() == 40);
  CHECK(sut.data(sut.index(added), ScheduleModel::SignalRole).toString() == "HS_FastUpdSOC");
  CHECK_FALSE(sut.candidates("hvessd").contains("HVESSD2_PGN61585"));
  // heartbeat counters of the old names change nothing: the schedule has its own channel
  stack->events()->publish(ipc::Heartbeat{.service = "vcu-can-tx",
                                          .instance = "x",
                                          .pid = 1,
                                          .counters = {{"tx.CCVS1_PGN65265.cycle_us", 7'000}},
                                          .status = "ok"});
  deliver(*stack);
  CHECK(sut.data(sut.index(ccvs), ScheduleModel::CycleRole).toInt() == 50);
}

/// A stack, a spy on its commandFinished and a vcu-fsm that refuses every command with "no".
struct RefusingFsm {
  std::unique_ptr<StackConnection> stack = openStack();
  QSignalSpy finished{stack.get(), &StackConnection::commandFinished};
  FakeCommandService fsm{*stack, "vcu-fsm"};
  RefusingFsm() { fsm.answer(false, "no"); }
  /// Sends `kind` for internal.operator.StartStop = 1; the request id.
  std::int64_t sendStartStop(ipc::CommandKind kind) {
    ipc::CommandRequest request;
    request.kind = kind;
    request.key = "internal.operator.StartStop";
    request.value = 1;
    return stack->sendCommand(request);
  }
};

TEST_CASE("a refused command shows the responder's reason") {
  RefusingFsm refusing;
  const std::int64_t id = refusing.sendStartStop(ipc::CommandKind::SetSignal);
  const QSignalSpy& finished = refusing.finished;
  FakeCommandService& fsm = refusing.fsm;
  REQUIRE(deliverUntil([&] { return finished.count() == 1; }));
  REQUIRE(fsm.requests().size() == 1);
  CHECK(fsm.requests()[0].requestId == id);
  CHECK(finished.at(0).at(0).toLongLong() == id);
  CHECK(finished.at(0).at(1).toBool() == false);
  CHECK(finished.at(0).at(2).toString() == "refused by vcu-fsm: no");
}

TEST_CASE("a forged acceptance on the event bus does not finish an HMI command: only the command socket answers") {
  RefusingFsm refusing;
  const std::int64_t id = refusing.sendStartStop(ipc::CommandKind::OperatorSwitch);
  StackConnection* stack = refusing.stack.get();
  const QSignalSpy& finished = refusing.finished;
  stack->events()->publish(
      ipc::CommandAck{.requestId = id, .issuer = "vcu-hmi", .responder = "vcu-fsm", .accepted = true, .reason = {}});
  deliver(*stack);  // the forged ack is handled here, before the socket's answer

  REQUIRE(deliverUntil([&] { return finished.count() == 1; }));
  CHECK(finished.at(0).at(1).toBool() == false);
  CHECK(finished.at(0).at(2).toString() == "refused by vcu-fsm: no");
}

TEST_CASE("the DBC tree lists bus and nodes and messages with ID and PGN and signals and search keeps parents") {
  auto stack = openStack();
  SignalTreeModel sut;
  CHECK(sut.nodeCount() > 100);
  const int collapsedRows = sut.rowCount();
  sut.setSearch("HS_FastUpdSOC");
  REQUIRE(sut.rowCount() == 4);  // bus, VIC, HVESSD2_PGN61585, the signal
  CHECK(sut.data(sut.index(0), SignalTreeModel::DepthRole).toInt() == 0);
  CHECK(sut.data(sut.index(2), SignalTreeModel::DetailRole).toString().contains("PGN 61585"));
  CHECK(sut.data(sut.index(3), SignalTreeModel::KeyRole).toString() == "VIC.HVESSD2_PGN61585.HS_FastUpdSOC");
  sut.setSearch("");
  CHECK(sut.rowCount() == collapsedRows);
}

TEST_CASE("the plot takes up to four known signals and says why it refuses more") {
  auto stack = openStack();
  SignalPlot sut;
  CHECK(sut.toggleKey("VIC.HVESSD1_PGN61584.HS_ULvl").isEmpty());
  CHECK(sut.toggleKey("VIC.HVESSD1_PGN61584.HS_I").isEmpty());
  CHECK(sut.toggleKey("VIC.HVESSD2_PGN61585.HS_FastUpdSOC").isEmpty());
  CHECK(sut.toggleKey("internal.relay.Cl15").isEmpty());
  CHECK(sut.toggleKey("internal.fault.Contactor").contains("at most 4"));
  CHECK(sut.keys().size() == 4);
  CHECK(sut.toggleKey("internal.relay.Cl15").isEmpty());  // removes it
  CHECK(sut.keys().size() == 3);
  sut.setKeys({"no.such.key"});
  CHECK(sut.keys().isEmpty());
  CHECK(sut.errorString().contains("unknown signal"));
  sut.setWindowSeconds(5);
  CHECK(sut.windowSeconds() == 10);
}

TEST_CASE("the trace viewer loads a candump log, decodes it with the DBC and exports CSV as vcu dbc decode does") {
  auto stack = openStack();
  QTemporaryDir folder;
  const std::string log = folder.filePath("drive.log").toStdString();
  {
    std::ofstream out(log);
    out << "(1436509052.249713) can0 18FF50E5#0102030405060708\n"  // OBC status 0x18FF50E5
        << "(1436509052.259713) can0 18FEF1F3#FFFFFFFFFFFFFFFF\n"
        << "this line is broken\n";
  }
  TraceModel sut;
  REQUIRE(sut.open(QString::fromStdString(log)));
  sut.waitUntilLoaded();
  CHECK(sut.rowCount() == 2);
  CHECK(sut.status() == ModelStatus::Stale);  // one malformed line
  CHECK(sut.errorString().contains("1 malformed"));
  CHECK(sut.data(sut.index(0), TraceModel::IdRole).toString() == "18FF50E5");
  CHECK(sut.data(sut.index(0), TraceModel::MessageRole).toString() == "OBC");
  CHECK_FALSE(sut.data(sut.index(0), TraceModel::DecodedRole).toString().isEmpty());
  const QString csv = folder.filePath("drive.csv");
  CHECK(sut.exportCsv(csv).isEmpty());
  std::ifstream in(csv.toStdString());
  std::string header;
  std::getline(in, header);
  CHECK(header == "t,bus,id,ext,msg,signal,raw,physical");  // trace::FrameWriter's CSV
  std::string first;
  std::getline(in, first);
  CHECK(first.rfind("1436509052.249713,can0,419385573,true,OBC,", 0) == 0);

  const QStringList names = sut.signalNames();
  REQUIRE(names.contains("OBC.OBC_Start_State"));
  TraceTimeline timeline;
  timeline.setTrace(&sut);
  CHECK(timeline.toggleKey("OBC.OBC_Start_State").isEmpty());
  REQUIRE(timeline.legend().size() == 1);
  CHECK(timeline.viewEnd() == doctest::Approx(0.01));          // the two frames are 10 ms apart
  CHECK(timeline.toggleKey("OBC.OBC_Start_State").isEmpty());  // removed again
  CHECK(timeline.legend().isEmpty());
  CHECK(timeline.toggleKey("OBC.OBC_Start_State").isEmpty());
  timeline.zoom(0.5, 0.5);
  CHECK(timeline.viewEnd() - timeline.viewStart() == doctest::Approx(0.005));
  timeline.reset();
  CHECK(timeline.viewStart() == 0);
  trace::SampleRing ring;
  CHECK_FALSE(sut.extract("NoSuch.Signal", ring));

  TraceModel missing;
  REQUIRE(missing.open("/nonexistent/drive.log"));
  missing.waitUntilLoaded();
  CHECK(missing.status() == ModelStatus::Error);
  CHECK(missing.errorString().contains("/nonexistent/drive.log"));
}

TEST_CASE("a refused dashboard file puts the dashboard model in Error with the reason") {
  QTemporaryDir folder;
  const std::string path = folder.filePath("dash.json").toStdString();
  {
    std::ofstream out(path);
    out << R"({"items": [{"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSoc"}]})";
  }
  auto stack = openStack(path);
  DashboardSettings sut;
  CHECK(sut.status() == ModelStatus::Error);
  CHECK(sut.errorString().contains("/items/0/key"));
  SignalListModel grid;
  grid.setDashboard(true);
  CHECK(grid.status() == ModelStatus::Error);
}

TEST_CASE("the shipped dashboard file is valid for the HHEA configuration") {
  auto stack = openStack(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/dashboard.json");
  DashboardSettings sut;
  CHECK_MESSAGE(sut.status() == ModelStatus::Ready, sut.errorString().toStdString());
  CHECK(sut.config().items.size() >= 8);
}

TEST_CASE(
    "the raw frame trace shows the newest frames first and filters by ID, PGN and node, and pause holds the view") {
  auto stack = openStack();
  FrameTraceModel sut;
  CHECK(sut.status() == ModelStatus::NotConnected);  // frame streams are off in tests: no RouDi
  FrameTraceModel::Entry entries[3]{};
  entries[0].frame.id = 0x18FF50E5;  // OBC, PGN 65360
  entries[0].frame.flags = can::FLAG_EXTENDED;
  entries[0].frame.length = 8;
  entries[1].frame.id = 0x18FEF1F3;  // PGN 65265
  entries[1].frame.flags = can::FLAG_EXTENDED;
  entries[1].frame.length = 8;
  entries[1].sent = true;
  entries[2].frame.id = 0x123;
  entries[2].frame.length = 2;
  sut.push(entries, 3);
  sut.collect();
  REQUIRE(sut.rowCount() == 3);
  CHECK(sut.data(sut.index(0), FrameTraceModel::IdRole).toString() == "123");  // newest first
  CHECK(sut.data(sut.index(1), FrameTraceModel::DirectionRole).toString() == "Tx");
  CHECK(sut.data(sut.index(2), FrameTraceModel::NodeRole).toString() == "OBC");
  CHECK_FALSE(sut.data(sut.index(2), FrameTraceModel::DecodedRole).toString().isEmpty());
  sut.setIdFilter("0x18ff50");
  CHECK(sut.rowCount() == 1);
  sut.setIdFilter("");
  sut.setPgnFilter("65265");
  CHECK(sut.rowCount() == 1);
  sut.setPgnFilter("");
  sut.setNodeFilter("obc");
  CHECK(sut.rowCount() == 1);
  sut.setNodeFilter("");
  sut.setPaused(true);
  sut.push(entries, 3);
  sut.collect();
  CHECK(sut.rowCount() == 3);
  sut.setPaused(false);
  sut.push(entries, 1);
  sut.collect();
  CHECK(sut.rowCount() == 4);  // what arrived while paused is not shown later
}

TEST_CASE("the raw frame trace keeps at most SHOWN frames however many arrive") {
  auto stack = openStack();
  FrameTraceModel sut;
  std::vector<FrameTraceModel::Entry> many(FrameTraceModel::RING + 100);
  for (std::size_t i = 0; i < many.size(); ++i) many[i].frame.id = static_cast<std::uint32_t>(i & 0x7FF);
  sut.push(many.data(), many.size());
  sut.collect();
  CHECK(sut.rowCount() == static_cast<int>(FrameTraceModel::SHOWN));
}

TEST_CASE("restart and power actions are fixed argv: known services only, reboot or poweroff only") {
  {
    auto stack = openStack();
    SystemActions sut;
    CHECK(sut.restartArgv("vcu-fsm").isEmpty());  // no --supervisor-config: not offered
    CHECK(sut.restartService("vcu-fsm").contains("--supervisor-config"));
  }
  auto stack = openStack({}, "/etc/openvcu/openvcu.conf");
  SystemActions sut;
  CHECK(sut.restartArgv("vcu-fsm") ==
        QStringList{"supervisorctl", "-c", "/etc/openvcu/openvcu.conf", "restart", "fsm"});
  CHECK(sut.restartArgv("can-rx") ==
        QStringList{"supervisorctl", "-c", "/etc/openvcu/openvcu.conf", "restart", "can-rx"});
  CHECK(sut.restartArgv("fsm; rm -rf /").isEmpty());
  CHECK(sut.restartArgv("vcu-unknown").isEmpty());
  CHECK(sut.power("reboot; rm -rf /").startsWith("refused"));
  CHECK(sut.power("halt").startsWith("refused"));
}

TEST_CASE("a system action's child starts with SIGTERM and SIGINT unblocked although vcu-hmi blocks them") {
  // as vcu-hmi's main does before its signalfd; restored at the end
  sigset_t blocked;
  sigset_t before;
  sigemptyset(&blocked);
  sigaddset(&blocked, SIGTERM);
  sigaddset(&blocked, SIGINT);
  REQUIRE(::pthread_sigmask(SIG_BLOCK, &blocked, &before) == 0);
  test::ensureApplication("test_hmi_models");
  SystemActions sut;
  sut.run({"/usr/bin/grep", "SigBlk", "/proc/self/status"});
  const bool ended = deliverUntil([&] { return !sut.lastResult().endsWith(": running"); });
  ::pthread_sigmask(SIG_SETMASK, &before, nullptr);
  REQUIRE_MESSAGE(ended, sut.lastResult().toStdString());
  // the child's own blocked set, as the kernel reports it: none
  CHECK_MESSAGE(sut.lastResult().contains("SigBlk:\t0000000000000000"), sut.lastResult().toStdString());
}

TEST_CASE("the command line refuses bad options with a message and checks the configuration before any display") {
  const QString hhea = QString::fromStdString(test::HHEA_CONFIG);
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--size", "10x10"}));
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--tab", "9"}));
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--time-zone", "Mars/Olympus"}));
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--no-such-option"}));
  const auto sut = parseCommandLine({"vcu-hmi", "--config", hhea, "--size", "800x480", "--tab", "2"});
  REQUIRE_MESSAGE(sut, sut.error().toString());
  CHECK(sut->width == 800);
  CHECK(sut->height == 480);
  CHECK(sut->tab == 2);
  CHECK(sut->stack.frameStreams);
  CHECK(sut->plotWindowSeconds == 30);
  CHECK_FALSE(sut->framesPage);
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--plot-window", "45"}));
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--plot-window", "600s"}));
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--can-page", "trace"}));
  const auto bench = parseCommandLine(
      {"vcu-hmi", "--config", hhea, "--plot-window", "600", "--can-page", "frames", "--data-folder", "/srv/x"});
  REQUIRE_MESSAGE(bench, bench.error().toString());
  CHECK(bench->plotWindowSeconds == 600);
  CHECK(bench->framesPage);
  CHECK(bench->stack.dataFolder == "/srv/x");
  // issue 21: the vcu of the Record button, a log or folder opened in the Trace tab at start
  const QString logs = QString(OPENVCU_SOURCE_DIR) + "/tests/data/logs";
  const auto trace = parseCommandLine(
      {"vcu-hmi", "--config", hhea, "--vcu", "/opt/openvcu/bin/vcu", "--trace", logs, "--trace-page", "statistics"});
  REQUIRE_MESSAGE(trace, trace.error().toString());
  CHECK(trace->stack.vcuProgram == "/opt/openvcu/bin/vcu");
  CHECK(trace->tracePath == logs);
  CHECK(trace->tracePageStatistics);
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--trace-page", "graphs"}));
  CHECK_FALSE(parseCommandLine({"vcu-hmi", "--config", hhea, "--trace", "/nonexistent/drive.log"}));
  HmiOptions missing;
  missing.stack.configPath = "/nonexistent/vehicle.json";
  const auto checked = checkBeforeStart(missing);
  REQUIRE_FALSE(checked);
  CHECK(checked.error().toString().find("/nonexistent/vehicle.json") != std::string::npos);
}

TEST_CASE("the file browser lists folders first, enters them, returns a tapped file and names exports") {
  QTemporaryDir folder;
  REQUIRE(folder.isValid());
  const QString root = folder.path();
  REQUIRE(QDir(root).mkpath("logs/day1"));
  std::ofstream((root + "/logs/b.log").toStdString()) << "x\n";
  std::ofstream((root + "/logs/A.asc").toStdString()) << "y\n";
  auto stack = openStack({}, {}, (root + "/logs").toStdString());
  FileBrowserModel sut;
  CHECK(sut.dataFolder() == root + "/logs");
  CHECK(sut.folder() == root + "/logs");  // starts in the data folder
  REQUIRE(sut.rowCount() == 4);
  const auto name = [&](int row) { return sut.data(sut.index(row), FileBrowserModel::NameRole).toString(); };
  CHECK(name(0) == "..");
  CHECK(name(1) == "day1");
  CHECK(sut.data(sut.index(1), FileBrowserModel::IsFolderRole).toBool());
  CHECK(name(2) == "A.asc");  // case-insensitive order
  CHECK(name(3) == "b.log");
  CHECK(sut.data(sut.index(3), FileBrowserModel::SizeRole).toString() == "2 B");
  CHECK(sut.enter(3) == root + "/logs/b.log");
  CHECK(sut.folder() == root + "/logs");  // a file does not change the folder
  CHECK(sut.enter(1).isEmpty());
  CHECK(sut.folder() == root + "/logs/day1");
  CHECK(sut.rowCount() == 1);  // only ".."
  sut.up();
  CHECK(sut.folder() == root + "/logs");
  sut.setFolder(root + "/missing");
  CHECK(sut.errorString().contains("/missing: cannot be read"));
  CHECK(sut.folder() == root + "/logs");  // the listing stays
  CHECK(sut.rowCount() == 4);
  const QString exportPath = sut.newFilePath("vcu-hmi-log", "txt");
  CHECK(exportPath.startsWith(root + "/logs/vcu-hmi-log-"));
  CHECK(exportPath.endsWith(".txt"));
}
