#pragma once
// A periodic timer on absolute deadlines: first, first + period, first + 2 period, ...
// on CLOCK_MONOTONIC (timerfd with TFD_TIMER_ABSTIME), so the phase never drifts however
// late each cycle is handled. A late reader gets ONE tick that reports how many deadlines
// it missed: there is no catch-up burst of back-to-back cycles.
//
//   auto timerResult = service::PeriodicTimer::create(10ms);
//   loop.addTimer(*timerResult, [&](const service::TimerTick& tick) {
//     if (tick.missed > 0) missedCycles.increment(tick.missed);
//     sendCyclicFrames(tick.deadline);
//   });
//
// std::chrono::steady_clock is CLOCK_MONOTONIC in libstdc++ and libc++ on Linux; its time
// points are the deadlines. The ticks are counted from the clock (which deadlines lie at or
// before now), so take(), takeDue() and the loop, which waits for nextDeadline() without
// the fd (service::Loop), agree on every cycle; the timerfd only makes the timer pollable.

#include <chrono>
#include <cstdint>
#include <optional>

#include "openvcu/core/result.hpp"

namespace openvcu::service {

using MonotonicTime = std::chrono::steady_clock::time_point;

struct TimerTick {
  MonotonicTime deadline;  ///< the newest deadline that has passed (first + (cycle - 1) * period)
  std::uint64_t cycle{};   ///< its number, 1 for the first deadline
  std::uint64_t missed{};  ///< deadlines passed since the previous tick without their own tick
};

/// @note restricted thread-safe: one thread at a time. take() is noexcept, allocation-free
///       and makes one read() system call.
class PeriodicTimer {
 public:
  /// Ticks every `period` (> 0), the first time one period from now.
  static Result<PeriodicTimer> create(std::chrono::nanoseconds period);
  /// Ticks at `firstDeadline` (may be in the past: then the first tick is due at once and
  /// reports the deadlines already missed) and every `period` after it.
  static Result<PeriodicTimer> create(std::chrono::nanoseconds period, MonotonicTime firstDeadline);

  PeriodicTimer(PeriodicTimer&& other) noexcept;
  PeriodicTimer& operator=(PeriodicTimer&& other) noexcept;
  PeriodicTimer(const PeriodicTimer&) = delete;
  PeriodicTimer& operator=(const PeriodicTimer&) = delete;
  ~PeriodicTimer();

  /// Readable when a deadline has passed (for Loop::addTimer, poll or Waiter::attachFd).
  [[nodiscard]] int fd() const noexcept { return m_fd; }

  /// The tick when at least one deadline passed since the last take(); empty otherwise
  /// (never blocks). Clears the fd's readiness (one read() system call).
  std::optional<TimerTick> take() noexcept;
  /// The tick when at least one deadline lies at or before `now` and was not taken yet;
  /// empty otherwise. No system call: for a caller that waits for nextDeadline() itself
  /// (service::Loop). The fd may stay readable; a later take() clears it without a tick.
  std::optional<TimerTick> takeDue(MonotonicTime now) noexcept;

  /// Blocks until the next tick or `timeout` (for simple loops and tests; services use Loop).
  std::optional<TimerTick> waitFor(std::chrono::nanoseconds timeout) noexcept;

  [[nodiscard]] std::chrono::nanoseconds period() const noexcept { return m_period; }
  [[nodiscard]] MonotonicTime firstDeadline() const noexcept { return m_first; }
  /// The next deadline that has not been taken yet.
  [[nodiscard]] MonotonicTime nextDeadline() const noexcept {
    return m_first + m_period * static_cast<std::int64_t>(m_cycles);
  }
  /// Deadlines passed so far (ticked or missed).
  [[nodiscard]] std::uint64_t cycles() const noexcept { return m_cycles; }
  /// Deadlines that passed without a tick of their own, in total.
  [[nodiscard]] std::uint64_t missedCycles() const noexcept { return m_missed; }

 private:
  PeriodicTimer(int fd, std::chrono::nanoseconds period, MonotonicTime first) noexcept
      : m_fd(fd), m_period(period), m_first(first) {}

  int m_fd{-1};
  std::chrono::nanoseconds m_period{};
  MonotonicTime m_first{};
  std::uint64_t m_cycles{};
  std::uint64_t m_missed{};
};

}  // namespace openvcu::service
