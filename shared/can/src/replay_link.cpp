#include "openvcu/can/replay_link.hpp"

#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <utility>

#include "openvcu/can/event_queue.hpp"
#include "openvcu/can/log_reader.hpp"

namespace openvcu::can {
namespace {

constexpr std::int64_t NS_PER_SECOND = 1'000'000'000;
constexpr std::int64_t MAX_NS = std::numeric_limits<std::int64_t>::max();

std::int64_t monotonicNow() noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * NS_PER_SECOND + now.tv_nsec;
}

/// Arms `timerFd` to expire at `atNs` on CLOCK_MONOTONIC (at once when that has passed);
/// atNs <= 0 disarms it.
void armTimer(int timerFd, std::int64_t atNs) noexcept {
  itimerspec spec{};
  if (atNs > 0) {
    spec.it_value.tv_sec = static_cast<time_t>(atNs / NS_PER_SECOND);
    spec.it_value.tv_nsec = static_cast<long>(atNs % NS_PER_SECOND);
  }
  timerfd_settime(timerFd, TFD_TIMER_ABSTIME, &spec, nullptr);
}

/// An absolute time long past: arming the timer at it makes the handle readable now.
constexpr std::int64_t PAST_NS = 1;

std::string describeReaderErrors(const LogReader& reader) {
  if (reader.errorCount() == 0) return {};
  std::string text = " (" + std::to_string(reader.errorCount()) + " malformed line";
  if (reader.errorCount() > 1) text += 's';
  if (reader.lastError()) text += "; last: " + reader.lastError()->toString();
  return text + ')';
}

class ReplayLinkImpl final : public ReplayLink {
 public:
  ReplayLinkImpl(std::string name, std::string path, LinkOptions options, LogReader reader, int timerFd) noexcept
      : m_name(std::move(name)),
        m_path(std::move(path)),
        m_options(std::move(options)),
        m_reader(std::move(reader)),
        m_timerFd(timerFd) {}

  ~ReplayLinkImpl() override { ::close(m_timerFd); }
  ReplayLinkImpl(const ReplayLinkImpl&) = delete;
  ReplayLinkImpl& operator=(const ReplayLinkImpl&) = delete;

  /// Reads ahead to the first frame (no budget: this is start-up). false when there is none.
  bool findFirstFrame() noexcept {
    std::size_t unlimited = std::numeric_limits<std::size_t>::max();
    m_state = readAhead(unlimited);
    if (m_state != State::Pending) return false;
    armTimer(m_timerFd, PAST_NS);  // readable now: the first frame is due at the first receive()
    return true;
  }

  [[nodiscard]] const LogReader& reader() const noexcept { return *m_reader; }

  // Link --------------------------------------------------------------------------------

  [[nodiscard]] LinkKind kind() const noexcept override { return LinkKind::Replay; }
  [[nodiscard]] const std::string& name() const noexcept override { return m_name; }
  [[nodiscard]] WaitHandle waitHandle() noexcept override { return WaitHandle{m_timerFd, nullptr}; }

  std::size_t receive(std::span<ReceivedFrame> out) noexcept override {
    if (out.empty() || m_state == State::Finished) return 0;
    std::uint64_t expirations = 0;
    (void)!::read(m_timerFd, &expirations, sizeof expirations);  // EAGAIN when not expired: fine
    const std::int64_t nowNs = monotonicNow();
    if (!m_started) {
      m_started = true;
      m_previousDueNs = nowNs;
      schedulePending();
    }
    std::size_t count = 0;
    std::size_t budget = SKIP_BUDGET;
    bool restarted = false;
    bool more = true;
    while (more) {
      switch (m_state) {
        case State::Pending:
          if (count == out.size() || (!asFastAsPossible() && m_pendingDueNs > nowNs)) {
            more = false;
            break;
          }
          if (passes(m_options.filters, m_pending)) {
            out[count].frame = m_pending;
            out[count].monotonicNs = asFastAsPossible() ? nowNs : m_pendingDueNs;
            ++count;
          } else {
            ++m_stats.filteredOut;
            if (budget > 0) --budget;
          }
          m_state = State::Scanning;
          break;
        case State::Scanning:
          if (budget == 0) {
            more = false;
            break;
          }
          m_state = readAhead(budget);
          break;
        case State::AtEnd:
          if (!m_options.replayLoop) {
            finish(nowNs);
          } else if (m_framesThisPass == 0) {
            noteProblem("the log no longer holds a frame to replay");
            finish(nowNs);
          } else if (restarted) {
            more = false;  // one pass per call: come back through the event loop
          } else {
            restarted = true;
            restart(nowNs);
          }
          break;
        case State::Finished:
          more = false;
          break;
      }
    }
    rearm();
    m_stats.framesReceived += count;
    return count;
  }

  SendStatus send(const Frame&) noexcept override {
    ++m_stats.sendFailures;  // a log is read-only
    return SendStatus::NotSupported;
  }

  std::optional<BusEvent> nextEvent() noexcept override { return m_events.pop(); }
  [[nodiscard]] bool up() const noexcept override { return m_state != State::Finished; }
  [[nodiscard]] LinkStats stats() const noexcept override { return m_stats; }

  // ReplayLink --------------------------------------------------------------------------

  [[nodiscard]] std::uint64_t malformedLines() const noexcept override {
    return m_malformedEarlierPasses + (m_reader ? m_reader->errorCount() : 0);
  }
  [[nodiscard]] std::uint64_t backwardTimestamps() const noexcept override { return m_backwardTimestamps; }
  [[nodiscard]] std::uint64_t restarts() const noexcept override { return m_restarts; }
  [[nodiscard]] std::optional<Error> lastLogError() const override {
    if (m_problem) return m_problem;
    if (m_reader && m_reader->lastError()) return m_reader->lastError();
    return m_lastReaderError;
  }

 private:
  enum class State : std::uint8_t {
    Pending,   ///< m_pending is the next frame, due at m_pendingDueNs
    Scanning,  ///< looking for the next frame of the channel (budget ran out, or not begun)
    AtEnd,     ///< the reader is exhausted: restart or finish
    Finished,  ///< the end of a non-looping log (or a log that could not be reopened)
  };

  [[nodiscard]] bool asFastAsPossible() const noexcept { return m_options.replaySpeed == 0.0; }

  /// Reads records until one of the selected channel: Pending (scheduled when started),
  /// AtEnd, or Scanning when `budget` records were skipped first.
  State readAhead(std::size_t& budget) noexcept {
    if (!m_reader) return State::AtEnd;
    try {
      while (budget > 0) {
        std::optional<LogRecord> maybeRecord = m_reader->next();
        if (!maybeRecord) return State::AtEnd;
        if (!m_options.replayChannel.empty() && maybeRecord->channel != m_options.replayChannel) {
          --budget;
          continue;
        }
        m_pending = maybeRecord->frame;
        m_pendingHasTime = maybeRecord->hasTime;
        ++m_framesThisPass;
        if (m_started) schedulePending();
        return State::Pending;
      }
      return State::Scanning;
    } catch (...) {  // LogReader::next() only throws when memory runs out: end the log there
      return State::AtEnd;
    }
  }

  /// m_pendingDueNs from the pending frame's logged time; the rules are in replay_link.hpp.
  void schedulePending() noexcept {
    std::int64_t dueNs = m_previousDueNs;  // no timestamp, or the first one: at once
    if (m_pendingHasTime) {
      const std::int64_t loggedNs = m_pending.timestampNs;
      if (!m_anchored) {
        m_anchored = true;
        m_anchorDueNs = m_previousDueNs;
        m_anchorLoggedNs = loggedNs;
      } else if (loggedNs < m_lastLoggedNs) {
        ++m_backwardTimestamps;
        if (m_lastLoggedNs - loggedNs > REBASE_BACKSTEP_NS) {
          m_anchorDueNs = m_previousDueNs;
          m_anchorLoggedNs = loggedNs;
        }
      } else {
        dueNs = std::max(m_previousDueNs, addSaturated(m_anchorDueNs, scaled(loggedNs - m_anchorLoggedNs)));
      }
      m_lastLoggedNs = loggedNs;
    }
    m_pendingDueNs = dueNs;
    m_previousDueNs = dueNs;
  }

  /// A log-time interval at the replay speed.
  [[nodiscard]] std::int64_t scaled(std::int64_t intervalNs) const noexcept {
    const double speed = m_options.replaySpeed;
    if (speed == 1.0 || speed == 0.0) return intervalNs;  // exact at original speed
    const double result = std::round(static_cast<double>(intervalNs) / speed);
    constexpr double LIMIT = 9.0e18;  // below MAX_NS
    if (result >= LIMIT) return MAX_NS;
    if (result <= -LIMIT) return -MAX_NS;
    return static_cast<std::int64_t>(result);
  }

  static std::int64_t addSaturated(std::int64_t a, std::int64_t b) noexcept {
    std::int64_t sum = 0;
    return __builtin_add_overflow(a, b, &sum) ? (b > 0 ? MAX_NS : 0) : sum;
  }

  /// Loops: a new pass from the top of the log with a new time base.
  void restart(std::int64_t nowNs) noexcept {
    ++m_restarts;
    m_events.push(BusEvent{BusEventKind::ReplayRestarted, nowNs, 0, 0, 0});
    try {
      keepReaderError();
      m_malformedEarlierPasses += m_reader ? m_reader->errorCount() : 0;
      m_reader.reset();
      auto openResult = LogReader::open(m_path);
      if (!openResult) {
        m_problem = openResult.error();
        finish(nowNs);
        return;
      }
      m_reader.emplace(std::move(*openResult));
    } catch (...) {
      finish(nowNs);
      return;
    }
    m_framesThisPass = 0;
    m_anchored = false;
    m_previousDueNs = nowNs;
    m_state = State::Scanning;
  }

  void finish(std::int64_t nowNs) noexcept {
    if (m_state == State::Finished) return;
    m_state = State::Finished;
    m_events.push(BusEvent{BusEventKind::ReplayFinished, nowNs, 0, 0, 0});
    try {
      keepReaderError();
    } catch (...) {  // out of memory: the counters below still hold
    }
    m_malformedEarlierPasses += m_reader ? m_reader->errorCount() : 0;
    m_reader.reset();  // closes the file and frees the read buffer
  }

  void noteProblem(const char* message) noexcept {
    try {
      m_problem = Error{message, Location{m_path, 0, 0, {}}};
    } catch (...) {  // out of memory: the ReplayFinished event still tells
    }
  }

  /// The reader's last error outlives the reader (it is replaced on every pass).
  void keepReaderError() {
    if (m_reader && m_reader->lastError()) m_lastReaderError = m_reader->lastError();
  }

  void rearm() noexcept {
    switch (m_state) {
      case State::Pending:
        armTimer(m_timerFd, asFastAsPossible() ? PAST_NS : std::max(m_pendingDueNs, PAST_NS));
        break;
      case State::Scanning:
      case State::AtEnd:
        armTimer(m_timerFd, PAST_NS);  // more to do: come back at once
        break;
      case State::Finished:
        armTimer(m_timerFd, 0);
        break;
    }
  }

  std::string m_name;
  std::string m_path;
  LinkOptions m_options;
  std::optional<LogReader> m_reader;
  int m_timerFd;
  detail::EventQueue m_events;
  LinkStats m_stats{};
  State m_state{State::Scanning};

  Frame m_pending{};
  bool m_pendingHasTime{};
  std::int64_t m_pendingDueNs{};

  bool m_started{};                 // the first receive() has set the time base
  bool m_anchored{};                // a timestamped frame of this pass has been scheduled
  std::int64_t m_anchorDueNs{};     // due time of the frame that anchors the schedule...
  std::int64_t m_anchorLoggedNs{};  // ...and its logged time
  std::int64_t m_lastLoggedNs{};
  std::int64_t m_previousDueNs{};

  std::uint64_t m_framesThisPass{};
  std::uint64_t m_malformedEarlierPasses{};
  std::uint64_t m_backwardTimestamps{};
  std::uint64_t m_restarts{};
  std::optional<Error> m_problem;          // the log could not be reopened
  std::optional<Error> m_lastReaderError;  // of an earlier pass
};

}  // namespace

Result<std::unique_ptr<ReplayLink>> ReplayLink::open(const std::string& path, const LinkOptions& options) {
  const std::string name = "replay:" + path;
  const Location where{name, 0, 0, {}};
  if (!(options.replaySpeed >= 0.0) || !std::isfinite(options.replaySpeed)) {
    return Error{
        "replay speed must be a number >= 0 (0: as fast as possible), got " + std::to_string(options.replaySpeed),
        where};
  }
  auto openResult = LogReader::open(path);
  if (!openResult) return Error{openResult.error().message, where};

  const int timerFd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  if (timerFd < 0) return Error{std::string("cannot create a timerfd: ") + std::strerror(errno), where};
  auto link = std::make_unique<ReplayLinkImpl>(name, path, options, std::move(*openResult), timerFd);
  if (!link->findFirstFrame()) {
    std::string reason = options.replayChannel.empty()
                             ? std::string("no CAN frame in the log")
                             : "no CAN frame of channel '" + options.replayChannel + "' in the log";
    return Error{reason + describeReaderErrors(link->reader()), where};
  }
  return std::unique_ptr<ReplayLink>(std::move(link));
}

Result<std::unique_ptr<Link>> openReplayLink(const std::string& path, const LinkOptions& options) {
  auto openResult = ReplayLink::open(path, options);
  if (!openResult) return openResult.error();
  return std::unique_ptr<Link>(std::move(*openResult));
}

}  // namespace openvcu::can
