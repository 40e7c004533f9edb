#pragma once
// The multi-process test harness (docs/testing.md): starts iox-roudi and real service
// processes inside the sandbox of run_isolated.sh, waits for their readiness through the
// systemd notify protocol (never a fixed sleep), runs command-line tools to completion,
// collects every process's output in files, prints them when the test case failed, and
// stops only what it started (by PID).
//
//   TEST_CASE("vcu signal set is accepted by the service that owns the key") {
//     if (!harness::isolated()) { MESSAGE(harness::NOT_ISOLATED); return; }
//     harness::Harness sut;
//     REQUIRE_STATUS(sut.startRoudi());
//     auto service = sut.start({.name = "fixture", .argv = {FIXTURE, "--config", CONFIG}, .notifyReadiness = true});
//     REQUIRE_STATUS(service);
//     const harness::CommandResult set = sut.run({VCU, "signal", "set", "--config", CONFIG, "internal.x", "1"});
//     CHECK_MESSAGE(set.exitCode == 0, set.describe());
//   }   // ~Harness: SIGTERM (then SIGKILL) to each process it started, reaped; logs printed if the case failed
//
// Readiness: the harness binds a Unix datagram socket (SO_PASSCRED) and gives its path to
// the processes it starts as NOTIFY_SOCKET; each datagram arrives with the sender's pid in
// SCM_CREDENTIALS, so "READY=1" is attributed to exactly the process that sent it (what
// systemd does for Type=notify). start() returns once READY=1 came from the new pid, or
// fails at once when the process exits first, or after the timeout.
//
// Logs: <build>/tests/harness-logs/<test case>-<pid>/ holds "<n>-<name>.log" (stdout and
// stderr of each started process), "<n>-<name>.out/.err" (each run()), "notify.log" and
// "transcript.log". The folder is removed when the test case passed and kept (and printed
// to stderr) when it failed.
//
// @note not thread-safe: one Harness per test case, used from the test's thread. The test
//       process itself should not register with iox-roudi (ipc::Runtime::init): stopping
//       RouDi would SIGTERM it; if it did, the harness leaves RouDi to the PID namespace.

#include <sys/types.h>

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::harness {

using namespace std::chrono_literals;

/// Generous: a loaded CI machine, a Debug build, a first iceoryx registration.
inline constexpr std::chrono::milliseconds READY_TIMEOUT = 20s;
inline constexpr std::chrono::milliseconds COMMAND_TIMEOUT = 30s;
inline constexpr std::chrono::milliseconds STOP_TIMEOUT = 5s;

/// true inside run_isolated.sh (OPENVCU_ISOLATED=1): private /dev/shm, /tmp, network, PIDs.
[[nodiscard]] bool isolated() noexcept;
/// What a test case outside the sandbox says when it skips.
inline constexpr const char* NOT_ISOLATED =
    "skipped: needs the sandbox of tests/harness/run_isolated.sh (ctest runs it there)";

/// What to start. argv[0] is a path or a name looked up in PATH.
struct ProcessSpec {
  std::string name{};  ///< for logs: "fixture", "roudi"
  std::vector<std::string> argv{};
  std::vector<std::string> environment{};  ///< extra "NAME=value" entries
  bool notifyReadiness{false};             ///< set NOTIFY_SOCKET; start() waits for READY=1
  bool captureOutput{false};               ///< stdout+stderr through a pipe for readLine (also logged)
};

/// How a process ended.
struct ExitStatus {
  bool exited{false};  ///< normal exit (then `code`); else killed by `signal`
  int code{-1};
  int signal{0};
  [[nodiscard]] std::string toString() const;  ///< "exit code 0", "killed by SIGKILL"
};

/// A process the harness started. Owned by the Harness; stays valid until it is destroyed.
class Process {
 public:
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;
  ~Process();

  [[nodiscard]] pid_t pid() const noexcept { return m_pid; }
  [[nodiscard]] const std::string& name() const noexcept { return m_spec.name; }
  [[nodiscard]] const ProcessSpec& spec() const noexcept { return m_spec; }
  [[nodiscard]] const std::string& logPath() const noexcept { return m_logPath; }

  /// true while it has not exited (reaps it when it has: no zombie, no busy wait).
  bool running();
  /// How it ended; empty while running.
  [[nodiscard]] const std::optional<ExitStatus>& exitStatus() const noexcept { return m_exit; }
  /// Waits (pidfd + poll) for the exit; empty on timeout.
  std::optional<ExitStatus> waitForExit(std::chrono::milliseconds timeout);
  /// Sends `signalNumber` to this process only (never to a group or a name).
  bool signal(int signalNumber) noexcept;

  /// captureOutput only: the next output line (without '\n'); empty on timeout or EOF.
  std::optional<std::string> readLine(std::chrono::milliseconds timeout);
  /// captureOutput only: reads lines until one contains `text`; returns it (empty on timeout/EOF).
  std::optional<std::string> waitForLine(std::string_view text, std::chrono::milliseconds timeout);
  /// Everything captured (captureOutput) or the log file's content.
  [[nodiscard]] std::string output() const;

 private:
  friend class Harness;
  Process(ProcessSpec spec, std::string logPath) : m_spec(std::move(spec)), m_logPath(std::move(logPath)) {}
  void pump(std::chrono::milliseconds timeout);

  ProcessSpec m_spec;
  std::string m_logPath;
  pid_t m_pid{-1};
  int m_pidFd{-1};
  int m_outFd{-1};  ///< read end of the capture pipe
  int m_logFd{-1};  ///< capture: where we copy what we read
  std::string m_buffer;
  std::string m_captured;
  std::optional<ExitStatus> m_exit;
};

/// The result of a command run to completion.
struct CommandResult {
  std::vector<std::string> argv;
  std::optional<ExitStatus> status;  ///< empty: timed out (then killed)
  std::string out;
  std::string err;
  /// exit code, -1 when killed or timed out
  [[nodiscard]] int exitCode() const noexcept { return status && status->exited ? status->code : -1; }
  /// The command, its status and both outputs, for failure messages.
  [[nodiscard]] std::string describe() const;
};

class Harness {
 public:
  /// Creates the log folder and the notify socket. Use only inside the sandbox.
  Harness();
  Harness(const Harness&) = delete;
  Harness& operator=(const Harness&) = delete;
  /// Stops what is still running (SIGTERM, SIGKILL after STOP_TIMEOUT; RouDi last), reaps,
  /// prints the logs if the test case failed, else removes them.
  ~Harness();

  /// Starts `iox-roudi -c <config>` (default: config/iceoryx/roudi.toml of the source tree)
  /// and waits until its socket answers; fails at once if it exits (a bad config).
  Status startRoudi(const std::string& configPath = {});
  /// The RouDi of the last startRoudi(), or nullptr (to kill it: roudi()->signal(SIGKILL)).
  [[nodiscard]] Process* roudi() noexcept { return m_roudi; }

  /// Starts a process; with spec.notifyReadiness waits for its READY=1.
  Result<Process*> start(ProcessSpec spec, std::chrono::milliseconds readyTimeout = READY_TIMEOUT);

  /// Waits until `process` sent a datagram containing the assignment `assignment`
  /// ("READY=1", "STOPPING=1"); true at once if it already did.
  bool waitForNotify(const Process& process, std::string_view assignment,
                     std::chrono::milliseconds timeout = READY_TIMEOUT);
  /// Every assignment received from `process` so far, in order ("READY=1", "STATUS=ready", ...).
  [[nodiscard]] std::vector<std::string> notifications(const Process& process);

  /// Runs a command to completion (stdout and stderr captured separately); killed after
  /// `timeout`. Not given NOTIFY_SOCKET.
  CommandResult run(std::vector<std::string> argv, std::chrono::milliseconds timeout = COMMAND_TIMEOUT,
                    std::vector<std::string> environment = {});

  /// SIGTERM, then SIGKILL after `timeout`; reaps. The exit status.
  std::optional<ExitStatus> stop(Process& process, std::chrono::milliseconds timeout = STOP_TIMEOUT);

  [[nodiscard]] const std::string& logDirectory() const noexcept { return m_logDirectory; }
  [[nodiscard]] const std::string& notifySocketPath() const noexcept { return m_notifyPath; }
  /// Writes every log of this harness to stderr (also done automatically on failure).
  void printLogs() const;

 private:
  Result<Process*> spawn(ProcessSpec spec, bool withNotify, const std::string& logPath);
  void receiveNotifications(std::chrono::milliseconds timeout, int extraFd = -1);
  void appendTranscript(const std::string& text) const;
  std::string nextLogName(const std::string& name);

  std::string m_logDirectory;
  std::string m_runDirectory;  ///< in the sandbox's /tmp: the notify socket
  std::string m_notifyPath;
  int m_notifyFd{-1};
  std::vector<std::unique_ptr<Process>> m_processes;
  Process* m_roudi{nullptr};
  std::map<pid_t, std::vector<std::string>> m_notifications;
  unsigned m_counter{};
};

/// true when an assertion failed in the current test case (the harness's doctest listener).
[[nodiscard]] bool currentTestFailed() noexcept;

}  // namespace openvcu::harness

/// REQUIRE on a Result/Status, printing its error when it fails.
#define REQUIRE_STATUS(result) \
  REQUIRE_MESSAGE((result).ok(), ((result).ok() ? std::string() : (result).error().toString()))
#define CHECK_STATUS(result) CHECK_MESSAGE((result).ok(), ((result).ok() ? std::string() : (result).error().toString()))
