// `vcu inject process`: SIGSTOP, SIGCONT and SIGKILL of a process this test started, found
// by its executable's name (a copy of sleep named vcu-<unique>), with the pid and time
// stamps printed; several matches are refused unless --pid names one; usage errors.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "inject_commands.hpp"
#include "openvcu/core/clock.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu;
using namespace openvcu::cli::test;
namespace fs = std::filesystem;

namespace {

/// A child running a copy of sleep named vcu-<service>; SIGKILLed and reaped at the end.
struct FakeService {
  pid_t pid{-1};
  FakeService(const fs::path& executable) {
    pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      ::execl(executable.c_str(), executable.c_str(), "30", static_cast<char*>(nullptr));
      ::_exit(127);
    }
    // exec has happened once /proc/<pid>/exe names the copy
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    std::error_code error;
    while (fs::read_symlink("/proc/" + std::to_string(pid) + "/exe", error) != executable &&
           std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  ~FakeService() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
  /// The state letter of /proc/<pid>/stat ('S' sleeping, 'T' stopped), once it is `wanted`
  /// or after 2 s.
  char waitForState(char wanted) const {
    char state = '?';
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    do {
      std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
      std::string line;
      std::getline(in, line);
      const auto close = line.rfind(')');
      state = close != std::string::npos && close + 2 < line.size() ? line[close + 2] : '?';
      if (state == wanted) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    } while (std::chrono::steady_clock::now() < end);
    return state;
  }
};

/// A unique service name and its executable (a copy of sleep) in the scratch folder.
std::pair<std::string, fs::path> fakeServiceBinary() {
  const std::string service = "inject-test-" + std::to_string(::getpid());
  const fs::path executable = scratchFolder() / ("vcu-" + service);
  fs::copy_file("/bin/sleep", executable, fs::copy_options::overwrite_existing);
  return {service, executable};
}

}  // namespace

TEST_CASE("vcu inject process stop and cont hang and resume the one process of that name, stamped") {
  const auto [service, executable] = fakeServiceBinary();
  FakeService sut(executable);
  REQUIRE(sut.waitForState('S') == 'S');

  const std::int64_t before = clock::monotonicNs();
  const RunResult stopped = runVcu({"inject", "process", "stop", service, "--json"});
  const std::int64_t after = clock::monotonicNs();
  REQUIRE_MESSAGE(stopped.exitCode == 0, stopped.err);
  CHECK(sut.waitForState('T') == 'T');
  const auto answer = nlohmann::json::parse(stopped.out);
  CHECK(answer["pid"] == sut.pid);
  CHECK(answer["signal"] == "STOP");
  CHECK(answer["executable"] == "vcu-" + service);
  CHECK(answer["monotonicNs"].get<std::int64_t>() >= before);
  CHECK(answer["monotonicNs"].get<std::int64_t>() <= after);
  CHECK(answer["realtimeNs"].get<std::int64_t>() > 0);

  const RunResult resumed = runVcu({"inject", "process", "cont", service});
  REQUIRE_MESSAGE(resumed.exitCode == 0, resumed.err);
  CHECK(
      contains(resumed.out, "SIGCONT sent to vcu-" + service + " (pid " + std::to_string(sut.pid) + ") at monotonic"));
  CHECK(sut.waitForState('S') == 'S');
}

TEST_CASE("vcu inject process refuses several matches unless --pid names one, and kills that one") {
  const auto [service, executable] = fakeServiceBinary();
  FakeService first(executable);
  FakeService second(executable);

  const RunResult ambiguous = runVcu({"inject", "process", "kill", service});
  CHECK(ambiguous.exitCode == 1);
  CHECK_MESSAGE(contains(ambiguous.err, "2 processes vcu-" + service + " are running (pids "), ambiguous.err);
  CHECK(contains(ambiguous.err, "name one with --pid"));

  const RunResult killed = runVcu({"inject", "process", "kill", service, "--pid", std::to_string(second.pid)});
  REQUIRE_MESSAGE(killed.exitCode == 0, killed.err);
  int status = 0;
  REQUIRE(::waitpid(second.pid, &status, 0) == second.pid);
  second.pid = -1;
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGKILL);
  CHECK(first.waitForState('S') == 'S');  // the other one untouched
}

TEST_CASE("vcu inject process names what is wrong: no such process, a foreign pid, a bad action") {
  const RunResult missing = runVcu({"inject", "process", "stop", "no-such-service-here"});
  CHECK(missing.exitCode == 1);
  CHECK(contains(missing.err, "no process vcu-no-such-service-here of this user is running"));

  const auto [service, executable] = fakeServiceBinary();
  FakeService sut(executable);
  const RunResult foreign = runVcu({"inject", "process", "stop", service, "--pid", "1"});
  CHECK(foreign.exitCode == 1);
  CHECK(contains(foreign.err, "pid 1 is not a process vcu-" + service + " of this user"));
  CHECK(sut.waitForState('S') == 'S');

  const RunResult badAction = runVcu({"inject", "process", "pause", service});
  CHECK(badAction.exitCode == 2);
  CHECK(contains(badAction.err, "expected stop, cont or kill, not 'pause'"));
}

TEST_CASE("frame fault keys carry the kind, the target and the parameter, and no parameter when cleared") {
  cli::FrameInjectOptions options;
  options.kind = "delay";
  options.target = "VIC";
  options.parameter = "300";
  CHECK(cli::frameFaultKey(options) == "delay.VIC=300");
  options.off = true;
  CHECK(cli::frameFaultKey(options) == "delay.VIC");
  const RunResult missing = runVcu({"inject", "delay", "VIC", "--config", "/nonexistent/vehicle.json"});
  CHECK(missing.exitCode == 2);
  CHECK(contains(missing.err, "--ms is required (or --off to clear)"));
}
