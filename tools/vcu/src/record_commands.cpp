// `vcu record` and `vcu replay`. Each command's description and footer are its manual
// (`vcu record --help`); README.md explains the decisions behind them.
#include "record_commands.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "cli_checks.hpp"
#include "diagnostics.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/can/log_writer.hpp"
#include "openvcu/can_links/open_link.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/ipc/waiter.hpp"
#include "stop_signal.hpp"

extern char** environ;

namespace openvcu::cli {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

/// The LCM log's name in the folder.
constexpr const char* EVENTS_FILE = "events.lcmlog";
/// The bus logs' extension: DIR/<bus>.log.
constexpr std::string_view LOG_EXTENSION = ".log";
/// The longest either command sleeps between looks at its stop flag (SIGINT, SIGTERM).
constexpr auto STOP_TICK = 200ms;
/// How long lcm-logger gets to create its file (readiness) and to end after SIGINT,
/// then after SIGTERM, before SIGKILL.
constexpr auto LOGGER_START_TIMEOUT = 3s;
constexpr auto LOGGER_STOP_TIMEOUT = 3s;
constexpr auto LOGGER_POLL_STEP = 10ms;
/// Bus logs are flushed to disk at least this often (a crash loses less).
constexpr auto FLUSH_INTERVAL = 500ms;
/// Whole lines wait in a buffer of this size per bus before they reach the file.
constexpr std::size_t LINE_BUFFER_BYTES = 64 * 1024;
/// Frames taken from a link in one receive() call; each such batch is put in time order.
constexpr std::size_t RECEIVE_BATCH = 64;
/// A frame refused as Busy (transmit queue or mempool full) is retried this long.
constexpr auto BUSY_RETRY_TIME = 100ms;
constexpr auto BUSY_RETRY_STEP = 1ms;
/// Bounds that keep the time arithmetic finite: --for up to ~31 years, --speed down to 1/1000.
constexpr double MAX_SECONDS = 1e9;
constexpr double MIN_SPEED = 1e-3;
constexpr double MAX_OFFSET_NS = 1e18;  ///< a log spanning more (~31 years) waits no longer
/// Malformed lines reported one by one before `vcu replay` only counts them.
constexpr std::uint64_t MAX_REPORTED_LOG_ERRORS = 20;

constexpr const char* CONFIG_NOTE =
    "The stack: --config FILE or $OPENVCU_CONFIG (required: there is no default), and\n"
    "--instance for a stack started with another instance name.\n";

constexpr const char* RECORD_DESCRIPTION = "Record every bus of a running stack and its LCM events into a folder";
constexpr const char* RECORD_FOOTER =
    "Records into DIR (created when missing):\n"
    "  DIR/<bus>.log      every frame of each configured bus, one candump -L line per\n"
    "                     frame, the bus name as the interface (what candump -L writes\n"
    "                     and canplayer, python-can, 'vcu dbc decode' and 'vcu replay'\n"
    "                     read):\n"
    "                       (1700000000.123456) vehicle 18FEF121#0102030405060708\n"
    "                       (1700000000.124000) body 123##1DEADBEEF     (CAN FD, BRS)\n"
    "  DIR/events.lcmlog  the LCM events of the session (heartbeats, faults, FSM\n"
    "                     transitions) on the configuration's LCM URL, written by\n"
    "                     lcm-logger (Debian package lcm), started as a child process\n"
    "                     from an argument list (no shell) and ended by its pid with\n"
    "                     SIGINT when the recording stops. Read it with lcm-logplayer\n"
    "                     or lcm-spy.\n"
    "Each bus is opened with its configured link (sim:NAME, socketcan:IFACE) as one more\n"
    "node that only listens; replay: buses are skipped (they are logs already). The time\n"
    "of a frame is its kernel/hardware stamp (socketcan) or the sender's clock at send\n"
    "(sim). Time never goes back within a log: the frames taken together are written in\n"
    "time order, and a frame stamped before the line written last (another sender's frame\n"
    "that overtook it) gets that line's time; the summary counts such frames and says by\n"
    "how much at most. Lines reach a log whole (a buffer of whole lines, written at least\n"
    "every 0.5 s), so a reader or a recorder killed by SIGKILL never leaves half a line.\n"
    "A line 'recording ...' on stderr says every link and lcm-logger are ready.\n"
    "Runs until Ctrl-C (SIGINT), SIGTERM or --for SECONDS, then prints a summary: frames\n"
    "per bus and the size of the events file. SIGINT and SIGTERM end it even when the\n"
    "parent started it with them blocked (the recorder unblocks them for itself and\n"
    "lcm-logger). Existing logs in DIR are not overwritten without --force.\n"
    "Needs iox-roudi for sim: buses; registers as vcu-record-<pid>.\n"
    "\n"
    "Examples:\n"
    "  vcu record drive1 --config config/hhea/vehicle.json\n"
    "  vcu record /tmp/session --for 60 --force\n"
    "Exit: 0 recorded and every file written, 1 configuration error, a link that cannot\n"
    "be opened, lcm-logger missing or failing, a write error, frames lost (the recorder\n"
    "fell behind), existing files without --force; 2 usage error.\n";

constexpr const char* REPLAY_DESCRIPTION = "Play a recorded folder back onto the configured buses with its timing";
constexpr const char* REPLAY_FOOTER =
    "Plays every DIR/*.log (candump -L, as 'vcu record' writes them; candump's other\n"
    "formats too) onto the buses of the configuration: the channel of each line\n"
    "('vehicle' in '(1700000000.123456) vehicle 123#11') names the bus. Frames of a\n"
    "channel that is not a configured bus are reported and skipped, as are CAN FD frames\n"
    "for a classic bus and replay: buses.\n"
    "Timing as canplayer: the files are merged by time; frame i goes out at\n"
    "T + (t_i - t_0) / SPEED, T the start and t_0 the first frame's time, an absolute\n"
    "deadline on CLOCK_MONOTONIC, so waiting never accumulates drift. A frame whose time\n"
    "goes back, or that has none, goes out at once. --speed 2 plays twice as fast,\n"
    "--speed 0 as fast as possible. --loop starts again at the end (a new time base)\n"
    "until Ctrl-C or SIGTERM.\n"
    "Every file is read and checked first: a malformed line is reported as\n"
    "file:line:column: reason and nothing is played. Each bus's link sends as one more\n"
    "node (a sim: link first waits until RouDi has connected it to the other nodes).\n"
    "DIR/events.lcmlog is not played (lcm-logplayer does that).\n"
    "Needs iox-roudi for sim: buses; registers as vcu-replay-<pid>.\n"
    "\n"
    "Examples:\n"
    "  vcu replay drive1 --config config/hhea/vehicle.json\n"
    "  vcu replay drive1 --speed 0 --loop\n"
    "Exit: 0 every frame for a configured bus sent (or stopped by a signal), 1 missing\n"
    "DIR, no log in it, malformed lines, configuration error, a link error or a refused\n"
    "frame; 2 usage error.\n";

// ---- shared -----------------------------------------------------------------------------

std::string plural(std::uint64_t count, std::string_view noun) {
  return std::to_string(count) + " " + std::string(noun) + (count == 1 ? "" : "s");
}

/// Registers with iox-roudi as "vcu-<command>-<pid>": unique per invocation.
bool initRuntime(std::string_view command, Sink& err) {
  const std::string name = "vcu-" + std::string(command) + "-" + std::to_string(::getpid());
  if (const Status initResult = ipc::Runtime::init(name); !initResult) {
    reportError(err, initResult.error().message);
    return false;
  }
  return true;
}

/// An error about a whole file or folder: "DIR: error: no such directory".
Error fileError(std::string message, const std::string& path) {
  return Error{std::move(message), Location{path, 0, 0, {}}};
}

std::chrono::steady_clock::duration secondsToDuration(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

// ---- record: lcm-logger -----------------------------------------------------------------

/// lcm-logger as a child process, started from an argument list and ended by its pid.
class LoggerProcess {
 public:
  LoggerProcess() = default;
  LoggerProcess(const LoggerProcess&) = delete;
  LoggerProcess& operator=(const LoggerProcess&) = delete;
  /// A logger still running here (an early return) gets SIGTERM and is reaped.
  ~LoggerProcess() {
    if (running()) (void)stop();
  }

  /// Starts `program -q -f -l URL FILE` with SIGINT and SIGTERM at their defaults.
  Status start(const std::string& program, const std::string& url, const std::string& file) {
    std::vector<std::string> argv{program, "--quiet", "--force", "--lcm-url=" + url, file};
    const int rc = spawnProcess(argv, {SIGINT, SIGTERM}, true, &m_pid);
    if (rc != 0) {
      m_pid = -1;
      return Error{"cannot start " + program + ": " + std::strerror(rc) +
                   (rc == ENOENT ? " (install the Debian package lcm)" : "")};
    }
    return {};
  }

  [[nodiscard]] pid_t pid() const noexcept { return m_pid; }

  /// true while the child has not exited (reaps it when it has).
  bool running() {
    if (m_pid < 0 || m_status) return false;
    int status = 0;
    const pid_t reaped = ::waitpid(m_pid, &status, WNOHANG);
    if (reaped == m_pid) {
      m_status = status;
      return false;
    }
    return reaped == 0;
  }

  /// How it ended, "exit code 1", "signal 9"; empty while running.
  [[nodiscard]] std::optional<std::string> endText() const {
    if (!m_status) return std::nullopt;
    if (WIFEXITED(*m_status)) return "exit code " + std::to_string(WEXITSTATUS(*m_status));
    return "signal " + std::to_string(WTERMSIG(*m_status));
  }

  /// true when it ended as asked: exit code 0, or killed by SIGINT/SIGTERM.
  [[nodiscard]] bool endedCleanly() const noexcept {
    if (!m_status) return false;
    if (WIFEXITED(*m_status)) return WEXITSTATUS(*m_status) == 0;
    return WTERMSIG(*m_status) == SIGINT || WTERMSIG(*m_status) == SIGTERM;
  }

  /// SIGINT (lcm-logger flushes and closes its file), then SIGTERM, then SIGKILL, each
  /// after LOGGER_STOP_TIMEOUT; reaps. false when it needed SIGKILL.
  bool stop() {
    for (const int signalNumber : {SIGINT, SIGTERM}) {
      if (!running()) return true;
      ::kill(m_pid, signalNumber);
      if (waitForExit(LOGGER_STOP_TIMEOUT)) return true;
    }
    if (!running()) return true;
    ::kill(m_pid, SIGKILL);
    int status = 0;
    while (::waitpid(m_pid, &status, 0) < 0 && errno == EINTR) {
    }
    m_status = status;
    return false;
  }

 private:
  bool waitForExit(std::chrono::steady_clock::duration timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (running()) {
      if (std::chrono::steady_clock::now() >= end) return false;
      std::this_thread::sleep_for(LOGGER_POLL_STEP);
    }
    return true;
  }

  pid_t m_pid{-1};
  std::optional<int> m_status;  ///< waitpid status once reaped
};

// ---- record: links ----------------------------------------------------------------------

/// A bus log that only ever receives whole lines: candump -L lines collect in a buffer
/// allocated once and reach the file with write(2) when it is nearly full or flush() is
/// called, so a reader or a recorder killed by SIGKILL never leaves half a line.
/// @note restricted thread-safe: one thread at a time; append() allocates nothing.
class LineFile {
 public:
  LineFile() = default;
  LineFile(LineFile&& other) noexcept
      : m_fd(std::exchange(other.m_fd, -1)),
        m_buffer(std::move(other.m_buffer)),
        m_used(std::exchange(other.m_used, 0)),
        m_writeErrno(other.m_writeErrno) {}
  LineFile& operator=(LineFile&&) = delete;
  LineFile(const LineFile&) = delete;
  LineFile& operator=(const LineFile&) = delete;
  ~LineFile() {
    if (m_fd >= 0) ::close(m_fd);
  }

  /// Creates or truncates `path`; the errno when it cannot.
  int open(const std::string& path) {
    m_fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (m_fd < 0) return errno;
    m_buffer = std::make_unique<char[]>(LINE_BUFFER_BYTES);
    return 0;
  }

  /// Appends the frame's candump -L line and its line ending; writes the buffered lines
  /// first when the longest line might not fit.
  void append(const can::Frame& frame, std::string_view channel) noexcept {
    if (LINE_BUFFER_BYTES - m_used < can::candumpLMaxLength(channel.size()) + 1) flush();
    const std::size_t length =
        can::formatCandumpL(frame, channel, std::span<char>(m_buffer.get() + m_used, LINE_BUFFER_BYTES - m_used - 1));
    if (length == 0) return;  // cannot happen: the room was checked above
    m_used += length;
    m_buffer[m_used++] = '\n';
  }

  /// Writes the buffered lines; after a failed write the lines are dropped and the first
  /// errno is kept.
  void flush() noexcept {
    std::size_t done = 0;
    while (done < m_used && m_writeErrno == 0) {
      const ssize_t written = ::write(m_fd, m_buffer.get() + done, m_used - done);
      if (written < 0) {
        if (errno != EINTR) m_writeErrno = errno;
        continue;
      }
      done += static_cast<std::size_t>(written);
    }
    m_used = 0;
  }

  /// Flushes and closes; the errno of the first failure, 0 when everything was written.
  int close() noexcept {
    flush();
    if (m_fd >= 0 && ::close(m_fd) != 0 && m_writeErrno == 0) m_writeErrno = errno;
    m_fd = -1;
    return m_writeErrno;
  }

 private:
  int m_fd{-1};
  std::unique_ptr<char[]> m_buffer;
  std::size_t m_used{};
  int m_writeErrno{};  ///< errno of the first failed write, 0 while none failed
};

/// Keeps a log's time from going back. Frames are stamped by their sender (sim) or the
/// kernel (socketcan); frames of different senders can reach the recorder in another
/// order than their stamps (one stamps, another stamps and publishes first). The time
/// written is the frame's stamp, or the time of the line written last when the stamp is
/// older (the log's high-water mark): such frames are counted with the largest shift.
/// @note thread-free; noexcept and allocation-free.
class MonotonicStamps {
 public:
  /// The time to write for a frame stamped `stampNs`.
  std::int64_t next(std::int64_t stampNs) noexcept {
    if (stampNs < m_lastNs) {
      ++m_raised;
      m_maxRaiseNs = std::max(m_maxRaiseNs, m_lastNs - stampNs);
      return m_lastNs;
    }
    m_lastNs = stampNs;
    return stampNs;
  }
  [[nodiscard]] std::uint64_t raised() const noexcept { return m_raised; }
  [[nodiscard]] std::int64_t maxRaiseNs() const noexcept { return m_maxRaiseNs; }

 private:
  std::int64_t m_lastNs{std::numeric_limits<std::int64_t>::min()};
  std::uint64_t m_raised{};
  std::int64_t m_maxRaiseNs{};
};

/// Orders a received batch by stamp (insertion sort: stable, no allocation, linear for
/// the nearly sorted batches a bus delivers).
void sortByStamp(std::span<can::ReceivedFrame> batch) noexcept {
  for (std::size_t i = 1; i < batch.size(); ++i) {
    const can::ReceivedFrame item = batch[i];
    std::size_t j = i;
    for (; j > 0 && batch[j - 1].frame.timestampNs > item.frame.timestampNs; --j) batch[j] = batch[j - 1];
    batch[j] = item;
  }
}

/// One recorded bus: its link and its log file.
struct RecordedBus {
  const config::BusConfig* bus{nullptr};
  std::unique_ptr<can::Link> link;
  std::string path;
  LineFile file;
  MonotonicStamps stamps;
  std::uint64_t frames{};
  std::uint64_t events{};
};

/// SIGINT and SIGTERM unblocked in this thread while it lives, the previous mask back
/// afterwards. A parent may start the recorder with them blocked (vcu-hmi reads them
/// through a signalfd, and a child inherits the mask); the StopSignalScope's handler
/// takes them from here on, and lcm-logger, started after it, inherits the open mask.
class UnblockedStopSignals {
 public:
  UnblockedStopSignals() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    ::pthread_sigmask(SIG_UNBLOCK, &set, &m_previous);
  }
  UnblockedStopSignals(const UnblockedStopSignals&) = delete;
  UnblockedStopSignals& operator=(const UnblockedStopSignals&) = delete;
  ~UnblockedStopSignals() { ::pthread_sigmask(SIG_SETMASK, &m_previous, nullptr); }

 private:
  sigset_t m_previous{};
};

/// Blocks until a link has something to do or the deadline: an ipc::Waiter when the
/// iceoryx runtime is up (sim links have no fd), poll() on the fds otherwise.
class LinkWaiter {
 public:
  Status attach(std::vector<RecordedBus>& buses) {
    if (ipc::Runtime::initialized()) {
      auto waiterResult = ipc::Waiter::create();
      if (!waiterResult) return waiterResult.error();
      m_waiter.emplace(std::move(*waiterResult));
    }
    for (std::size_t i = 0; i < buses.size(); ++i) {
      const can::WaitHandle handle = buses[i].link->waitHandle();
      if (m_waiter) {
        if (const Status attached = m_waiter->attachLink(handle, i); !attached) return attached.error();
      } else if (handle.source != nullptr) {
        return Error{buses[i].link->name() + ": needs the iceoryx runtime"};
      } else {
        m_fds.push_back(pollfd{handle.fd, POLLIN, 0});
      }
    }
    return {};
  }

  void waitUntil(std::chrono::steady_clock::time_point deadline) {
    if (m_waiter) {
      (void)m_waiter->waitUntil(deadline);
      return;
    }
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return;
    (void)::poll(m_fds.data(), m_fds.size(), static_cast<int>(left.count()));
  }

 private:
  std::optional<ipc::Waiter> m_waiter;
  std::vector<pollfd> m_fds;
};

/// Takes everything the bus's link has and appends it to its log in time order. Events
/// are counted.
/// @note allocation-free.
void drain(RecordedBus& recorded) noexcept {
  std::array<can::ReceivedFrame, RECEIVE_BATCH> batch{};
  for (;;) {
    const std::size_t count = recorded.link->receive(batch);
    const std::span<can::ReceivedFrame> received(batch.data(), count);
    for (can::ReceivedFrame& item : received) {
      if (item.frame.timestampNs == 0) item.frame.timestampNs = clock::realtimeNs();
    }
    sortByStamp(received);
    for (can::ReceivedFrame& item : received) {
      item.frame.timestampNs = recorded.stamps.next(item.frame.timestampNs);
      recorded.file.append(item.frame, recorded.bus->name);
    }
    recorded.frames += count;
    if (count < batch.size()) break;
  }
  while (recorded.link->nextEvent()) ++recorded.events;
}

/// Checks DIR and the files a recording would replace. Reports and returns false when not usable.
bool prepareDirectory(const RecordOptions& options, const std::vector<const config::BusConfig*>& buses, Sink& err) {
  std::error_code error;
  const fs::path directory(options.directory);
  if (fs::exists(directory, error) && !fs::is_directory(directory, error)) {
    report(err, fileError("not a directory", options.directory));
    return false;
  }
  fs::create_directories(directory, error);
  if (error) {
    report(err, fileError("cannot create the folder: " + error.message(), options.directory));
    return false;
  }
  if (options.force) return true;
  std::vector<std::string> existing;
  for (const config::BusConfig* bus : buses) {
    const fs::path path = directory / (bus->name + std::string(LOG_EXTENSION));
    if (fs::exists(path, error)) existing.push_back(path.string());
  }
  if (fs::exists(directory / EVENTS_FILE, error)) existing.push_back((directory / EVENTS_FILE).string());
  if (existing.empty()) return true;
  std::string list;
  for (const std::string& path : existing) list += (list.empty() ? "" : ", ") + path;
  reportError(err, "a recording is already there (" + list + "): --force overwrites it, or choose another folder");
  return false;
}

}  // namespace

ExitCode runRecord(const RecordOptions& options, Streams streams) {
  if (!std::isfinite(options.forSeconds) || options.forSeconds < 0 || options.forSeconds > MAX_SECONDS) {
    reportError(streams.err, "--for " + formatNumber(options.forSeconds) + ": must be between 0 and " +
                                 formatNumber(MAX_SECONDS) + " seconds");
    return ExitCode::Usage;
  }
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::VehicleConfig& config = maybeStack->config;

  std::vector<const config::BusConfig*> buses;
  bool anySim = false;
  for (const config::BusConfig& bus : config.buses) {
    if (bus.link.kind == config::LinkKind::Replay) {
      streams.err.write("vcu: note: bus '" + bus.name + "' is " + bus.link.toString() +
                        ": not recorded (it is a log already)\n");
      continue;
    }
    anySim = anySim || bus.link.kind == config::LinkKind::Sim;
    buses.push_back(&bus);
  }
  if (buses.empty()) {
    reportError(streams.err, config.path + " has no bus to record (every bus is a replay: link)");
    return ExitCode::Failure;
  }
  if (!prepareDirectory(options, buses, streams.err)) return ExitCode::Failure;
  if (anySim && !initRuntime("record", streams.err)) return ExitCode::Failure;

  std::vector<RecordedBus> recorded;
  recorded.reserve(buses.size());  // the waiter refers to the links by index; no reallocation
  for (const config::BusConfig* bus : buses) {
    RecordedBus item;
    item.bus = bus;
    auto linkResult = can::openLink(bus->link.kind, bus->link.target, bus->linkOptions());
    if (!linkResult) {
      reportError(streams.err, linkResult.error().message);
      return ExitCode::Failure;
    }
    item.link = std::move(*linkResult);
    item.path = (fs::path(options.directory) / (bus->name + std::string(LOG_EXTENSION))).string();
    if (const int openErrno = item.file.open(item.path); openErrno != 0) {
      report(streams.err, fileError(std::string("cannot create: ") + std::strerror(openErrno), item.path));
      return ExitCode::Failure;
    }
    recorded.push_back(std::move(item));
  }
  LinkWaiter waiter;
  if (const Status attached = waiter.attach(recorded); !attached) {
    reportError(streams.err, attached.error().message);
    return ExitCode::Failure;
  }

  const StopSignalScope stopSignals;     // before lcm-logger: a Ctrl-C from now on ends the recording cleanly
  const UnblockedStopSignals unblocked;  // after the handler: a signal pending since start stops it cleanly
  const std::string eventsPath = (fs::path(options.directory) / EVENTS_FILE).string();
  std::error_code ignored;
  fs::remove(eventsPath, ignored);  // its appearance is lcm-logger's readiness signal
  LoggerProcess logger;
  if (const Status started = logger.start(options.lcmLogger, config.lcmUrl, eventsPath); !started) {
    reportError(streams.err, started.error().message);
    return ExitCode::Failure;
  }
  const auto loggerDeadline = std::chrono::steady_clock::now() + LOGGER_START_TIMEOUT;
  while (!fs::exists(eventsPath, ignored)) {
    if (!logger.running()) {
      reportError(streams.err, options.lcmLogger + " ended at start with " + logger.endText().value_or("?") +
                                   " (LCM URL " + config.lcmUrl + ")");
      return ExitCode::Failure;
    }
    if (stopRequested()) {
      reportError(streams.err, "stopped before the recording began");
      return ExitCode::Failure;  // ~LoggerProcess ends lcm-logger
    }
    if (std::chrono::steady_clock::now() >= loggerDeadline) {
      reportError(streams.err, options.lcmLogger + " did not create " + eventsPath + " within " +
                                   std::to_string(std::chrono::milliseconds(LOGGER_START_TIMEOUT).count()) + " ms");
      return ExitCode::Failure;  // ~LoggerProcess ends it
    }
    std::this_thread::sleep_for(LOGGER_POLL_STEP);
  }

  std::string names;
  for (const RecordedBus& item : recorded) {
    names += (names.empty() ? "" : ", ") + item.bus->name + " (" + item.link->name() + ")";
  }
  streams.err.write("recording " + names + " and the LCM events (" + config.lcmUrl + ", " + options.lcmLogger +
                    " pid " + std::to_string(logger.pid()) + ") into " + options.directory +
                    (options.forSeconds > 0 ? " for " + formatNumber(options.forSeconds) + " s" : "") +
                    " (Ctrl-C to stop)\n");
  streams.err.flush();

  const auto start = std::chrono::steady_clock::now();
  const std::optional<std::chrono::steady_clock::time_point> maybeEnd =
      options.forSeconds > 0 ? std::optional(start + secondsToDuration(options.forSeconds)) : std::nullopt;
  auto nextFlush = start + FLUSH_INTERVAL;
  bool loggerDiedEarly = false;
  for (;;) {
    for (RecordedBus& item : recorded) drain(item);
    const auto now = std::chrono::steady_clock::now();
    if (stopRequested() || (maybeEnd && now >= *maybeEnd)) break;
    if (now >= nextFlush) {
      for (RecordedBus& item : recorded) item.file.flush();
      nextFlush = now + FLUSH_INTERVAL;
      if (!loggerDiedEarly && !logger.running()) {
        loggerDiedEarly = true;
        reportError(streams.err, options.lcmLogger + " ended early with " + logger.endText().value_or("?") +
                                     ": the events after this point are missing");
      }
    }
    auto wakeAt = std::min(now + STOP_TICK, nextFlush);
    if (maybeEnd) wakeAt = std::min(wakeAt, *maybeEnd);
    waiter.waitUntil(wakeAt);
  }
  const auto recordedFor = std::chrono::steady_clock::now() - start;
  for (RecordedBus& item : recorded) drain(item);  // the last frames that arrived before the stop
  const bool loggerStopped = logger.stop();

  bool ok = !loggerDiedEarly;
  if (!loggerDiedEarly && !logger.endedCleanly()) {
    reportError(streams.err, options.lcmLogger + " ended with " + logger.endText().value_or("?") +
                                 (loggerStopped ? "" : " (it ignored SIGINT and SIGTERM)"));
    ok = false;
  }
  std::string summary =
      "recorded " + formatDuration(std::chrono::nanoseconds(recordedFor).count()) + " into " + options.directory + "\n";
  for (RecordedBus& item : recorded) {
    if (const int writeErrno = item.file.close(); writeErrno != 0) {
      report(streams.err, fileError(std::string("cannot write: ") + std::strerror(writeErrno), item.path));
      ok = false;
    }
    const can::LinkStats stats = item.link->stats();
    if (stats.receiveDropped > 0) {
      reportError(streams.err, item.link->name() + ": " + plural(stats.receiveDropped, "frame") +
                                   " lost before the recorder read them (it fell behind)");
      ok = false;
    }
    summary += "  " + item.bus->name + ": " + plural(item.frames, "frame") + " -> " + item.path;
    if (item.events > 0) summary += " (" + plural(item.events, "bus event") + ", not in the log)";
    if (item.stamps.raised() > 0) {
      std::array<char, 32> shift{};
      std::snprintf(shift.data(), shift.size(), "%.3f ms", static_cast<double>(item.stamps.maxRaiseNs()) / 1e6);
      summary += " (" + plural(item.stamps.raised(), "frame") + " written up to " + shift.data() +
                 " later than stamped: another sender's frame overtook it)";
    }
    summary += "\n";
  }
  std::error_code sizeError;
  const std::uintmax_t eventsSize = fs::file_size(eventsPath, sizeError);
  if (sizeError) {
    report(streams.err, fileError("not written: " + sizeError.message(), eventsPath));
    ok = false;
  } else {
    summary += "  events: " + plural(eventsSize, "byte") + " -> " + eventsPath + "\n";
  }
  streams.out.write(summary);
  return ok ? ExitCode::Ok : ExitCode::Failure;
}

// ---- replay -----------------------------------------------------------------------------

namespace {

/// A bus of the configuration that frames are played onto.
struct PlayedBus {
  const config::BusConfig* bus{nullptr};
  std::unique_ptr<can::Link> link;
  std::uint64_t frames{};
  std::uint64_t failures{};
};

/// What the check pass found in the logs.
struct LogSurvey {
  std::vector<std::string> files;                    ///< DIR/*.log, sorted
  std::map<std::string, std::uint64_t> perChannel;   ///< frames by channel
  std::map<std::string, std::uint64_t> fdOnClassic;  ///< FD frames for a classic bus, by bus
  std::uint64_t frames{};
  std::uint64_t errors{};
};

/// Lists DIR/*.log and reads every one of them, reporting malformed lines. Empty on a
/// missing or unreadable DIR or one without logs (reported).
std::optional<LogSurvey> surveyLogs(const std::string& directory, const config::VehicleConfig& config, Sink& err) {
  std::error_code error;
  if (!fs::is_directory(directory, error)) {
    report(err, fileError(fs::exists(directory, error) ? "not a directory" : "no such directory", directory));
    return std::nullopt;
  }
  LogSurvey survey;
  for (fs::directory_iterator it(directory, error), end; !error && it != end; it.increment(error)) {
    if (it->path().extension() == LOG_EXTENSION && it->is_regular_file(error))
      survey.files.push_back(it->path().string());
  }
  if (error) {
    report(err, fileError("cannot list: " + error.message(), directory));
    return std::nullopt;
  }
  if (survey.files.empty()) {
    report(err, fileError("no *.log file (vcu record writes <bus>.log)", directory));
    return std::nullopt;
  }
  std::sort(survey.files.begin(), survey.files.end());
  for (const std::string& file : survey.files) {
    auto readerResult = can::LogReader::open(file, can::LogFormat::Candump);
    if (!readerResult) {
      report(err, readerResult.error());
      ++survey.errors;
      continue;
    }
    can::LogReader& reader = *readerResult;
    reader.setErrorHandler([&survey, &err](const Error& lineError) {
      if (survey.errors < MAX_REPORTED_LOG_ERRORS) report(err, lineError);
      ++survey.errors;
    });
    while (const auto maybeRecord = reader.next()) {
      ++survey.frames;
      ++survey.perChannel[std::string(maybeRecord->channel)];
      const config::BusConfig* bus = config.findBus(maybeRecord->channel);
      if (bus != nullptr && maybeRecord->frame.fd() && !bus->fd) ++survey.fdOnClassic[bus->name];
    }
  }
  return survey;
}

/// One log being played: its reader and the record it holds next.
struct PlaySource {
  can::LogReader reader;
  bool pending{};
  can::Frame frame{};
  std::int64_t timeNs{};  ///< logged time; a line without one takes its predecessor's
  int target{-1};         ///< index into the played buses; -1: skipped
};

/// Reads the source's next frame that goes somewhere; false at its end.
bool advance(PlaySource& source, const std::map<std::string, int, std::less<>>& targets) {
  while (const auto maybeRecord = source.reader.next()) {
    if (maybeRecord->hasTime) source.timeNs = maybeRecord->frame.timestampNs;
    const auto found = targets.find(maybeRecord->channel);
    if (found == targets.end() || found->second < 0) continue;
    source.frame = maybeRecord->frame;
    source.target = found->second;
    source.pending = true;
    return true;
  }
  source.pending = false;
  return false;
}

/// Sleeps until `deadline` (CLOCK_MONOTONIC, absolute), in slices that let a stop signal
/// through. false when a stop was requested.
bool sleepUntil(std::chrono::steady_clock::time_point deadline) {
  for (;;) {
    if (stopRequested()) return false;
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return true;
    const auto until = std::min(deadline, now + STOP_TICK);
    const auto sinceEpoch = std::chrono::duration_cast<std::chrono::nanoseconds>(until.time_since_epoch()).count();
    timespec wake{};
    wake.tv_sec = static_cast<time_t>(sinceEpoch / 1'000'000'000);
    wake.tv_nsec = static_cast<long>(sinceEpoch % 1'000'000'000);
    (void)::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr);  // steady_clock is CLOCK_MONOTONIC
  }
}

/// Sends with the Busy retry; the final status.
can::SendStatus sendFrame(can::Link& link, const can::Frame& frame) {
  can::SendStatus status = link.send(frame);
  const auto busyDeadline = std::chrono::steady_clock::now() + BUSY_RETRY_TIME;
  while (status == can::SendStatus::Busy && std::chrono::steady_clock::now() < busyDeadline) {
    std::this_thread::sleep_for(BUSY_RETRY_STEP);
    status = link.send(frame);
  }
  return status;
}

/// One pass over every log, merged by time. false when stopped by a signal or a log
/// could not be reopened (reported).
bool playOnce(const ReplayOptions& options, const std::vector<std::string>& files,
              const std::map<std::string, int, std::less<>>& targets, std::vector<PlayedBus>& played, Sink& err) {
  std::vector<PlaySource> sources;
  sources.reserve(files.size());
  for (const std::string& file : files) {
    auto readerResult = can::LogReader::open(file, can::LogFormat::Candump);
    if (!readerResult) {
      report(err, readerResult.error());
      return false;
    }
    sources.push_back(PlaySource{std::move(*readerResult)});
    advance(sources.back(), targets);
  }
  const auto start = std::chrono::steady_clock::now();
  std::optional<std::int64_t> firstTimeNs;
  for (;;) {
    PlaySource* next = nullptr;
    for (PlaySource& source : sources) {
      if (source.pending && (next == nullptr || source.timeNs < next->timeNs)) next = &source;
    }
    if (next == nullptr) return true;
    if (!firstTimeNs) firstTimeNs = next->timeNs;
    if (options.speed > 0) {
      const double offsetNs = static_cast<double>(next->timeNs - *firstTimeNs) / options.speed;
      const auto due =
          start + std::chrono::nanoseconds(static_cast<std::int64_t>(std::clamp(offsetNs, 0.0, MAX_OFFSET_NS)));
      if (!sleepUntil(due)) return false;
    } else if (stopRequested()) {
      return false;
    }
    PlayedBus& target = played[static_cast<std::size_t>(next->target)];
    const can::SendStatus status = sendFrame(*target.link, next->frame);
    if (status == can::SendStatus::Sent) {
      ++target.frames;
    } else {
      if (target.failures == 0) {
        reportError(err, target.link->name() + ": " + can::formatCandumpL(next->frame, target.bus->name) +
                             " not sent: " + std::string(can::sendStatusName(status)) + " (further failures counted)");
      }
      ++target.failures;
    }
    advance(*next, targets);
  }
}

}  // namespace

ExitCode runReplay(const ReplayOptions& options, Streams streams) {
  if (!std::isfinite(options.speed) || options.speed < 0 || (options.speed > 0 && options.speed < MIN_SPEED)) {
    reportError(streams.err, "--speed " + formatNumber(options.speed) +
                                 ": must be 0 (as fast as possible) or at least " + formatNumber(MIN_SPEED));
    return ExitCode::Usage;
  }
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::VehicleConfig& config = maybeStack->config;
  const auto maybeSurvey = surveyLogs(options.directory, config, streams.err);
  if (!maybeSurvey) return ExitCode::Failure;
  const LogSurvey& survey = *maybeSurvey;
  if (survey.errors > 0) {
    if (survey.errors > MAX_REPORTED_LOG_ERRORS) {
      reportError(streams.err, "... and " + std::to_string(survey.errors - MAX_REPORTED_LOG_ERRORS) + " more");
    }
    reportError(streams.err, plural(survey.errors, "malformed line") + " in " + options.directory + ": nothing played");
    return ExitCode::Failure;
  }

  // Which channel goes where: a played bus index, or -1 (reported, skipped).
  std::map<std::string, int, std::less<>> targets;
  std::vector<PlayedBus> played;
  bool anySim = false;
  for (const auto& [channel, count] : survey.perChannel) {
    const config::BusConfig* bus = config.findBus(channel);
    std::string skipped;
    if (bus == nullptr) {
      skipped = "'" + channel + "' is not a bus of " + config.path;
    } else if (bus->link.kind == config::LinkKind::Replay) {
      skipped = "bus '" + channel + "' is " + bus->link.toString() + " (a log cannot be sent to)";
    }
    if (!skipped.empty()) {
      streams.err.write("vcu: warning: " + plural(count, "frame") + " skipped: " + skipped + "\n");
      targets[channel] = -1;
      continue;
    }
    if (const auto found = survey.fdOnClassic.find(channel); found != survey.fdOnClassic.end()) {
      streams.err.write("vcu: warning: bus '" + channel + "' is classic CAN: its " +
                        plural(found->second, "CAN FD frame") + " will be refused\n");
    }
    targets[channel] = static_cast<int>(played.size());
    anySim = anySim || bus->link.kind == config::LinkKind::Sim;
    played.push_back(PlayedBus{bus, nullptr});
  }
  if (played.empty()) {
    reportError(streams.err, "no frame in " + options.directory + " is for a bus of " + config.path);
    return ExitCode::Failure;
  }
  if (anySim && !initRuntime("replay", streams.err)) return ExitCode::Failure;
  for (PlayedBus& item : played) {
    can::LinkOptions linkOptions = item.bus->linkOptions();
    linkOptions.errorFrames = false;
    auto linkResult = can::openLink(item.bus->link.kind, item.bus->link.target, linkOptions);
    if (!linkResult) {
      reportError(streams.err, linkResult.error().message);
      return ExitCode::Failure;
    }
    item.link = std::move(*linkResult);
    if (item.bus->link.kind == config::LinkKind::Sim) {
      if (const Status connected = waitUntilSimLinkConnected(item.bus->link.target); !connected) {
        reportError(streams.err, connected.error().message);
        return ExitCode::Failure;
      }
    }
  }

  const StopSignalScope stopSignals;
  std::string names;
  for (const PlayedBus& item : played)
    names += (names.empty() ? "" : ", ") + item.bus->name + " (" + item.link->name() + ")";
  streams.err.write("replaying " + plural(survey.files.size(), "log") + " of " + options.directory + " onto " + names +
                    (options.speed == 1.0 ? std::string() : " at speed " + formatNumber(options.speed)) +
                    (options.loop ? ", looping" : "") + " (Ctrl-C to stop)\n");
  streams.err.flush();

  const auto start = std::chrono::steady_clock::now();
  std::uint64_t passes = 0;
  while (playOnce(options, survey.files, targets, played, streams.err)) {
    ++passes;
    if (!options.loop) break;
  }
  const bool stopped = stopRequested();
  const std::chrono::nanoseconds playedFor = std::chrono::steady_clock::now() - start;
  std::string summary = "played " + formatDuration(playedFor.count()) +
                        (passes > 1 ? " (" + std::to_string(passes) + " passes)" : std::string()) + "\n";
  bool ok = stopped || passes > 0;
  for (const PlayedBus& item : played) {
    summary += "  " + item.bus->name + ": " + plural(item.frames, "frame") + " -> " + item.link->name();
    if (item.failures > 0) {
      summary += ", " + plural(item.failures, "frame") + " refused";
      ok = false;
    }
    summary += "\n";
  }
  streams.out.write(summary);
  return ok ? ExitCode::Ok : ExitCode::Failure;
}

void registerRecordCommands(CLI::App& app, CommandContext& context) {
  auto recordOptions = std::make_shared<RecordOptions>();
  CLI::App* record = app.add_subcommand("record", RECORD_DESCRIPTION);
  record->footer(std::string(RECORD_FOOTER) + CONFIG_NOTE);
  record->add_option("DIR", recordOptions->directory, "folder for <bus>.log and events.lcmlog")
      ->required()
      ->type_name("");
  record->add_option("--for", recordOptions->forSeconds, "stop after this many seconds (default: at Ctrl-C)")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  record->add_flag("-f,--force", recordOptions->force, "overwrite a recording already in DIR");
  record->add_option("--lcm-logger", recordOptions->lcmLogger, "the lcm-logger program (default: from PATH)")
      ->option_text("PROGRAM");
  addStackOptions(*record, recordOptions->stack);
  record->callback([recordOptions, &context] { context.exitCode = runRecord(*recordOptions, context.streams); });

  auto replayOptions = std::make_shared<ReplayOptions>();
  CLI::App* replay = app.add_subcommand("replay", REPLAY_DESCRIPTION);
  replay->footer(std::string(REPLAY_FOOTER) + CONFIG_NOTE);
  replay->add_option("DIR", replayOptions->directory, "folder with the <bus>.log files")->required()->type_name("");
  replay->add_option("--speed", replayOptions->speed, "time factor: 2 twice as fast, 0 as fast as possible (default 1)")
      ->check(nonNegativeNumber())
      ->option_text("X");
  replay->add_flag("--loop", replayOptions->loop, "start again at the end until Ctrl-C");
  addStackOptions(*replay, replayOptions->stack);
  replay->callback([replayOptions, &context] { context.exitCode = runReplay(*replayOptions, context.streams); });
}

}  // namespace openvcu::cli
