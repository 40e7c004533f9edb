#pragma once
// Service logging: one line per record on stderr (journald or the harness collect it) and a
// LogRecord on the event bus (lcm-spy, lcm-logger), both behind one rate limit so a fault
// storm cannot flood the journal or the network.
//
//   Logger log("vcu-fsm", {.threshold = ipc::LogLevel::Info});
//   log.attachEventBus(&events);
//   log.info("ready (instance hhea, 812 signals)");
//   -> stderr: "2026-11-21T06:00:00.123Z info vcu-fsm[4242]: ready (instance hhea, 812 signals)"
//      under systemd (JOURNAL_STREAM set): "<6>ready (instance hhea, 812 signals)"
//
// When the rate limit drops lines, the next line that passes is preceded by
// "N log lines suppressed by the rate limit" (and suppressed() counts them all).

#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <string_view>

#include "openvcu/ipc/events.hpp"

namespace openvcu::ipc {
class EventBus;
}

namespace openvcu::service {

/// A token bucket: `burst` lines at once, refilled at `ratePerSecond`. Time is the caller's
/// (CLOCK_MONOTONIC ns), so tests drive it without sleeping.
/// @note not thread-safe (Logger guards it); noexcept, allocation-free.
class RateLimiter {
 public:
  RateLimiter(double ratePerSecond, std::uint32_t burst) noexcept;
  /// true: pass (and take one token); false: drop.
  bool allow(std::int64_t nowNs) noexcept;

 private:
  double m_ratePerNs;
  double m_capacity;
  double m_tokens;
  std::int64_t m_lastNs{-1};
};

struct LoggerOptions {
  ipc::LogLevel threshold{ipc::LogLevel::Info};  ///< lower levels are not logged at all
  double ratePerSecond{20.0};                    ///< sustained lines per second
  std::uint32_t burst{50};                       ///< lines allowed at once
  /// Journal style ("<6>text", no time stamp) instead of "time level program[pid]: text".
  /// Service::open sets it when stderr is the journal (JOURNAL_STREAM).
  bool journalFormat{false};
};

/// @note thread-safe: any thread may log (a mutex orders lines). Not real-time: formats
///       and writes; keep it out of per-frame paths (count there, log once per second).
class Logger {
 public:
  /// `program`: "vcu-fsm". Writes to `stream` (stderr by default; not owned).
  explicit Logger(std::string program, LoggerOptions options = {}, std::FILE* stream = stderr);

  /// Also publish every record that passes as a LogRecord (nullptr: stop). The bus must
  /// outlive the logger or be detached first.
  void attachEventBus(ipc::EventBus* events) noexcept;

  void log(ipc::LogLevel level, std::string_view text);
  void trace(std::string_view text) { log(ipc::LogLevel::Trace, text); }
  void debug(std::string_view text) { log(ipc::LogLevel::Debug, text); }
  void info(std::string_view text) { log(ipc::LogLevel::Info, text); }
  void warning(std::string_view text) { log(ipc::LogLevel::Warning, text); }
  void error(std::string_view text) { log(ipc::LogLevel::Error, text); }
  void critical(std::string_view text) { log(ipc::LogLevel::Critical, text); }

  /// true when `level` would be logged (to skip building expensive text).
  [[nodiscard]] bool enabled(ipc::LogLevel level) const noexcept;
  void setThreshold(ipc::LogLevel level) noexcept;
  /// Lines dropped by the rate limit so far.
  [[nodiscard]] std::uint64_t suppressed() const noexcept;
  [[nodiscard]] const std::string& program() const noexcept { return m_program; }

 private:
  void emit(ipc::LogLevel level, std::string_view text, std::int64_t realtimeNs);

  std::string m_program;
  LoggerOptions m_options;
  std::FILE* m_stream;
  ipc::EventBus* m_events{nullptr};
  mutable std::mutex m_mutex;
  RateLimiter m_limiter;
  std::uint64_t m_suppressed{};
  std::uint64_t m_suppressedUnreported{};
  int m_pid;
};

/// "2026-11-21T06:00:00.123Z" for CLOCK_REALTIME nanoseconds.
[[nodiscard]] std::string formatUtc(std::int64_t realtimeNs);

}  // namespace openvcu::service
