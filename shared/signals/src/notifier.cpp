#include "notifier.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <ctime>
#include "openvcu/core/clock.hpp"

namespace openvcu::signals::detail {

namespace {

constexpr std::int64_t NS_PER_SECOND = 1'000'000'000;

void futexWait(std::uint32_t* word, std::uint32_t expected, std::int64_t timeoutNs) noexcept {
  timespec relative{};
  relative.tv_sec = static_cast<time_t>(timeoutNs / NS_PER_SECOND);
  relative.tv_nsec = static_cast<long>(timeoutNs % NS_PER_SECOND);
  // FUTEX_WAIT's timeout is relative and measured against CLOCK_MONOTONIC. EAGAIN (the word
  // changed), EINTR and ETIMEDOUT all mean "look again"; the caller loops on the deadline.
  syscall(SYS_futex, word, FUTEX_WAIT, expected, &relative, nullptr, 0);
}

void futexWakeAll(std::uint32_t* word) noexcept {
  syscall(SYS_futex, word, FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

}  // namespace

void notifyChange(std::uint32_t& word) noexcept {
  std::atomic_ref<std::uint32_t> change(word);
  // Release: a waiter that sees the new epoch (acquire) also sees the value just written.
  const std::uint32_t previous = change.fetch_add(EPOCH_STEP, std::memory_order_acq_rel);
  if ((previous & WAITERS_FLAG) != 0) {
    change.fetch_and(~WAITERS_FLAG, std::memory_order_relaxed);
    futexWakeAll(&word);
  }
}

std::uint32_t currentEpoch(std::uint32_t& word) noexcept {
  return std::atomic_ref<std::uint32_t>(word).load(std::memory_order_acquire) >> 1;
}

std::uint32_t waitForEpochChange(std::uint32_t& word, std::uint32_t lastEpoch,
                                 std::chrono::nanoseconds timeout) noexcept {
  std::atomic_ref<std::uint32_t> change(word);
  const std::int64_t start = clock::monotonicNs();
  const std::int64_t timeoutNs = timeout.count() < 0 ? 0 : timeout.count();
  const std::int64_t deadline = timeoutNs > INT64_MAX - start ? INT64_MAX : start + timeoutNs;
  for (;;) {
    std::uint32_t seen = change.load(std::memory_order_acquire);
    if ((seen >> 1) != lastEpoch) return seen >> 1;
    const std::int64_t remaining = deadline - clock::monotonicNs();
    if (remaining <= 0) return lastEpoch;
    // Setting the flag and changing the epoch are RMWs on one word, so they are totally
    // ordered: either the writer's add comes first (we see the new epoch here) or it
    // comes after our flag (the writer sees the flag and wakes us). The kernel re-checks
    // the word under its lock before sleeping, which closes the gap until FUTEX_WAIT.
    seen = change.fetch_or(WAITERS_FLAG, std::memory_order_acq_rel);
    if ((seen >> 1) != lastEpoch) return seen >> 1;
    futexWait(&word, seen | WAITERS_FLAG, remaining);
  }
}

}  // namespace openvcu::signals::detail
