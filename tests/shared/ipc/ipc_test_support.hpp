#pragma once
// Test support for the IPC tests: child processes with a readable stdout, the isolated
// iox-roudi, and the isolation check. Header-only; used by test_ipc, ipc_test_peer and the
// benchmark.

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/ipc/runtime.hpp"

extern char** environ;

namespace openvcu::ipctest {

using namespace std::chrono_literals;

inline constexpr auto READY_TIMEOUT = 20s;  // generous: JVM start-up on a loaded CI machine

/// true inside tests/shared/ipc/run_isolated.sh (private /dev/shm, /tmp, network, PIDs).
inline bool isolated() {
  return std::getenv("OPENVCU_ISOLATED") != nullptr;
}

inline const std::string NOT_ISOLATED_MESSAGE =
    "skipped: needs the sandbox of tests/shared/ipc/run_isolated.sh (ctest runs it there)";

/// A child process started with posix_spawn; its stdout (and stderr, merged) readable line by
/// line with a deadline. Ended by its pid (or its own process group) when destroyed.
class ChildProcess {
 public:
  ChildProcess() = default;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ChildProcess(ChildProcess&& other) noexcept { *this = std::move(other); }
  ChildProcess& operator=(ChildProcess&& other) noexcept {
    std::swap(m_pid, other.m_pid);
    std::swap(m_out, other.m_out);
    std::swap(m_ownGroup, other.m_ownGroup);
    std::swap(m_buffer, other.m_buffer);
    std::swap(m_exitStatus, other.m_exitStatus);
    return *this;
  }
  ~ChildProcess() {
    stop();
    if (m_out >= 0) ::close(m_out);
  }

  /// Starts argv[0] (searched in PATH). ownGroup: the child leads a new process group, so
  /// stop() ends it with everything it started (xvfb-run -> Xvfb + java). logFile: send
  /// the output there instead of a pipe (for long-running children nobody reads).
  static std::optional<ChildProcess> spawn(const std::vector<std::string>& argv, bool ownGroup = false,
                                           const std::string& logFile = {}) {
    int pipeFds[2] = {-1, -1};
    if (logFile.empty()) {
      if (::pipe2(pipeFds, O_CLOEXEC) != 0) return std::nullopt;
    } else {
      pipeFds[1] = ::open(logFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (pipeFds[1] < 0) return std::nullopt;
    }
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pipeFds[1], STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, pipeFds[1], STDERR_FILENO);
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    if (ownGroup) {
      posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
      posix_spawnattr_setpgroup(&attributes, 0);
    }
    std::vector<char*> args;
    for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
    args.push_back(nullptr);
    pid_t pid = -1;
    const int rc = ::posix_spawnp(&pid, args[0], &actions, &attributes, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    ::close(pipeFds[1]);
    if (rc != 0) {
      if (pipeFds[0] >= 0) ::close(pipeFds[0]);
      return std::nullopt;
    }
    ChildProcess child;
    child.m_pid = pid;
    child.m_out = pipeFds[0];
    child.m_ownGroup = ownGroup;
    return child;
  }

  [[nodiscard]] pid_t pid() const { return m_pid; }

  /// Next line of output (without '\n'), or empty when `timeout` passed or the child closed
  /// its output.
  std::optional<std::string> readLine(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      if (const auto newline = m_buffer.find('\n'); newline != std::string::npos) {
        std::string line = m_buffer.substr(0, newline);
        m_buffer.erase(0, newline + 1);
        return line;
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0 || m_out < 0) return std::nullopt;
      pollfd pfd{m_out, POLLIN, 0};
      if (::poll(&pfd, 1, static_cast<int>(left.count())) <= 0) continue;
      char chunk[4096];
      const ssize_t got = ::read(m_out, chunk, sizeof(chunk));
      if (got <= 0) {
        ::close(m_out);
        m_out = -1;
        continue;
      }
      m_buffer.append(chunk, static_cast<std::size_t>(got));
    }
  }

  /// Reads lines until one starts with `prefix`; returns it (empty on timeout / EOF).
  /// Every line read is appended to *transcript when given.
  std::optional<std::string> readUntil(const std::string& prefix, std::chrono::milliseconds timeout,
                                       std::string* transcript = nullptr) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      auto line = readLine(left);
      if (!line) return std::nullopt;
      if (transcript != nullptr) *transcript += *line + "\n";
      if (line->rfind(prefix, 0) == 0) return line;
    }
  }

  /// true while the child has not exited (reaps it when it has).
  bool running() {
    if (m_pid <= 0) return false;
    int status = 0;
    const pid_t rc = ::waitpid(m_pid, &status, WNOHANG);
    if (rc == 0) return true;
    m_exitStatus = status;
    m_pid = -1;
    return false;
  }

  /// Waits for the exit; the exit code, or empty on timeout (child left running) or signal.
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running()) {
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      drain();
      ::usleep(2000);
    }
    if (!m_exitStatus || !WIFEXITED(*m_exitStatus)) return std::nullopt;
    return WEXITSTATUS(*m_exitStatus);
  }

  /// SIGTERM (to its group if it leads one), then SIGKILL after 3 s; reaps it.
  void stop() {
    if (!running()) return;
    const pid_t target = m_ownGroup ? -m_pid : m_pid;
    ::kill(target, SIGTERM);
    if (wait(3s)) return;
    if (m_pid > 0) {
      ::kill(m_ownGroup ? -m_pid : m_pid, SIGKILL);
      int status = 0;
      ::waitpid(m_pid, &status, 0);
      m_pid = -1;
    }
  }

  /// Everything read but not yet returned as a line.
  [[nodiscard]] const std::string& pending() const { return m_buffer; }

 private:
  // Keeps the pipe from filling up while we wait for an exit.
  void drain() {
    if (m_out < 0) return;
    pollfd pfd{m_out, POLLIN, 0};
    if (::poll(&pfd, 1, 0) <= 0) return;
    char chunk[4096];
    const ssize_t got = ::read(m_out, chunk, sizeof(chunk));
    if (got > 0) m_buffer.append(chunk, static_cast<std::size_t>(got));
  }

  pid_t m_pid{-1};
  int m_out{-1};
  bool m_ownGroup{false};
  std::string m_buffer;
  std::optional<int> m_exitStatus;
};

/// Starts iox-roudi with config/iceoryx/roudi.toml once per test process and waits until it
/// accepts clients (its socket answers; no fixed sleep). Only inside the sandbox.
///
/// RouDi is deliberately never stopped by the test: stopping it while this process is
/// registered makes RouDi SIGTERM its clients, us included. The PID namespace of
/// run_isolated.sh ends it when the test process exits.
inline bool startIsolatedRoudi(const std::string& configPath) {
  static ChildProcess* roudi = nullptr;  // leaked on purpose, see above
  if (roudi != nullptr) return openvcu::ipc::Runtime::waitForRoudi(5s);
  if (!isolated()) return false;
  auto child = ChildProcess::spawn({"iox-roudi", "-c", configPath, "-l", "warning"}, false, "/tmp/iox-roudi.log");
  if (!child) return false;
  roudi = new ChildProcess(std::move(*child));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (!openvcu::ipc::Runtime::waitForRoudi(20ms)) {
    if (!roudi->running() || std::chrono::steady_clock::now() >= deadline) return false;  // e.g. a bad config
  }
  return true;
}

}  // namespace openvcu::ipctest
