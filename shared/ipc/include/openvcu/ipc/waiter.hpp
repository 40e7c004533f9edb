#pragma once
// One blocking wait for a service's inputs: frame and request subscribers (iceoryx WaitSet, no fd)
// and ordinary file descriptors such as EventBus::fileno() (LCM).
//
//   auto waiterResult = ipc::Waiter::create();
//   waiterResult->attach(rxSubscriber, RX_ID);
//   waiterResult->attachFd(eventBus.fileno(), EVENTS_ID);
//   while (running) {
//     for (std::uint64_t id : waiterResult->waitFor(std::chrono::milliseconds{100})) {
//       if (id == RX_ID) while (auto maybeSample = rxSubscriber.take()) handle(*maybeSample);
//       if (id == EVENTS_ID) eventBus.handleAll();
//     }
//   }
//
// Why a helper thread for fds: iceoryx 2.0's WaitSet waits on a semaphore in shared
// memory and has no fd, so poll() cannot wait on it. The first attachFd() starts one
// thread per Waiter that waits in epoll_wait on the fds (each armed for one report,
// EPOLLONESHOT) and wakes the WaitSet; everything else (the callbacks, take()) stays on
// the caller's thread. Attach, detach and re-arming after a report are epoll_ctl calls on
// the caller's thread: the watcher wakes only for a readable fd (and to stop). A Waiter
// without fds has no thread; timers belong in the wait's timeout (service::Loop does
// that), not here. Added latency of an fd: ~one thread wake-up.

#include <chrono>
#include <cstdint>
#include <memory>
#include <span>

#include "openvcu/can/link.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::ipc {

class SampleSubscriber;
struct WaiterImpl;

/// Waits on several frame subscribers and fds with a timeout. Movable: the WaitSet
/// itself stays put on the heap, attachments survive a move.
/// @note restricted thread-safe: attach/detach/wait from one thread; wake() from any thread.
class Waiter {
 public:
  /// Most attachments (subscribers + fds) one Waiter takes.
  static constexpr std::size_t CAPACITY = 64;

  /// Needs an initialised Runtime (the WaitSet's condition variable lives in RouDi's memory).
  static Result<Waiter> create();

  Waiter(Waiter&& other) noexcept;
  Waiter& operator=(Waiter&& other) noexcept;
  Waiter(const Waiter&) = delete;
  Waiter& operator=(const Waiter&) = delete;
  ~Waiter();

  /// Reports `id` from wait while `subscriber` has data (level-triggered: again and again
  /// until it is drained). The subscriber must stay alive while attached, or detach first
  /// (destroying an attached subscriber detaches it). Fails when full or already attached.
  Status attach(SampleSubscriber& subscriber, std::uint64_t id);
  void detach(SampleSubscriber& subscriber) noexcept;

  /// A link's wait handle (can::Link::waitHandle()): its fd (attachFd) or its subscriber
  /// (attach). Fails like those, or for a handle with neither or a source that is no
  /// ipc::SampleSubscriber. Detach with detachLink before the link goes away.
  Status attachLink(const can::WaitHandle& handle, std::uint64_t id);
  void detachLink(const can::WaitHandle& handle) noexcept;

  /// Reports `id` from wait when `fd` is readable. After it is reported, the fd is watched
  /// again from the next wait call on: handle it before waiting again, or it is reported
  /// again at once. Detach before closing the fd. Fails on a negative fd, a duplicate, or
  /// when full. The first attachFd starts the Waiter's watcher thread.
  Status attachFd(int fd, std::uint64_t id);
  void detachFd(int fd) noexcept;

  /// Blocks until something attached is ready, wake() is called or `timeout` passed.
  /// Returns the ids of what is ready (empty on timeout or wake-up). The span stays valid
  /// until the next wait call. Allocates nothing.
  std::span<const std::uint64_t> waitFor(std::chrono::nanoseconds timeout) noexcept;
  std::span<const std::uint64_t> waitUntil(std::chrono::steady_clock::time_point deadline) noexcept;

  /// Makes a current or the next wait return (for shutdown and cross-thread nudges).
  /// @note thread-safe, not async-signal-safe: from a signal handler set a flag and rely
  ///       on the wait timeout instead.
  void wake() noexcept;

 private:
  explicit Waiter(std::unique_ptr<WaiterImpl> impl) noexcept;
  std::unique_ptr<WaiterImpl> m_impl;
};

}  // namespace openvcu::ipc
