// openvcu::service against the real things, inside the sandbox (private /dev/shm, /tmp,
// network): the command handler on a real signal table, the heartbeat slot, Service::open
// with readiness and SIGTERM, and the loop's iceoryx back end with a real iox-roudi.

#include <doctest/doctest.h>

#include "skip.hpp"
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <thread>
#include <vector>
#include <cstring>
#include <optional>

#include "harness.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/service/command_handler.hpp"
#include "openvcu/service/service.hpp"
#include "service_test_support.hpp"

namespace harness = openvcu::harness;
namespace ipc = openvcu::ipc;
namespace service = openvcu::service;
namespace signals = openvcu::signals;
using namespace std::chrono_literals;

namespace {

const std::string CONFIG = INTEGRATION_CONFIG;
constexpr signals::WriterId WRITER = 0xF0;

#define SKIP_UNLESS_ISOLATED() \
  do {                          \
    if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED); \
  } while (false)

signals::SignalTable openTable(const signals::Catalog& catalog, const std::string& instance) {
  auto tableResult = signals::SignalTable::open(catalog, instance);
  REQUIRE_STATUS(tableResult);
  return std::move(*tableResult);
}

ipc::EventBus openMemq(const std::string& instance) {
  auto eventsResult = ipc::EventBus::open("memq://", instance);
  REQUIRE_STATUS(eventsResult);
  return std::move(*eventsResult);
}

/// The handler on its real command socket (in the sandbox's /tmp), a table and an
/// in-process bus; a raw client connection sends requests; decided answers land in `acks`,
/// "not mine" answers in `notOwner`.
struct HandlerBench {
  HandlerBench()
      : catalog(service::testing::makeCatalog()),
        table(openTable(catalog, "svc-handler")),
        events(openMemq("svc-handler")),
        sut(catalog, table, events, "vcu-demo", WRITER, service::CommandPolicy::byPrefix("internal.")) {
    ::setenv(ipc::COMMAND_ROOT_ENV, "/tmp/openvcu-run", 1);
    REQUIRE_STATUS(sut.listen("svc-handler", "openvcu"));
    client = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, sut.listener()->path().c_str(), sizeof(address.sun_path) - 1);
    REQUIRE(::connect(client, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0);
  }
  HandlerBench(const HandlerBench&) = delete;
  HandlerBench& operator=(const HandlerBench&) = delete;
  ~HandlerBench() { ::close(client); }

  /// Sends one request (deadline `deadlineInNs` from now; 0: none) and serves the socket
  /// until its answer is back.
  void send(ipc::CommandKind kind, const std::string& key, double value, std::int64_t requestId = 1,
            std::int64_t deadlineInNs = 2'000'000'000) {
    const std::int64_t deadline = deadlineInNs == 0 ? 0 : openvcu::clock::monotonicNs() + deadlineInNs;
    sendRaw(ipc::encodeCommandRequest(ipc::CommandRequest{0, requestId, "test", kind, key, value, "", deadline}));
  }
  void sendRaw(const std::vector<std::uint8_t>& bytes) {
    REQUIRE(::send(client, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size()));
    for (int round = 0; round < 200; ++round) {
      pollfd pfds[2] = {{sut.fd(), POLLIN, 0}, {client, POLLIN, 0}};
      REQUIRE(::poll(pfds, 2, 20) >= 0);
      if ((pfds[0].revents & POLLIN) != 0) sut.onReadable();
      if ((pfds[1].revents & POLLIN) != 0) {
        std::vector<std::uint8_t> buffer(ipc::MAX_COMMAND_BYTES);
        const ssize_t size = ::recv(client, buffer.data(), buffer.size(), 0);
        REQUIRE(size > 0);
        const auto ack = ipc::decodeCommandAck(buffer.data(), static_cast<std::size_t>(size));
        REQUIRE(ack);
        (ack->owner ? acks : notOwner).push_back(*ack);
        return;
      }
    }
    FAIL("no answer on the command socket");
  }
  signals::SignalIndex index(const std::string& key) { return *catalog.indexOf(key); }

  signals::Catalog catalog;
  signals::SignalTable table;
  ipc::EventBus events;
  service::CommandHandler sut;
  int client{-1};
  std::vector<ipc::CommandAck> acks;
  std::vector<ipc::CommandAck> notOwner;
};

/// A datagram socket in the sandbox's /tmp standing in for systemd; NOTIFY_SOCKET points to it.
class NotifyReceiver {
 public:
  NotifyReceiver() {
    m_fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, PATH, sizeof(address.sun_path) - 1);
    ::unlink(PATH);
    REQUIRE(::bind(m_fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0);
    ::setenv("NOTIFY_SOCKET", PATH, 1);
  }
  NotifyReceiver(const NotifyReceiver&) = delete;
  NotifyReceiver& operator=(const NotifyReceiver&) = delete;
  ~NotifyReceiver() {
    ::unsetenv("NOTIFY_SOCKET");
    ::close(m_fd);
    ::unlink(PATH);
  }
  std::string receive() {
    pollfd pfd{m_fd, POLLIN, 0};
    if (::poll(&pfd, 1, 5000) <= 0) return {};
    char buffer[1024];
    const ssize_t got = ::recv(m_fd, buffer, sizeof(buffer), 0);
    return got > 0 ? std::string(buffer, static_cast<std::size_t>(got)) : std::string();
  }

 private:
  static constexpr const char* PATH = "/tmp/test-service-runtime.notify";
  int m_fd{-1};
};

service::ServiceInfo demoInfo() {
  service::ServiceInfo info;
  info.name = "fixture";  // the integration configuration declares its heartbeat slot
  info.program = "vcu-demo";
  info.writerId = WRITER;
  return info;
}

}  // namespace

TEST_CASE("an accepted command is written to the command plane and acknowledged with its request id") {
  SKIP_UNLESS_ISOLATED();
  HandlerBench bench;
  constexpr std::int64_t REQUEST_ID = 77;

  bench.send(ipc::CommandKind::SetSignal, "internal.test.level", 42.5, REQUEST_ID);

  const auto command = bench.table.readCommand(bench.index("internal.test.level"));
  REQUIRE(command);
  CHECK(command->value == 42.5);
  CHECK(command->writer == WRITER);
  CHECK(command->updates == 1);
  REQUIRE(bench.acks.size() == 1);
  CHECK(bench.acks[0] == ipc::CommandAck{bench.acks[0].timestampNs, REQUEST_ID, "test", "vcu-demo", true, ""});
  CHECK(bench.sut.accepted() == 1);
}

TEST_CASE("an operator switch writes the command plane like a set") {
  SKIP_UNLESS_ISOLATED();
  HandlerBench bench;

  bench.send(ipc::CommandKind::OperatorSwitch, "internal.operator.Start", 1);

  const auto command = bench.table.readCommand(bench.index("internal.operator.Start"));
  REQUIRE(command);
  CHECK(command->value == 1);
}

TEST_CASE("SetOverride and ClearOverride drive the override plane, leaving the command alone") {
  SKIP_UNLESS_ISOLATED();
  HandlerBench bench;
  const auto level = bench.index("internal.test.level");

  bench.send(ipc::CommandKind::SetOverride, "internal.test.level", 60, 1);
  const auto whileSet = bench.table.readOverride(level);
  bench.send(ipc::CommandKind::ClearOverride, "internal.test.level", 0, 2);
  const auto afterClear = bench.table.readOverride(level);

  REQUIRE(whileSet);
  CHECK(whileSet->active);
  CHECK(whileSet->value == 60);
  REQUIRE(afterClear);
  CHECK_FALSE(afterClear->active);
  CHECK(afterClear->writer == WRITER);
  CHECK(bench.table.readCommand(level)->updates == 0);
  CHECK(bench.acks.size() == 2);
}

TEST_CASE("a refused command changes nothing and is acknowledged with the reason") {
  SKIP_UNLESS_ISOLATED();
  HandlerBench bench;

  bench.send(ipc::CommandKind::SetSignal, "internal.test.level", 101);

  CHECK(bench.table.readCommand(bench.index("internal.test.level"))->updates == 0);
  REQUIRE(bench.acks.size() == 1);
  CHECK_FALSE(bench.acks[0].accepted);
  CHECK(bench.acks[0].reason == "value 101 is outside the range [0, 100] % of 'internal.test.level'");
  CHECK(bench.sut.refused() == 1);
}

TEST_CASE("a command for a key the service does not own is answered 'not mine' and changes nothing") {
  SKIP_UNLESS_ISOLATED();
  HandlerBench bench;

  bench.send(ipc::CommandKind::SetSignal, "VCU.Command.Enable", 1, 5);

  CHECK(bench.acks.empty());
  REQUIRE(bench.notOwner.size() == 1);
  CHECK(bench.notOwner[0].requestId == 5);
  CHECK(bench.sut.ignored() == 1);
  CHECK(bench.table.readCommand(bench.index("VCU.Command.Enable"))->updates == 0);
}

TEST_CASE("a request past its deadline, without one or too far ahead is refused and never applied") {
  SKIP_UNLESS_ISOLATED();
  HandlerBench bench;
  const auto level = bench.index("internal.test.level");

  bench.send(ipc::CommandKind::SetSignal, "internal.test.level", 10, 1, -5'000'000);  // expired 5 ms ago
  bench.send(ipc::CommandKind::SetSignal, "internal.test.level", 11, 2, 0);           // no deadline
  bench.send(ipc::CommandKind::SetSignal, "internal.test.level", 12, 3, 120'000'000'000);  // 2 min ahead

  CHECK(bench.table.readCommand(level)->updates == 0);
  REQUIRE(bench.acks.size() == 3);
  for (const auto& ack : bench.acks) CHECK_FALSE(ack.accepted);
  CHECK(bench.acks[0].reason.starts_with("expired: taken "));
  CHECK(bench.acks[1].reason == "the request carries no deadline; nothing applied");
  CHECK(bench.acks[2].reason == "the request's deadline is more than 30 s ahead; nothing applied");
  CHECK(bench.sut.expired() == 1);
}

TEST_CASE("a malformed message on the command socket is refused and the connection keeps working") {
  SKIP_UNLESS_ISOLATED();
  HandlerBench bench;

  bench.sendRaw({0x01, 0x02, 0x03});
  bench.send(ipc::CommandKind::SetSignal, "internal.test.level", 7, 9);

  REQUIRE(bench.notOwner.empty());
  REQUIRE(bench.acks.size() == 2);
  CHECK(bench.acks[0].reason == "malformed request: not one command_request_t");
  CHECK(bench.acks[1].accepted);
  CHECK(bench.table.readCommand(bench.index("internal.test.level"))->value == 7);
}

TEST_CASE("the heartbeat counts on the bus plane of its slot and continues after a restart") {
  SKIP_UNLESS_ISOLATED();
  const auto catalog = service::testing::makeCatalog();
  auto table = openTable(catalog, "svc-heartbeat");
  const auto slot = catalog.indexOf(service::heartbeatKey("fixture"));
  REQUIRE(slot);

  {
    service::HeartbeatPublisher firstRun("vcu-demo", "svc-heartbeat", nullptr, &table, slot, WRITER);
    firstRun.beat();
    firstRun.beat();
  }
  const auto beforeRestart = table.readBus(*slot);
  service::HeartbeatPublisher secondRun("vcu-demo", "svc-heartbeat", nullptr, &table, slot, WRITER);
  secondRun.beat();
  const auto afterRestart = table.readBus(*slot);

  REQUIRE(beforeRestart);
  CHECK(beforeRestart->value == 2);
  CHECK(beforeRestart->quality == signals::Quality::Valid);
  CHECK(beforeRestart->source == WRITER);
  REQUIRE(afterRestart);
  CHECK(afterRestart->value == 3);
  CHECK(table.readCommand(*slot)->updates == 0);  // the command plane stays the operators'
}

TEST_CASE("Service::open attaches everything, run sends READY=1, and SIGTERM ends it with STOPPING=1 and 0") {
  SKIP_UNLESS_ISOLATED();
  NotifyReceiver supervisor;
  service::ServiceOptions options;
  options.configPath = CONFIG;
  options.logLevel = ipc::LogLevel::Warning;
  auto serviceResult = service::Service::open(demoInfo(), options);
  REQUIRE_STATUS(serviceResult);
  service::Service& sut = **serviceResult;
  REQUIRE_STATUS(sut.answerCommands(service::CommandPolicy::byPrefix("internal.")));
  // The first tick inside run(): readiness has been announced by then; a supervisor stops us.
  bool stopRequested = false;
  auto kickTimer = service::PeriodicTimer::create(1ms);
  REQUIRE_STATUS(kickTimer);
  REQUIRE_STATUS(sut.loop().addTimer(*kickTimer, [&](const service::TimerTick&) {
    if (!stopRequested) ::raise(SIGTERM);  // blocked: it waits in the signalfd like a supervisor's kill
    stopRequested = true;
  }));

  const int exitCode = sut.run();

  CHECK(exitCode == 0);
  CHECK(sut.instance() == "itest");
  CHECK(sut.program() == "vcu-demo");
  const std::string ready = supervisor.receive();
  CHECK(ready.starts_with("READY=1\nSTATUS=ready\nMAINPID="));
  CHECK(supervisor.receive() == "STOPPING=1\nSTATUS=stopping (SIGTERM)");
  const auto slot = sut.catalog().indexOf("internal.service.fixture.heartbeat");
  REQUIRE(slot);
  const auto beats = sut.table().readBus(*slot);
  REQUIRE(beats);
  CHECK(beats->value >= 2);  // ready and stopping both beat
  CHECK(sut.heartbeat().status() == "stopping (SIGTERM)");
}

TEST_CASE("--instance overrides the configuration's instance for the table and the events") {
  SKIP_UNLESS_ISOLATED();
  service::ServiceOptions options;
  options.configPath = CONFIG;
  options.instance = "other";
  options.logLevel = ipc::LogLevel::Error;

  auto serviceResult = service::Service::open(demoInfo(), options);

  REQUIRE_STATUS(serviceResult);
  CHECK((*serviceResult)->instance() == "other");
  CHECK((*serviceResult)->table().info().name == "openvcu-other");
  CHECK((*serviceResult)->events().channel(ipc::EventKind::Heartbeat) == "OPENVCU_OTHER_HEARTBEAT");
}

TEST_CASE("Service::open refuses a missing configuration and a bad --instance with one error each") {
  SKIP_UNLESS_ISOLATED();
  service::ServiceOptions missing;
  missing.configPath = "/tmp/no-such-vehicle.json";
  service::ServiceOptions badInstance;
  badInstance.configPath = CONFIG;
  badInstance.instance = "no spaces";

  const auto first = service::Service::open(demoInfo(), missing);
  const auto second = service::Service::open(demoInfo(), badInstance);

  REQUIRE_FALSE(first.ok());
  CHECK(first.error().toString().find("/tmp/no-such-vehicle.json") != std::string::npos);
  REQUIRE_FALSE(second.ok());
  CHECK(second.error().message == "--instance 'no spaces': must be 1-32 letters, digits, '-' or '_'");
}

TEST_CASE("Service::open refuses a known service with another writer id than config::SERVICES gives it (#20)") {
  SKIP_UNLESS_ISOLATED();
  service::ServiceOptions options;
  options.configPath = CONFIG;
  service::ServiceInfo fsm = demoInfo();
  fsm.name = "fsm";
  fsm.writerId = 9;
  const auto refused = service::Service::open(fsm, options);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message == "service 'fsm' has writer id 9, config::SERVICES gives it 3");
  service::ServiceInfo zero = demoInfo();
  zero.writerId = 0;
  const auto none = service::Service::open(zero, options);
  REQUIRE_FALSE(none.ok());
  CHECK(none.error().message.find("writer id 0") != std::string::npos);
}

TEST_CASE("a pending SIGTERM is read from the shutdown signalfd, not delivered as a kill") {
  SKIP_UNLESS_ISOLATED();
  auto signalsResult = service::ShutdownSignals::install();
  REQUIRE_STATUS(signalsResult);

  ::raise(SIGTERM);
  const auto received = signalsResult->take();
  const auto nothingMore = signalsResult->take();

  CHECK(received == SIGTERM);
  CHECK_FALSE(nothingMore.has_value());
  CHECK(service::signalName(SIGTERM) == "SIGTERM");
}

TEST_CASE("the loop waits on a frame subscriber, an fd and a timer together through ipc::Waiter") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness roudi;
  REQUIRE_STATUS(roudi.startRoudi());
  REQUIRE_STATUS(ipc::Runtime::init("test_service_runtime", 5s));
  auto loopResult = service::Loop::create();
  REQUIRE_STATUS(loopResult);
  service::Loop& sut = *loopResult;
  int pipeFds[2] = {-1, -1};
  REQUIRE(::pipe(pipeFds) == 0);
  bool fdSeen = false;
  REQUIRE_STATUS(sut.addFd(pipeFds[0], [&] {
    char byte = 0;
    REQUIRE(::read(pipeFds[0], &byte, 1) == 1);
    fdSeen = true;
  }));
  const ipc::FrameTopic topic{"svc", "vehicle", ipc::FrameStream::Received};
  auto subscriber = ipc::FrameSubscriber::create(topic);
  auto publisher = ipc::FramePublisher::create(topic);
  REQUIRE_STATUS(subscriber);
  REQUIRE_STATUS(publisher);
  std::uint64_t framesSeen = 0;
  REQUIRE_STATUS(sut.addSubscriber(*subscriber, [&] {
    while (subscriber->take()) ++framesSeen;
  }));
  auto timer = service::PeriodicTimer::create(5ms);
  REQUIRE_STATUS(timer);
  std::uint64_t ticks = 0;
  REQUIRE_STATUS(sut.addTimer(*timer, [&](const service::TimerTick&) { ++ticks; }));
  REQUIRE(publisher->waitForSubscribers(5s));

  REQUIRE(publisher->publish(ipc::FrameSample{}));
  const char byte = 'x';
  REQUIRE(::write(pipeFds[1], &byte, 1) == 1);
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while ((framesSeen == 0 || !fdSeen || ticks == 0) && std::chrono::steady_clock::now() < deadline) sut.runOnce(1s);

  CHECK(sut.usesWaiter());
  CHECK(framesSeen == 1);
  CHECK(fdSeen);
  CHECK(ticks >= 1);
  sut.removeFd(pipeFds[0]);
  ::close(pipeFds[0]);
  ::close(pipeFds[1]);
}

TEST_CASE("a loop with a subscriber and a timer only runs no fd-watcher thread, ticks on time and stops from another thread (#27)") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness roudi;
  REQUIRE_STATUS(roudi.startRoudi());
  REQUIRE_STATUS(ipc::Runtime::init("test_service_runtime", 5s));
  const ipc::FrameTopic topic{"svc", "timers", ipc::FrameStream::Received};
  auto subscriber = ipc::FrameSubscriber::create(topic);
  auto publisher = ipc::FramePublisher::create(topic);
  REQUIRE_STATUS(subscriber);
  REQUIRE_STATUS(publisher);
  auto threadCount = [] {
    std::size_t count = 0;
    for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator("/proc/self/task")) ++count;
    return count;
  };
  const std::size_t threadsBefore = threadCount();
  auto loopResult = service::Loop::create();
  REQUIRE_STATUS(loopResult);
  service::Loop& sut = *loopResult;
  std::uint64_t framesSeen = 0;
  REQUIRE_STATUS(sut.addSubscriber(*subscriber, [&] {
    while (subscriber->take()) ++framesSeen;
  }));
  constexpr auto PERIOD = 10ms;
  const auto first = std::chrono::steady_clock::now() + PERIOD;
  auto timer = service::PeriodicTimer::create(PERIOD, first);
  REQUIRE_STATUS(timer);
  std::vector<service::TimerTick> ticks;
  std::vector<std::chrono::steady_clock::time_point> tickedAt;
  REQUIRE_STATUS(sut.addTimer(*timer, [&](const service::TimerTick& tick) {
    ticks.push_back(tick);
    tickedAt.push_back(std::chrono::steady_clock::now());
  }));
  REQUIRE(publisher->waitForSubscribers(5s));
  REQUIRE(publisher->publish(ipc::FrameSample{}));

  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while ((framesSeen == 0 || ticks.size() < 3) && std::chrono::steady_clock::now() < deadline) sut.runOnce(1s);
  const std::size_t threadsRunning = threadCount();

  CHECK(sut.usesWaiter());
  CHECK(threadsRunning == threadsBefore);  // the timer needs no watcher thread
  CHECK(framesSeen == 1);
  REQUIRE(ticks.size() >= 3);
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    CHECK(ticks[i].deadline == first + PERIOD * static_cast<std::int64_t>(ticks[i].cycle - 1));
    CHECK(tickedAt[i] >= ticks[i].deadline);  // never early
  }

  sut.removeFd(timer->fd());  // nothing left to end the wait but stop()
  // run() has started when a deadline due at once has run
  std::atomic<bool> running{false};
  auto started = sut.addDeadline([&] { running.store(true); });
  REQUIRE(started.ok());
  sut.setDeadline(*started, std::chrono::steady_clock::now());
  std::thread stopper([&] {
    const auto giveUp = std::chrono::steady_clock::now() + 5s;
    while (!running.load() && std::chrono::steady_clock::now() < giveUp) std::this_thread::yield();
    sut.stop(5);
  });
  const auto stopStart = std::chrono::steady_clock::now();
  const int exitCode = sut.run();
  stopper.join();
  CHECK(running.load());
  CHECK(exitCode == 5);
  CHECK(std::chrono::steady_clock::now() - stopStart < 5s);
}
