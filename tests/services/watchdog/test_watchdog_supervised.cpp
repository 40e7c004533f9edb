// vcu-watchdog with a hung service, in the sandbox: a tiny supervisord runs the real vcu-gpio
// (simulated chip, HHEA configuration) and the real vcu-watchdog, watching gpio with
// silentAfterMs 1500 and feeding a FIFO standing in for /dev/watchdog (the test reads it and
// stamps every byte). vcu-gpio is SIGSTOPped (a hang). Shown, with times from the SIGSTOP:
//   - the critical fault service_silent.gpio from vcu-watchdog on LCM within silentAfterMs +
//     one heartbeat period (the last beat lies up to a period before the hang);
//   - "restart": the stopped process killed, supervisord starting a new vcu-gpio that beats
//     (a heartbeat with a new pid) and the fault cleared;
//   - without "restart": nothing killed, no feed of the board watchdog while gpio is silent,
//     the fault cleared and the feeds resumed once it is SIGCONTinued; the magic close 'V'
//     when supervisord stops vcu-watchdog.

#include <doctest/doctest.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "harness.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "skip.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace openvcu;
using Clock = std::chrono::steady_clock;

namespace {

constexpr std::int64_t SILENT_AFTER_MS = 1500;
constexpr auto BEAT_PERIOD = 1000ms;
/// Detection: silentAfterMs after the last beat, which lies up to one period before the hang.
constexpr auto DETECTION_BOUND = std::chrono::milliseconds(SILENT_AFTER_MS) + BEAT_PERIOD;
/// Restart: detection, the kill, supervisord's restart (at once or at its next once-a-second
/// tick), the new process's start-up (configuration, DBC, checks: slow on a loaded machine)
/// and first beat.
constexpr auto RESTART_BOUND = DETECTION_BOUND + 5000ms;

std::int64_t msSince(Clock::time_point start, Clock::time_point end) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(end - start).count();
}

std::string readAll(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

/// config/hhea copied to `folder` with a safety case whose watchdog watches gpio only, kills
/// (or not: `restart`) and feeds `device`; returns the vehicle.json path.
fs::path writeVehicle(const fs::path& folder, const fs::path& device, bool restart) {
  fs::create_directories(folder);
  for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config" / "hhea")) {
    fs::copy(entry.path(), folder / entry.path().filename(), fs::copy_options::overwrite_existing);
  }
  const nlohmann::json safety = {
      {"watchdog",
       {{"services", {"gpio"}}, {"silentAfterMs", SILENT_AFTER_MS}, {"restart", restart}, {"device", device.string()}}},
      {"hazards", nlohmann::json::array()}};
  std::ofstream(folder / "safety.json") << safety.dump(2);
  std::ifstream in(folder / "vehicle.json");
  nlohmann::json vehicle = nlohmann::json::parse(in);
  vehicle["safety"] = "safety.json";
  std::ofstream(folder / "vehicle.json") << vehicle.dump(2);
  return folder / "vehicle.json";
}

/// A supervisord configuration with vcu-gpio and vcu-watchdog, as config/supervisor/openvcu.conf.
fs::path writeSupervisorConf(const fs::path& folder, const fs::path& vehicle) {
  std::ofstream conf(folder / "supervisord.conf");
  conf << "[supervisord]\nnodaemon=true\nlogfile=" << (folder / "supervisord.log").string()
       << "\npidfile=" << (folder / "supervisord.pid").string() << "\nchildlogdir=" << folder.string() << "\n"
       << (::geteuid() == 0 ? "user=root\n" : "")
       << "[unix_http_server]\nfile=" << (folder / "supervisor.sock").string() << "\n"
       << "[rpcinterface:supervisor]\nsupervisor.rpcinterface_factory = "
          "supervisor.rpcinterface:make_main_rpcinterface\n";
  for (const auto& [name, binary] : {std::pair<std::string, std::string>{"gpio", GPIO_BINARY},
                                     std::pair<std::string, std::string>{"watchdog", WATCHDOG_BINARY}}) {
    conf << "[program:" << name << "]\ncommand=" << binary << " --config " << vehicle.string()
         << "\nautorestart=true\nstartsecs=1\nstopsignal=TERM\nstopwaitsecs=5\nstdout_logfile="
         << (folder / (name + ".log")).string() << "\nredirect_stderr=true\n";
  }
  return folder / "supervisord.conf";
}

/// The FIFO standing in for /dev/watchdog: every byte written to it, with the time it was read.
/// The test holds a write end too, so the reader never sees an end of file.
class FeedRecorder {
 public:
  explicit FeedRecorder(const fs::path& path) {
    REQUIRE(::mkfifo(path.c_str(), 0600) == 0);
    m_readFd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    REQUIRE(m_readFd >= 0);
    m_holdFd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    REQUIRE(m_holdFd >= 0);
    m_thread = std::thread([this] { run(); });
  }
  ~FeedRecorder() {
    m_stop = true;
    m_thread.join();
    ::close(m_holdFd);
    ::close(m_readFd);
  }
  [[nodiscard]] std::vector<std::pair<Clock::time_point, char>> bytes() const {
    std::lock_guard lock(m_mutex);
    return m_bytes;
  }
  /// Bytes read in [from, to].
  [[nodiscard]] std::size_t countBetween(Clock::time_point from, Clock::time_point to) const {
    std::size_t count = 0;
    for (const auto& [at, byte] : bytes()) count += (at >= from && at <= to) ? 1 : 0;
    return count;
  }

 private:
  void run() {
    pollfd readable{m_readFd, POLLIN, 0};
    while (!m_stop) {
      if (::poll(&readable, 1, 50) <= 0) continue;
      char buffer[64];
      const ssize_t count = ::read(m_readFd, buffer, sizeof buffer);
      const auto now = Clock::now();
      std::lock_guard lock(m_mutex);
      for (ssize_t i = 0; i < count; ++i) m_bytes.emplace_back(now, buffer[i]);
    }
  }
  int m_readFd{-1};
  int m_holdFd{-1};
  std::atomic<bool> m_stop{false};
  mutable std::mutex m_mutex;
  std::vector<std::pair<Clock::time_point, char>> m_bytes;
  std::thread m_thread;
};

/// What the test hears on the event plane.
struct Heard {
  std::vector<std::pair<Clock::time_point, ipc::FaultEvent>> faults;
  std::vector<std::pair<Clock::time_point, ipc::Heartbeat>> heartbeats;
};

/// supervisord with vcu-gpio and vcu-watchdog, the FIFO and the event plane.
struct SupervisedStack {
  fs::path folder = fs::temp_directory_path() / "watchdog-test";
  fs::path device = folder / "fake-watchdog";
  std::optional<FeedRecorder> feeds;
  std::optional<ipc::EventBus> bus;
  Heard heard;
  harness::Harness sut;
  harness::Process* supervisor{};

  explicit SupervisedStack(bool restart) {
    fs::create_directories(folder);
    feeds.emplace(device);
    const fs::path vehicle = writeVehicle(folder / "hhea", device, restart);
    auto vehicleResult = config::loadVehicleConfig(vehicle.string());
    REQUIRE_STATUS(vehicleResult);
    auto busResult = ipc::EventBus::open(vehicleResult->lcmUrl, vehicleResult->instance);
    REQUIRE_STATUS(busResult);
    bus.emplace(std::move(*busResult));
    REQUIRE_STATUS(
        bus->onFault([this](const ipc::FaultEvent& event) { heard.faults.emplace_back(Clock::now(), event); }));
    REQUIRE_STATUS(
        bus->onHeartbeat([this](const ipc::Heartbeat& beat) { heard.heartbeats.emplace_back(Clock::now(), beat); }));
    auto started = sut.start(
        {.name = "supervisord", .argv = {"supervisord", "-n", "-c", writeSupervisorConf(folder, vehicle).string()}});
    REQUIRE_STATUS(started);
    supervisor = *started;
    // both beat, and the watchdog sees gpio beating (its status)
    REQUIRE_MESSAGE(pumpUntil(
                        [&] {
                          // vcu-watchdog kills only a process it has seen beat (or one older than
                          // its start grace): it reads the slot every 100 ms, so a watchdog beat
                          // after vcu-gpio's second beat comes after it saw the first
                          int gpioBeats = 0;
                          for (const auto& [at, beat] : heard.heartbeats) {
                            if (beat.service == "vcu-gpio") ++gpioBeats;
                            if (gpioBeats >= 2 && beat.service == "vcu-watchdog" &&
                                beat.status == "all 1 services beating" && latestPid("vcu-gpio")) {
                              return true;
                            }
                          }
                          return false;
                        },
                        10s),
                    "vcu-gpio and vcu-watchdog did not both beat: " << log());
  }

  /// Dispatches events until `done` or `timeout`; true when done.
  template <typename Done>
  bool pumpUntil(const Done& done, std::chrono::milliseconds timeout) {
    const auto end = Clock::now() + timeout;
    while (!done()) {
      if (Clock::now() >= end) return false;
      (void)bus->handle(20ms);
    }
    return true;
  }
  [[nodiscard]] std::optional<std::int32_t> latestPid(const std::string& service) const {
    for (auto it = heard.heartbeats.rbegin(); it != heard.heartbeats.rend(); ++it) {
      if (it->second.service == service) return it->second.pid;
    }
    return std::nullopt;
  }
  /// When service_silent.gpio was heard raised (`active`) or cleared after `after`.
  [[nodiscard]] std::optional<Clock::time_point> silentFault(bool active, Clock::time_point after) const {
    for (const auto& [at, event] : heard.faults) {
      if (event.name == "service_silent.gpio" && event.active == active && at > after) return at;
    }
    return std::nullopt;
  }
  [[nodiscard]] std::string log() const { return readAll(folder / "watchdog.log"); }
  void checkFaultEvents() const {
    for (const auto& [at, event] : heard.faults) {
      if (event.name != "service_silent.gpio") continue;
      CHECK(event.source == "vcu-watchdog");
      CHECK(event.severity == ipc::FaultSeverity::Critical);
      if (event.active) CHECK_MESSAGE(event.text.find("vcu-gpio silent for") == 0, event.text);
    }
  }
};

}  // namespace

TEST_CASE("a SIGSTOPped vcu-gpio is reported silent, killed and restarted by vcu-watchdog under supervisord") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  SupervisedStack stack(true);
  const std::int32_t hung = *stack.latestPid("vcu-gpio");

  REQUIRE(::kill(hung, SIGSTOP) == 0);
  const auto stoppedAt = Clock::now();
  REQUIRE_MESSAGE(stack.pumpUntil([&] { return stack.silentFault(true, stoppedAt).has_value(); }, 6s),
                  "no service_silent.gpio within 6 s: " << stack.log());
  const auto raisedAt = *stack.silentFault(true, stoppedAt);

  // the hung process goes (supervisord reaps it), a new one beats, the fault clears
  std::optional<Clock::time_point> killedAt;
  std::optional<Clock::time_point> restartedAt;
  REQUIRE_MESSAGE(stack.pumpUntil(
                      [&] {
                        if (!killedAt && ::kill(hung, 0) != 0) killedAt = Clock::now();
                        for (const auto& [at, beat] : stack.heard.heartbeats) {
                          if (!restartedAt && at > stoppedAt && beat.service == "vcu-gpio" && beat.pid != hung) {
                            restartedAt = at;
                          }
                        }
                        return killedAt && restartedAt && stack.silentFault(false, raisedAt);
                      },
                      15s),
                  "within 15 s of the fault: reaped "
                      << killedAt.has_value() << ", a new vcu-gpio beating " << restartedAt.has_value() << ", cleared "
                      << stack.silentFault(false, raisedAt).has_value() << "; " << stack.log()
                      << readAll(stack.folder / "gpio.log"));
  const auto clearedAt = *stack.silentFault(false, raisedAt);
  const std::string watchdogLog = stack.log();

  const std::int64_t detectionMs = msSince(stoppedAt, raisedAt);
  const std::int64_t restartMs = msSince(stoppedAt, *restartedAt);
  MESSAGE("from the SIGSTOP: service_silent.gpio after "
          << detectionMs << " ms, reaped by supervisord after " << msSince(stoppedAt, *killedAt)
          << " ms, a new vcu-gpio beating after " << restartMs << " ms, fault cleared after "
          << msSince(stoppedAt, clearedAt) << " ms");
  CHECK(detectionMs <= std::chrono::milliseconds(DETECTION_BOUND).count());
  CHECK(restartMs <= std::chrono::milliseconds(RESTART_BOUND).count());
  stack.checkFaultEvents();
  CHECK_MESSAGE(watchdogLog.find("killed vcu-gpio (pid " + std::to_string(hung) + ", state T") != std::string::npos,
                watchdogLog);
  // no feed while silent (heard up to 100 ms after vcu-watchdog cleared it and may have fed)
  CHECK(stack.feeds->countBetween(raisedAt, clearedAt - 100ms) == 0);
}

TEST_CASE("without restart vcu-watchdog kills nothing and stops feeding the board watchdog while a service is silent") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  SupervisedStack stack(false);
  const std::int32_t hung = *stack.latestPid("vcu-gpio");
  REQUIRE(stack.pumpUntil([&] { return stack.feeds->bytes().size() >= 2; }, 3s));

  REQUIRE(::kill(hung, SIGSTOP) == 0);
  const auto stoppedAt = Clock::now();
  REQUIRE_MESSAGE(stack.pumpUntil([&] { return stack.silentFault(true, stoppedAt).has_value(); }, 6s),
                  "no service_silent.gpio within 6 s: " << stack.log());
  const auto raisedAt = *stack.silentFault(true, stoppedAt);
  // silent for two feed periods more: not killed, not fed
  (void)stack.pumpUntil([] { return false; }, 2200ms);
  CHECK(::kill(hung, 0) == 0);
  REQUIRE(::kill(hung, SIGCONT) == 0);
  const auto continuedAt = Clock::now();
  REQUIRE_MESSAGE(stack.pumpUntil([&] { return stack.silentFault(false, raisedAt).has_value(); }, 3s),
                  "service_silent.gpio not cleared after SIGCONT: " << stack.log());
  REQUIRE(stack.pumpUntil([&] { return stack.feeds->countBetween(continuedAt, Clock::now()) > 0; }, 3s));

  const auto fed = stack.feeds->bytes();
  std::int64_t longestGapMs = 0;
  for (std::size_t i = 1; i < fed.size(); ++i)
    longestGapMs = std::max(longestGapMs, msSince(fed[i - 1].first, fed[i].first));
  MESSAGE("service_silent.gpio after " << msSince(stoppedAt, raisedAt) << " ms; feeds " << fed.size()
                                       << ", longest gap " << longestGapMs << " ms");
  CHECK(msSince(stoppedAt, raisedAt) <= std::chrono::milliseconds(DETECTION_BOUND).count());
  CHECK(stack.feeds->countBetween(raisedAt, continuedAt) == 0);
  CHECK(longestGapMs >= 2200);  // fed once a second otherwise
  for (const auto& [at, byte] : fed) CHECK(byte == '1');
  stack.checkFaultEvents();
  CHECK(stack.log().find("killed vcu-gpio") == std::string::npos);
  CHECK(stack.latestPid("vcu-gpio") == hung);

  REQUIRE(stack.sut.stop(*stack.supervisor, 10s));
  // supervisord stopped vcu-watchdog with SIGTERM: the magic close
  REQUIRE(stack.pumpUntil(
      [&] {
        const auto written = stack.feeds->bytes();
        return !written.empty() && written.back().second == 'V';
      },
      1s));
}
