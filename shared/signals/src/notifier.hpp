#pragma once
// Change notification across processes: one 32-bit futex word in the table header holds
// a change epoch (bits 31..1) and a "someone sleeps" flag (bit 0).
//
//   writer: fetch_add(2); if the flag was set: clear it, FUTEX_WAKE everyone
//   waiter: if the epoch moved, return; else set the flag and FUTEX_WAIT on the value it saw
//
// A writer makes a system call only for the first change after a waiter went to sleep;
// every other change is one atomic add. A waiter killed while asleep leaves the flag set:
// the next change clears it with one unneeded FUTEX_WAKE, nothing else happens.
// FUTEX_WAIT/WAKE without FUTEX_PRIVATE_FLAG work across processes on a MAP_SHARED page.

#include <chrono>
#include <cstdint>

namespace openvcu::signals::detail {

inline constexpr std::uint32_t WAITERS_FLAG = 1;
inline constexpr std::uint32_t EPOCH_STEP = 2;

/// Bumps the epoch and wakes sleepers if any. @note lock-free; a system call only when the flag was set.
void notifyChange(std::uint32_t& word) noexcept;

/// The current epoch (31 bits).
[[nodiscard]] std::uint32_t currentEpoch(std::uint32_t& word) noexcept;

/// Blocks until the epoch differs from `lastEpoch` or `timeout` passed; returns the epoch.
[[nodiscard]] std::uint32_t waitForEpochChange(std::uint32_t& word, std::uint32_t lastEpoch,
                                               std::chrono::nanoseconds timeout) noexcept;


}  // namespace openvcu::signals::detail
