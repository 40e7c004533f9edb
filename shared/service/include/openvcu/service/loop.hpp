#pragma once
// The one wait of a service: frame subscribers (iceoryx), file descriptors (the LCM event
// bus, the shutdown signalfd, sockets) and periodic timers, all in one blocking call, with
// every callback on the service's own thread (no locks in service code) and no busy loop.
//
//   auto loopResult = service::Loop::create();
//   service::Loop& loop = *loopResult;
//   loop.addFd(events.fileno(), [&] { events.handleAll(); });
//   loop.addTimer(cycleTimer, [&](const service::TimerTick& tick) { onCycle(tick); });
//   loop.addSubscriber(rxSubscriber, [&] { while (auto maybeSample = rxSubscriber.take()) onFrame(*maybeSample); });
//   return loop.run();   // until stop(exitCode)
//
// Two back ends, chosen by what is attached:
//   - no frame subscriber: ppoll(2) on the fds (a service without iceoryx never needs RouDi);
//   - from the first addSubscriber on: ipc::Waiter, its WaitSet for the subscribers and
//     attachFd for every fd (iceoryx 2.0's WaitSet has no fd, docs/design/ipc.md).
// Timers and deadlines are never fds of the wait: each wait's timeout ends at the earliest
// of them (absolute, CLOCK_MONOTONIC), and the loop runs their callbacks itself, so a timer
// costs no fd-watcher hand-over (docs/design/loop-wakeups.md).
// Either way the wait blocks until something is ready: there is no periodic wake-up.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>

#include "openvcu/core/result.hpp"
#include "openvcu/service/timer.hpp"

namespace openvcu::ipc {
class SampleSubscriber;
}
namespace openvcu::can {
class Link;
}

namespace openvcu::service {

struct LoopImpl;

/// @note restricted thread-safe: add/remove/run/runOnce on one thread; stop() from any
///       thread (not from a signal handler: use ShutdownSignals). Callbacks run inside
///       run()/runOnce() on that thread and may call add/remove/stop.
class Loop {
 public:
  static Result<Loop> create();

  Loop(Loop&& other) noexcept;
  Loop& operator=(Loop&& other) noexcept;
  Loop(const Loop&) = delete;
  Loop& operator=(const Loop&) = delete;
  ~Loop();

  /// Calls `onReadable` whenever `fd` is readable (level-triggered: the callback must
  /// consume what made it readable, or it is called again at once). Fails for a negative
  /// or already added fd. Remove the fd before closing it.
  Status addFd(int fd, std::function<void()> onReadable);
  /// Stops watching `fd` (safe inside a callback).
  void removeFd(int fd) noexcept;

  /// Calls `onTick` for each tick of `timer` (the loop takes it with takeDue once the clock
  /// passes nextDeadline(); a late tick reports the missed deadlines). The timer must
  /// outlive the loop or be removed (removeFd(timer.fd())).
  Status addTimer(PeriodicTimer& timer, std::function<void(const TimerTick&)> onTick);

  /// A one-shot wake-up its owner moves: `onDue` runs on the loop thread once the clock
  /// reaches the time last given to setDeadline; then the deadline is unset until set again
  /// (the callback may set the next one). Unset after addDeadline.
  struct DeadlineId {
    std::uint64_t value{};
  };
  Result<DeadlineId> addDeadline(std::function<void()> onDue);
  /// Sets (replaces) the absolute time of `deadline`; MonotonicTime::max() unsets it.
  /// @note noexcept, allocation-free, O(sources): fine per dispatch.
  void setDeadline(DeadlineId deadline, MonotonicTime due) noexcept;
  void removeDeadline(DeadlineId deadline) noexcept;

  /// Calls `onData` while `subscriber` holds samples (level-triggered: take them all).
  /// Needs an initialised ipc::Runtime; switches the loop to the ipc::Waiter back end.
  /// The subscriber must outlive the loop.
  Status addSubscriber(ipc::SampleSubscriber& subscriber, std::function<void()> onData);

  /// Calls `onReadable` whenever `link` has something to do: its wait handle is an fd
  /// (addFd) or, for a sim link, an iceoryx subscriber (addSubscriber). The link must
  /// outlive the loop (or its fd be removed).
  Status addLink(can::Link& link, std::function<void()> onReadable);

  /// Waits and dispatches until stop(); returns the code given to stop().
  int run();
  /// One wait of at most `timeout` (less when a timer or deadline comes first), then the
  /// callbacks of what is ready and of the timers and deadlines due. false once stopped.
  bool runOnce(std::chrono::nanoseconds timeout);

  /// Makes run() return `exitCode` after the callback in progress (if any) finishes.
  void stop(int exitCode = 0) noexcept;
  [[nodiscard]] bool stopped() const noexcept;
  /// run(): after a dispatch of fds or subscribers, sleep `window` before waiting again, so
  /// that frames arriving meanwhile are handled in one batch (fewer wake-ups). While each
  /// wait finds work already waiting (traffic keeps coming), the window doubles up to
  /// `maxWindow`; after a wait that blocked it is `window` again. A sleep never passes the
  /// earliest timer or deadline. Added latency of an fd or subscriber event: at most the
  /// current window (`maxWindow` under sustained traffic). 0: off (default).
  void setBatchWindow(std::chrono::nanoseconds window, std::chrono::nanoseconds maxWindow = {}) noexcept;
  /// From a callback: no batch sleep after this dispatch, and the window falls back to the
  /// first one (e.g. a receive queue is filling up faster than the window allows).
  void skipNextBatchWindow() noexcept;
  /// The window of run()'s latest batch sleep (the first window before any), for tests and
  /// stats.
  [[nodiscard]] std::chrono::nanoseconds currentBatchWindow() const noexcept;
  /// true when the iceoryx back end (ipc::Waiter) is in use.
  [[nodiscard]] bool usesWaiter() const noexcept;

 private:
  explicit Loop(std::unique_ptr<LoopImpl> impl) noexcept;
  std::unique_ptr<LoopImpl> m_impl;
};

}  // namespace openvcu::service
