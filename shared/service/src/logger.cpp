#include "openvcu/core/clock.hpp"
#include "openvcu/service/logger.hpp"

#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>

#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/service/options.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::service {

namespace {

constexpr double NS_PER_SECOND = 1e9;

/// syslog priorities (RFC 5424 severity) for journald's "<N>" line prefix.
int journalPriority(ipc::LogLevel level) noexcept {
  switch (level) {
    case ipc::LogLevel::Trace:
    case ipc::LogLevel::Debug:
      return 7;  // debug
    case ipc::LogLevel::Info:
      return 6;  // info
    case ipc::LogLevel::Warning:
      return 4;  // warning
    case ipc::LogLevel::Error:
      return 3;  // err
    case ipc::LogLevel::Critical:
      return 2;  // crit
  }
  return 6;
}

/// One line: newlines in the text would forge log lines.
std::string oneLine(std::string_view text) {
  std::string line(text);
  std::replace(line.begin(), line.end(), '\n', ' ');
  std::replace(line.begin(), line.end(), '\r', ' ');
  return line;
}

}  // namespace

std::string formatUtc(std::int64_t realtimeNs) {
  const std::int64_t seconds =
      realtimeNs >= 0 ? realtimeNs / 1'000'000'000 : (realtimeNs - 999'999'999) / 1'000'000'000;
  const std::int64_t milliseconds = (realtimeNs - seconds * 1'000'000'000) / 1'000'000;
  const auto time = static_cast<time_t>(seconds);
  tm parts{};
  ::gmtime_r(&time, &parts);
  std::array<char, 96> text{};  // room for any int the compiler imagines (-Wformat-truncation)
  std::snprintf(text.data(), text.size(), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", parts.tm_year + 1900, parts.tm_mon + 1,
                parts.tm_mday, parts.tm_hour, parts.tm_min, parts.tm_sec, static_cast<int>(milliseconds));
  return text.data();
}

RateLimiter::RateLimiter(double ratePerSecond, std::uint32_t burst) noexcept
    : m_ratePerNs(std::max(0.0, ratePerSecond) / NS_PER_SECOND),
      m_capacity(std::max<double>(1.0, burst)),
      m_tokens(m_capacity) {}

bool RateLimiter::allow(std::int64_t nowNs) noexcept {
  if (m_lastNs >= 0 && nowNs > m_lastNs) {
    m_tokens = std::min(m_capacity, m_tokens + static_cast<double>(nowNs - m_lastNs) * m_ratePerNs);
  }
  if (m_lastNs < 0 || nowNs > m_lastNs) m_lastNs = nowNs;
  if (m_tokens < 1.0) return false;
  m_tokens -= 1.0;
  return true;
}

Logger::Logger(std::string program, LoggerOptions options, std::FILE* stream)
    : m_program(std::move(program)),
      m_options(options),
      m_stream(stream),
      m_limiter(options.ratePerSecond, options.burst),
      m_pid(static_cast<int>(::getpid())) {}

void Logger::attachEventBus(ipc::EventBus* events) noexcept {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_events = events;
}

bool Logger::enabled(ipc::LogLevel level) const noexcept {
  std::lock_guard<std::mutex> lock(m_mutex);
  return level >= m_options.threshold;
}

void Logger::setThreshold(ipc::LogLevel level) noexcept {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_options.threshold = level;
}

std::uint64_t Logger::suppressed() const noexcept {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_suppressed;
}

void Logger::log(ipc::LogLevel level, std::string_view text) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (level < m_options.threshold) return;
  if (!m_limiter.allow(clock::monotonicNs())) {
    ++m_suppressed;
    ++m_suppressedUnreported;
    return;
  }
  const std::int64_t now = clock::realtimeNs();
  if (m_suppressedUnreported > 0) {
    emit(ipc::LogLevel::Warning, std::to_string(m_suppressedUnreported) + " log lines suppressed by the rate limit",
         now);
    m_suppressedUnreported = 0;
  }
  emit(level, text, now);
}

void Logger::emit(ipc::LogLevel level, std::string_view text, std::int64_t realtimeNs) {
  const std::string line = oneLine(text);
  if (m_stream != nullptr) {
    std::string out;
    if (m_options.journalFormat) {
      out = "<" + std::to_string(journalPriority(level)) + ">" + line + "\n";
    } else {
      out = formatUtc(realtimeNs) + " " + std::string(logLevelName(level)) + " " + m_program + "[" +
            std::to_string(m_pid) + "]: " + line + "\n";
    }
    std::fwrite(out.data(), 1, out.size(), m_stream);
    std::fflush(m_stream);
  }
  if (m_events != nullptr) {
    m_events->publish(ipc::LogRecord{realtimeNs, m_program, level, line});
  }
}

}  // namespace openvcu::service
