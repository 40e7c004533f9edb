#include "harness.hpp"

#include <doctest/doctest.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "openvcu/ipc/runtime.hpp"

extern char** environ;

namespace openvcu::harness {

namespace {

namespace fs = std::filesystem;

std::atomic<bool> g_testFailed{false};
std::string g_testName = "test";  // written by the listener between test cases only

/// Marks the current test case failed on any failed assertion or escaped exception, so the
/// Harness destructor knows whether to print its logs.
struct FailureListener : doctest::IReporter {
  explicit FailureListener(const doctest::ContextOptions& /*options*/) {}
  void report_query(const doctest::QueryData& /*data*/) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats& /*stats*/) override {}
  void test_case_start(const doctest::TestCaseData& data) override {
    g_testFailed = false;
    g_testName = data.m_name;
  }
  void test_case_reenter(const doctest::TestCaseData& /*data*/) override {}
  void test_case_end(const doctest::CurrentTestCaseStats& /*stats*/) override {}
  void test_case_exception(const doctest::TestCaseException& /*exception*/) override { g_testFailed = true; }
  void subcase_start(const doctest::SubcaseSignature& /*signature*/) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData& data) override {
    if (data.m_failed) g_testFailed = true;
  }
  void log_message(const doctest::MessageData& /*data*/) override {}
  void test_case_skipped(const doctest::TestCaseData& /*data*/) override {}
};

}  // namespace
}  // namespace openvcu::harness

REGISTER_LISTENER("openvcu-harness", 1, openvcu::harness::FailureListener);

namespace openvcu::harness {

namespace {

std::string sanitize(std::string_view text, std::size_t maxLength) {
  std::string out;
  for (const char c : text) {
    if (out.size() >= maxLength) break;
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-';
    out += plain ? c : '_';
  }
  return out.empty() ? "test" : out;
}

std::string joinArgv(const std::vector<std::string>& argv) {
  std::string text;
  for (const std::string& arg : argv) {
    if (!text.empty()) text += ' ';
    const bool plain = !arg.empty() && arg.find_first_of(" \t'\"*?$\\") == std::string::npos;
    text += plain ? arg : "'" + arg + "'";
  }
  return text;
}

std::string readWholeFile(const std::string& path, std::size_t maxBytes = SIZE_MAX) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  std::string content = text.str();
  if (content.size() > maxBytes)
    content = "[... " + std::to_string(content.size() - maxBytes) + " bytes cut ...]\n" +
              content.substr(content.size() - maxBytes);
  return content;
}

/// argv[0] as given when it has a '/', else the first match in PATH (resolved before fork).
std::string resolveProgram(const std::string& program) {
  if (program.find('/') != std::string::npos) return program;
  const char* path = std::getenv("PATH");
  std::string_view dirs = path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin";
  while (!dirs.empty()) {
    const std::size_t colon = dirs.find(':');
    const std::string dir(dirs.substr(0, colon));
    dirs = colon == std::string_view::npos ? std::string_view{} : dirs.substr(colon + 1);
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return program;
}

int pidfdOpen(pid_t pid) noexcept {
  return static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
}

ExitStatus toExitStatus(int status) noexcept {
  ExitStatus exit;
  if (WIFEXITED(status)) {
    exit.exited = true;
    exit.code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    exit.signal = WTERMSIG(status);
  }
  return exit;
}

struct Spawned {
  pid_t pid{-1};
  int pidFd{-1};
};

/// fork + execve with prepared arrays: the child only makes async-signal-safe calls.
Result<Spawned> spawnProcess(const std::vector<std::string>& argv, const std::vector<std::string>& environment,
                             int stdoutFd, int stderrFd) {
  if (argv.empty()) return Error{"no command given"};
  const std::string program = resolveProgram(argv[0]);
  std::vector<char*> args;
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  std::vector<char*> envp;
  for (const std::string& entry : environment) envp.push_back(const_cast<char*>(entry.c_str()));
  envp.push_back(nullptr);
  const int devNull = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  const pid_t parent = ::getpid();

  const pid_t pid = ::fork();
  if (pid < 0) {
    if (devNull >= 0) ::close(devNull);
    return Error{std::string("fork failed: ") + std::strerror(errno)};
  }
  if (pid == 0) {
    if (devNull >= 0) ::dup2(devNull, STDIN_FILENO);
    ::dup2(stdoutFd, STDOUT_FILENO);
    ::dup2(stderrFd, STDERR_FILENO);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);  // a test may block signals; children start clean
    struct sigaction defaultAction {};
    defaultAction.sa_handler = SIG_DFL;
    for (const int sig : {SIGTERM, SIGINT, SIGPIPE, SIGCHLD}) ::sigaction(sig, &defaultAction, nullptr);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // the test process died: so do we
    if (::getppid() != parent) ::_exit(127);
    ::execve(program.c_str(), args.data(), envp.data());
    const char message[] = "harness: execve failed\n";
    [[maybe_unused]] const auto written = ::write(STDERR_FILENO, message, sizeof(message) - 1);
    ::_exit(127);
  }
  if (devNull >= 0) ::close(devNull);
  return Spawned{pid, pidfdOpen(pid)};
}

/// The test process's environment without the variables the harness sets itself, plus `extra`.
std::vector<std::string> childEnvironment(const std::vector<std::string>& extra, const std::string& notifyPath) {
  std::vector<std::string> environment;
  auto overridden = [&](std::string_view entry) {
    const std::string_view name = entry.substr(0, entry.find('='));
    if (name == "NOTIFY_SOCKET" || name == "WATCHDOG_USEC" || name == "WATCHDOG_PID") return true;
    return std::any_of(extra.begin(), extra.end(), [&](const std::string& mine) {
      return std::string_view(mine).substr(0, mine.find('=')) == name;
    });
  };
  for (char** entry = environ; *entry != nullptr; ++entry) {
    if (!overridden(*entry)) environment.emplace_back(*entry);
  }
  environment.insert(environment.end(), extra.begin(), extra.end());
  if (!notifyPath.empty()) environment.push_back("NOTIFY_SOCKET=" + notifyPath);
  return environment;
}

int remainingMs(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
  return static_cast<int>(std::clamp<std::int64_t>(left.count(), 0, 3'600'000));
}

}  // namespace

bool isolated() noexcept {
  return std::getenv("OPENVCU_ISOLATED") != nullptr;
}

bool currentTestFailed() noexcept {
  return g_testFailed;
}

std::string ExitStatus::toString() const {
  if (exited) return "exit code " + std::to_string(code);
  if (signal == SIGKILL) return "killed by SIGKILL";
  if (signal == SIGTERM) return "killed by SIGTERM";
  if (signal != 0) return "killed by signal " + std::to_string(signal);
  return "unknown status";
}

std::string CommandResult::describe() const {
  std::string text = "$ " + joinArgv(argv) + "\n-> " + (status ? status->toString() : "timed out (killed)") + "\n";
  if (!out.empty()) text += "stdout:\n" + out + (out.back() == '\n' ? "" : "\n");
  if (!err.empty()) text += "stderr:\n" + err + (err.back() == '\n' ? "" : "\n");
  return text;
}

// ---- Process ---------------------------------------------------------------------------

Process::~Process() {
  if (m_pid > 0 && running()) {
    ::kill(m_pid, SIGKILL);
    int status = 0;
    ::waitpid(m_pid, &status, 0);
  }
  for (const int fd : {m_pidFd, m_outFd, m_logFd}) {
    if (fd >= 0) ::close(fd);
  }
}

bool Process::running() {
  if (m_exit) return false;
  if (m_pid <= 0) return false;
  int status = 0;
  const pid_t rc = ::waitpid(m_pid, &status, WNOHANG);
  if (rc == 0) return true;
  m_exit = rc == m_pid ? toExitStatus(status) : ExitStatus{};
  if (m_pidFd >= 0) {
    ::close(m_pidFd);
    m_pidFd = -1;
  }
  return false;
}

std::optional<ExitStatus> Process::waitForExit(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (running()) {
    const int left = remainingMs(deadline);
    if (left <= 0) return std::nullopt;
    if (m_outFd >= 0) {
      pump(std::chrono::milliseconds{std::min(left, 50)});  // keep its pipe from filling up
      continue;
    }
    if (m_pidFd >= 0) {
      pollfd pfd{m_pidFd, POLLIN, 0};
      ::poll(&pfd, 1, left);
    } else {
      ::usleep(5000);  // no pidfd (very old kernel): poll the exit
    }
  }
  return m_exit;
}

bool Process::signal(int signalNumber) noexcept {
  if (m_pid <= 0 || m_exit) return false;
  return ::kill(m_pid, signalNumber) == 0;
}

void Process::pump(std::chrono::milliseconds timeout) {
  if (m_outFd < 0) return;
  pollfd pfd{m_outFd, POLLIN, 0};
  if (::poll(&pfd, 1, static_cast<int>(timeout.count())) <= 0) return;
  char chunk[4096];
  const ssize_t got = ::read(m_outFd, chunk, sizeof(chunk));
  if (got <= 0) {
    ::close(m_outFd);
    m_outFd = -1;
    return;
  }
  m_buffer.append(chunk, static_cast<std::size_t>(got));
  m_captured.append(chunk, static_cast<std::size_t>(got));
  if (m_logFd >= 0) {
    [[maybe_unused]] const auto written = ::write(m_logFd, chunk, static_cast<std::size_t>(got));
  }
}

std::optional<std::string> Process::readLine(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    if (const auto newline = m_buffer.find('\n'); newline != std::string::npos) {
      std::string line = m_buffer.substr(0, newline);
      m_buffer.erase(0, newline + 1);
      return line;
    }
    const int left = remainingMs(deadline);
    if (left <= 0 || m_outFd < 0) return std::nullopt;
    pump(std::chrono::milliseconds{left});
  }
}

std::optional<std::string> Process::waitForLine(std::string_view text, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    auto line = readLine(std::chrono::milliseconds{remainingMs(deadline)});
    if (!line) return std::nullopt;
    if (line->find(text) != std::string::npos) return line;
  }
}

std::string Process::output() const {
  if (m_spec.captureOutput) return m_captured;
  return readWholeFile(m_logPath);
}

// ---- Harness ---------------------------------------------------------------------------

Harness::Harness() {
  static std::atomic<unsigned> instances{0};
  const unsigned number = instances.fetch_add(1);
  const char* root = std::getenv("OPENVCU_HARNESS_LOGS");
  const std::string logRoot = root != nullptr ? root : OPENVCU_HARNESS_LOG_ROOT;
  m_logDirectory =
      logRoot + "/" + sanitize(g_testName, 80) + "-" + std::to_string(::getpid()) + "-" + std::to_string(number);
  m_runDirectory = "/tmp/openvcu-harness-" + std::to_string(::getpid()) + "-" + std::to_string(number);
  std::error_code ignored;
  fs::remove_all(m_logDirectory, ignored);
  fs::create_directories(m_logDirectory, ignored);
  fs::create_directories(m_runDirectory, ignored);

  m_notifyPath = m_runDirectory + "/notify";
  m_notifyFd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  const int on = 1;
  ::setsockopt(m_notifyFd, SOL_SOCKET, SO_PASSCRED, &on, sizeof(on));  // the sender's pid on every datagram
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, m_notifyPath.c_str(), sizeof(address.sun_path) - 1);
  if (::bind(m_notifyFd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    appendTranscript("harness: cannot bind the notify socket " + m_notifyPath + ": " + std::strerror(errno) + "\n");
  }
}

Harness::~Harness() {
  for (auto it = m_processes.rbegin(); it != m_processes.rend(); ++it) {
    if (it->get() != m_roudi && (*it)->running()) stop(**it);
  }
  // Stopping RouDi SIGTERMs its registered clients: if this test process registered, leave
  // RouDi to the PID namespace (it ends with the test process).
  if (m_roudi != nullptr && m_roudi->running() && !ipc::Runtime::initialized()) stop(*m_roudi);
  if (m_notifyFd >= 0) ::close(m_notifyFd);
  std::error_code ignored;
  fs::remove_all(m_runDirectory, ignored);
  if (currentTestFailed() || std::uncaught_exceptions() > 0) {
    printLogs();
  } else {
    m_processes.clear();
    fs::remove_all(m_logDirectory, ignored);
  }
}

std::string Harness::nextLogName(const std::string& name) {
  return m_logDirectory + "/" + std::to_string(++m_counter) + "-" + sanitize(name, 40);
}

void Harness::appendTranscript(const std::string& text) const {
  std::ofstream(m_logDirectory + "/transcript.log", std::ios::app) << text;
}

Result<Process*> Harness::spawn(ProcessSpec spec, bool withNotify, const std::string& logPath) {
  const int logFd = ::open(logPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (logFd < 0) return Error{"cannot create " + logPath + ": " + std::strerror(errno)};
  int pipeFds[2] = {-1, -1};
  if (spec.captureOutput && ::pipe2(pipeFds, O_CLOEXEC) != 0) {
    ::close(logFd);
    return Error{std::string("pipe failed: ") + std::strerror(errno)};
  }
  const int childOut = spec.captureOutput ? pipeFds[1] : logFd;
  auto spawned =
      spawnProcess(spec.argv, childEnvironment(spec.environment, withNotify ? m_notifyPath : ""), childOut, childOut);
  if (spec.captureOutput) ::close(pipeFds[1]);
  if (!spawned) {
    ::close(logFd);
    if (pipeFds[0] >= 0) ::close(pipeFds[0]);
    return spawned.error();
  }
  auto process = std::unique_ptr<Process>(new Process(std::move(spec), logPath));
  process->m_pid = spawned->pid;
  process->m_pidFd = spawned->pidFd;
  if (process->m_spec.captureOutput) {
    process->m_outFd = pipeFds[0];
    process->m_logFd = logFd;
  } else {
    ::close(logFd);
  }
  appendTranscript("started " + process->name() + " (pid " + std::to_string(process->pid()) +
                   "): " + joinArgv(process->spec().argv) + "\n");
  m_processes.push_back(std::move(process));
  return m_processes.back().get();
}

Status Harness::startRoudi(const std::string& configPath) {
  if (!isolated()) return Error{NOT_ISOLATED};
  const std::string config =
      configPath.empty() ? std::string(OPENVCU_HARNESS_SOURCE_DIR) + "/config/iceoryx/roudi.toml" : configPath;
  // The stack's launcher (group openvcu, no group-root ACL: config/iceoryx/iox-roudi.sh).
  const std::string launcher = std::string(OPENVCU_HARNESS_SOURCE_DIR) + "/config/iceoryx/iox-roudi.sh";
  ProcessSpec spec{.name = "iox-roudi", .argv = {launcher, "-c", config, "-l", "warning"}};
  auto started = spawn(std::move(spec), false, nextLogName("iox-roudi") + ".log");
  if (!started) return started.error();
  m_roudi = *started;
  // RouDi does not speak the notify protocol: its socket accepting connections is its readiness.
  const auto deadline = std::chrono::steady_clock::now() + READY_TIMEOUT;
  while (!ipc::Runtime::waitForRoudi(std::chrono::milliseconds{20})) {
    if (!m_roudi->running()) {
      return Error{"iox-roudi exited (" + m_roudi->exitStatus()->toString() + ") before accepting clients:\n" +
                   readWholeFile(m_roudi->logPath(), 4000)};
    }
    if (std::chrono::steady_clock::now() >= deadline) return Error{"iox-roudi did not accept clients in time"};
  }
  return {};
}

Result<Process*> Harness::start(ProcessSpec spec, std::chrono::milliseconds readyTimeout) {
  const bool notify = spec.notifyReadiness;
  const std::string name =
      spec.name.empty() ? fs::path(spec.argv.empty() ? "process" : spec.argv[0]).filename().string() : spec.name;
  spec.name = name;
  auto started = spawn(std::move(spec), notify, nextLogName(name) + ".log");
  if (!started) return started.error();
  Process* process = *started;
  if (!notify) return process;
  if (waitForNotify(*process, "READY=1", readyTimeout)) return process;
  // A captured process's output reaches its log file only as it is read: drain it first.
  for (int chunk = 0; chunk < 64 && process->m_outFd >= 0; ++chunk) process->pump(std::chrono::milliseconds{100});
  if (!process->running()) {
    return Error{name + " (pid " + std::to_string(process->pid()) + ") exited with " +
                 process->exitStatus()->toString() + " before READY=1:\n" + readWholeFile(process->logPath(), 4000)};
  }
  return Error{name + " (pid " + std::to_string(process->pid()) + ") sent no READY=1 within " +
               std::to_string(readyTimeout.count()) + " ms:\n" + readWholeFile(process->logPath(), 4000)};
}

void Harness::receiveNotifications(std::chrono::milliseconds timeout, int extraFd) {
  pollfd pfds[2] = {{m_notifyFd, POLLIN, 0}, {extraFd, POLLIN, 0}};
  if (::poll(pfds, extraFd >= 0 ? 2 : 1, static_cast<int>(timeout.count())) <= 0) return;
  std::ofstream notifyLog(m_logDirectory + "/notify.log", std::ios::app);
  while (true) {
    char payload[4096];
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(ucred))];
    iovec vector{payload, sizeof(payload)};
    msghdr message{};
    message.msg_iov = &vector;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof(control);
    const ssize_t got = ::recvmsg(m_notifyFd, &message, MSG_DONTWAIT);
    if (got < 0) return;  // EAGAIN: all read
    pid_t sender = -1;
    for (cmsghdr* header = CMSG_FIRSTHDR(&message); header != nullptr; header = CMSG_NXTHDR(&message, header)) {
      if (header->cmsg_level == SOL_SOCKET && header->cmsg_type == SCM_CREDENTIALS) {
        ucred credentials{};
        std::memcpy(&credentials, CMSG_DATA(header), sizeof(credentials));
        sender = credentials.pid;
      }
    }
    std::string_view text(payload, static_cast<std::size_t>(got));
    while (!text.empty()) {
      const std::size_t newline = text.find('\n');
      const std::string assignment(text.substr(0, newline));
      if (!assignment.empty()) {
        m_notifications[sender].push_back(assignment);
        notifyLog << "pid " << sender << ": " << assignment << '\n';
      }
      text = newline == std::string_view::npos ? std::string_view{} : text.substr(newline + 1);
    }
  }
}

bool Harness::waitForNotify(const Process& process, std::string_view assignment, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  auto received = [&] {
    const auto found = m_notifications.find(process.pid());
    return found != m_notifications.end() &&
           std::find(found->second.begin(), found->second.end(), assignment) != found->second.end();
  };
  auto& mutableProcess = const_cast<Process&>(process);
  while (true) {
    receiveNotifications(std::chrono::milliseconds{0});
    if (received()) return true;
    if (!mutableProcess.running()) {
      receiveNotifications(std::chrono::milliseconds{0});  // it may have sent just before exiting
      return received();
    }
    const int left = remainingMs(deadline);
    if (left <= 0) return false;
    // Wakes on a datagram or on the process's exit (its pidfd), whichever comes first.
    receiveNotifications(std::chrono::milliseconds{left}, mutableProcess.m_pidFd);
  }
}

std::vector<std::string> Harness::notifications(const Process& process) {
  receiveNotifications(std::chrono::milliseconds{0});
  const auto found = m_notifications.find(process.pid());
  return found == m_notifications.end() ? std::vector<std::string>{} : found->second;
}

CommandResult Harness::run(std::vector<std::string> argv, std::chrono::milliseconds timeout,
                           std::vector<std::string> environment) {
  CommandResult result;
  result.argv = argv;
  std::string name = argv.empty() ? "command" : fs::path(argv[0]).filename().string();
  for (std::size_t i = 1; i < argv.size() && i < 3; ++i) {
    if (!argv[i].starts_with("-")) name += "-" + argv[i];
  }
  const std::string base = nextLogName(name);
  const int outFd = ::open((base + ".out").c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const int errFd = ::open((base + ".err").c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const auto started = std::chrono::steady_clock::now();
  auto spawned = spawnProcess(argv, childEnvironment(environment, ""), outFd, errFd);
  ::close(outFd);
  ::close(errFd);
  if (!spawned) {
    result.err = spawned.error().toString();
    return result;
  }
  int status = 0;
  const auto deadline = started + timeout;
  bool exited = false;
  while (!exited) {
    const pid_t rc = ::waitpid(spawned->pid, &status, WNOHANG);
    if (rc == spawned->pid) {
      exited = true;
      break;
    }
    const int left = remainingMs(deadline);
    if (left <= 0) break;
    pollfd pfd{spawned->pidFd, POLLIN, 0};
    if (spawned->pidFd >= 0) {
      ::poll(&pfd, 1, left);
    } else {
      ::usleep(5000);
    }
  }
  if (exited) {
    result.status = toExitStatus(status);
  } else {
    ::kill(spawned->pid, SIGKILL);
    ::waitpid(spawned->pid, &status, 0);
  }
  if (spawned->pidFd >= 0) ::close(spawned->pidFd);
  result.out = readWholeFile(base + ".out");
  result.err = readWholeFile(base + ".err");
  const auto elapsedMs =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - started).count();
  appendTranscript(result.describe() + "(" + std::to_string(elapsedMs) + " ms)\n\n");
  return result;
}

std::optional<ExitStatus> Harness::stop(Process& process, std::chrono::milliseconds timeout) {
  if (process.running()) {
    process.signal(SIGTERM);
    if (!process.waitForExit(timeout)) {
      appendTranscript(process.name() + " (pid " + std::to_string(process.pid()) + ") ignored SIGTERM: SIGKILL\n");
      process.signal(SIGKILL);
      process.waitForExit(STOP_TIMEOUT);
    }
  }
  if (process.exitStatus()) {
    appendTranscript("stopped " + process.name() + " (pid " + std::to_string(process.pid()) +
                     "): " + process.exitStatus()->toString() + "\n");
  }
  return process.exitStatus();
}

void Harness::printLogs() const {
  std::error_code ignored;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(m_logDirectory, ignored)) files.push_back(entry.path());
  std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
    // "<n>-name" numerically, then the rest (transcript, notify) at the end
    const auto number = [](const fs::path& p) { return std::atoi(p.filename().c_str()); };
    const int na = number(a) == 0 ? INT32_MAX : number(a);
    const int nb = number(b) == 0 ? INT32_MAX : number(b);
    return na != nb ? na < nb : a < b;
  });
  std::cerr << "===== harness logs (" << m_logDirectory << ") =====\n";
  for (const fs::path& file : files) {
    std::cerr << "----- " << file.filename().string() << " -----\n" << readWholeFile(file.string(), 64 * 1024);
  }
  std::cerr << "===== end of harness logs =====" << std::endl;
}

}  // namespace openvcu::harness
