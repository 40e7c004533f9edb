#pragma once
// The stack's clocks, read in one place: CLOCK_MONOTONIC for every timestamp, deadline and
// age (the signal table, frames, commands), CLOCK_REALTIME only for wall-clock answers
// (J1939 Time/Date, "since" texts).
//
//   const std::int64_t deadlineNs = clock::monotonicNs() + 250'000'000;

#include <cstdint>
#include <ctime>

namespace openvcu::clock {

/// CLOCK_MONOTONIC in nanoseconds. @note noexcept, allocation-free, any thread.
[[nodiscard]] inline std::int64_t monotonicNs() noexcept {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

/// CLOCK_REALTIME in nanoseconds since the Unix epoch. @note noexcept, allocation-free, any thread.
[[nodiscard]] inline std::int64_t realtimeNs() noexcept {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace openvcu::clock
