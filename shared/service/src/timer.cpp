#include "openvcu/service/timer.hpp"

#include <poll.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace openvcu::service {

namespace {

timespec toTimespec(std::chrono::nanoseconds duration) noexcept {
  const auto count = duration.count();
  return timespec{static_cast<time_t>(count / 1'000'000'000), static_cast<long>(count % 1'000'000'000)};
}

}  // namespace

Result<PeriodicTimer> PeriodicTimer::create(std::chrono::nanoseconds period) {
  return create(period, std::chrono::steady_clock::now() + period);
}

Result<PeriodicTimer> PeriodicTimer::create(std::chrono::nanoseconds period, MonotonicTime firstDeadline) {
  if (period.count() <= 0) return Error{"periodic timer: the period must be positive"};
  if (firstDeadline.time_since_epoch().count() <= 0) {
    return Error{"periodic timer: the first deadline must be after the clock's epoch"};
  }
  const int fd = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  if (fd < 0) return Error{std::string("periodic timer: timerfd_create failed: ") + std::strerror(errno)};
  // The kernel keeps the grid: each expiry is first + k * period (hrtimer forwarding), and
  // expirations a reader missed are counted, not queued.
  itimerspec spec{};
  spec.it_value = toTimespec(firstDeadline.time_since_epoch());
  spec.it_interval = toTimespec(period);
  if (::timerfd_settime(fd, TFD_TIMER_ABSTIME, &spec, nullptr) != 0) {
    const int error = errno;
    ::close(fd);
    return Error{std::string("periodic timer: timerfd_settime failed: ") + std::strerror(error)};
  }
  return PeriodicTimer(fd, period, firstDeadline);
}

PeriodicTimer::PeriodicTimer(PeriodicTimer&& other) noexcept
    : m_fd(other.m_fd),
      m_period(other.m_period),
      m_first(other.m_first),
      m_cycles(other.m_cycles),
      m_missed(other.m_missed) {
  other.m_fd = -1;
}

PeriodicTimer& PeriodicTimer::operator=(PeriodicTimer&& other) noexcept {
  if (this != &other) {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = other.m_fd;
    m_period = other.m_period;
    m_first = other.m_first;
    m_cycles = other.m_cycles;
    m_missed = other.m_missed;
    other.m_fd = -1;
  }
  return *this;
}

PeriodicTimer::~PeriodicTimer() {
  if (m_fd >= 0) ::close(m_fd);
}

std::optional<TimerTick> PeriodicTimer::take() noexcept {
  if (m_fd < 0) return std::nullopt;
  std::uint64_t expirations = 0;
  [[maybe_unused]] const ssize_t got = ::read(m_fd, &expirations, sizeof(expirations));  // EAGAIN: not yet
  // The kernel's expiry comes at or after the deadline on the same clock, so the clock
  // read after it always covers what the fd reported.
  return takeDue(std::chrono::steady_clock::now());
}

std::optional<TimerTick> PeriodicTimer::takeDue(MonotonicTime now) noexcept {
  if (now < m_first) return std::nullopt;
  const auto passed = static_cast<std::uint64_t>((now - m_first) / m_period) + 1;  // deadlines <= now
  if (passed <= m_cycles) return std::nullopt;
  const std::uint64_t expirations = passed - m_cycles;
  m_cycles = passed;
  m_missed += expirations - 1;
  return TimerTick{m_first + m_period * static_cast<std::int64_t>(m_cycles - 1), m_cycles, expirations - 1};
}

std::optional<TimerTick> PeriodicTimer::waitFor(std::chrono::nanoseconds timeout) noexcept {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    if (auto maybeTick = take()) return maybeTick;
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return std::nullopt;
    pollfd pfd{m_fd, POLLIN, 0};
    const int rc = ::poll(&pfd, 1, static_cast<int>(std::min<std::int64_t>(left.count(), 1'000'000)));
    if (rc < 0 && errno != EINTR) return std::nullopt;
  }
}

}  // namespace openvcu::service
