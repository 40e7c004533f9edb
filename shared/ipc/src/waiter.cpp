#include "openvcu/ipc/waiter.hpp"

#include "openvcu/ipc/frame_stream.hpp"

#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "iceoryx_posh/popo/user_trigger.hpp"
#include "iceoryx_posh/popo/wait_set.hpp"
#include "iox_ports.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace openvcu::ipc {

namespace {

/// One watched fd. fired: the watcher saw it readable and has not told the caller yet;
/// reported: the caller was told, and it is re-armed at the start of the next wait.
struct WatchedFd {
  int fd{-1};
  std::uint64_t id{};
  bool fired{false};
  bool reported{false};
};

constexpr std::uint64_t CONTROL_KEY = ~std::uint64_t{0};  // epoll key of the stop eventfd

}  // namespace

struct WaiterImpl {
  WaiterImpl() = default;
  WaiterImpl(const WaiterImpl&) = delete;
  WaiterImpl& operator=(const WaiterImpl&) = delete;
  ~WaiterImpl() {
    stopWatcher();
    if (epollFd >= 0) ::close(epollFd);
  }

  Status startWatcher();
  void stopWatcher() noexcept;
  void watch() noexcept;
  /// Watches `fd` for one readiness report (EPOLLONESHOT): after the watcher saw it once it
  /// is quiet until re-armed, so a readable fd the caller has not handled yet never spins.
  bool arm(int fd, int op) const noexcept {
    epoll_event event{};
    event.events = EPOLLIN | EPOLLONESHOT;
    event.data.u64 = static_cast<std::uint64_t>(fd);
    return ::epoll_ctl(epollFd, op, fd, &event) == 0;
  }

  iox::popo::WaitSet<Waiter::CAPACITY + 1> waitSet;  // +1: the user trigger
  iox::popo::UserTrigger trigger;
  std::size_t subscriberCount{0};

  std::mutex mutex;            // guards fds and stopRequested (shared with the watcher)
  std::vector<WatchedFd> fds;  // capacity reserved at create(): no allocation in wait
  bool stopRequested{false};
  std::atomic<bool> anyFired{false};  // set by the watcher: a wait need not lock otherwise
  std::size_t reportedCount{0};       // caller's thread only: fds to re-arm
  int epollFd{-1};    // the watched fds; attach, detach and re-arm are epoll_ctl calls
                      // from the caller's thread: the watcher is never woken for them
  int controlFd{-1};  // eventfd in the epoll set: wakes the watcher only to stop it
  std::thread watcher;

  std::array<std::uint64_t, Waiter::CAPACITY> ready{};
};

Status WaiterImpl::startWatcher() {
  if (watcher.joinable()) return {};
  epollFd = ::epoll_create1(EPOLL_CLOEXEC);
  if (epollFd < 0) return Error{std::string("Waiter: epoll_create1 failed: ") + std::strerror(errno)};
  controlFd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (controlFd < 0) return Error{std::string("Waiter: eventfd failed: ") + std::strerror(errno)};
  epoll_event control{};
  control.events = EPOLLIN;
  control.data.u64 = CONTROL_KEY;
  if (::epoll_ctl(epollFd, EPOLL_CTL_ADD, controlFd, &control) != 0) {
    return Error{std::string("Waiter: epoll_ctl failed: ") + std::strerror(errno)};
  }
  try {
    watcher = std::thread([this] { watch(); });
  } catch (const std::exception& e) {
    return Error{std::string("Waiter: cannot start the fd watcher thread: ") + e.what()};
  }
  return {};
}

void WaiterImpl::stopWatcher() noexcept {
  if (watcher.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      stopRequested = true;
    }
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto written = ::write(controlFd, &one, sizeof(one));
    watcher.join();
  }
  if (controlFd >= 0) ::close(controlFd);
  controlFd = -1;
}

// The watcher thread: blocks in epoll_wait; when a watched fd becomes readable (reported
// once, EPOLLONESHOT) it marks it fired and triggers the WaitSet. It never spins and is
// never woken for bookkeeping: re-arming happens in the caller's wait.
void WaiterImpl::watch() noexcept {
  std::array<epoll_event, Waiter::CAPACITY + 1> events{};
  while (true) {
    const int count = ::epoll_wait(epollFd, events.data(), static_cast<int>(events.size()), -1);
    if (count < 0) {
      if (errno == EINTR) continue;
      return;  // cannot happen with valid arguments; the waits then simply time out
    }
    bool firedNow = false;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (stopRequested) return;
      for (int i = 0; i < count; ++i) {
        const std::uint64_t key = events[static_cast<std::size_t>(i)].data.u64;
        if (key == CONTROL_KEY) continue;
        for (WatchedFd& watched : fds) {
          if (static_cast<std::uint64_t>(watched.fd) == key && !watched.reported) {
            watched.fired = true;
            firedNow = true;
          }
        }
      }
    }
    if (firedNow) {
      anyFired = true;
      trigger.trigger();
    }
  }
}

Result<Waiter> Waiter::create() {
  if (!Runtime::initialized()) return Error{"cannot create a Waiter: call ipc::Runtime::init first"};
  auto impl = std::make_unique<WaiterImpl>();
  impl->fds.reserve(CAPACITY);
  auto attachResult = impl->waitSet.attachEvent(impl->trigger);
  if (attachResult.has_error()) return Error{"Waiter: cannot attach its wake-up trigger"};
  return Waiter(std::move(impl));
}

Waiter::Waiter(std::unique_ptr<WaiterImpl> impl) noexcept : m_impl(std::move(impl)) {}
Waiter::Waiter(Waiter&& other) noexcept = default;
Waiter& Waiter::operator=(Waiter&& other) noexcept = default;
Waiter::~Waiter() = default;

Status Waiter::attach(SampleSubscriber& subscriber, std::uint64_t id) {
  if (m_impl->subscriberCount + m_impl->fds.size() >= CAPACITY) {
    return Error{"Waiter is full (" + std::to_string(CAPACITY) + " attachments)"};
  }
  auto attachResult = m_impl->waitSet.attachState(subscriber.m_impl->port, iox::popo::SubscriberState::HAS_DATA, id);
  if (attachResult.has_error()) {
    return Error{"Waiter: cannot attach subscriber " + subscriber.topic().toString() +
                 (attachResult.get_error() == iox::popo::WaitSetError::ALREADY_ATTACHED ? ": already attached"
                                                                                        : ": wait set full")};
  }
  ++m_impl->subscriberCount;
  return {};
}

void Waiter::detach(SampleSubscriber& subscriber) noexcept {
  if (m_impl->subscriberCount == 0) return;
  const auto before = m_impl->waitSet.size();
  m_impl->waitSet.detachState(subscriber.m_impl->port, iox::popo::SubscriberState::HAS_DATA);
  if (m_impl->waitSet.size() < before) --m_impl->subscriberCount;
}

Status Waiter::attachLink(const can::WaitHandle& handle, std::uint64_t id) {
  if (handle.source != nullptr) {
    auto* subscriber = dynamic_cast<SampleSubscriber*>(handle.source);
    if (subscriber == nullptr) return Error{"Waiter: the link's wait source is not an iceoryx subscriber"};
    return attach(*subscriber, id);
  }
  return attachFd(handle.fd, id);
}

void Waiter::detachLink(const can::WaitHandle& handle) noexcept {
  if (handle.source != nullptr) {
    if (auto* subscriber = dynamic_cast<SampleSubscriber*>(handle.source)) detach(*subscriber);
    return;
  }
  detachFd(handle.fd);
}

Status Waiter::attachFd(int fd, std::uint64_t id) {
  if (fd < 0) return Error{"Waiter: cannot attach fd " + std::to_string(fd)};
  {
    std::lock_guard<std::mutex> lock(m_impl->mutex);
    if (m_impl->subscriberCount + m_impl->fds.size() >= CAPACITY) {
      return Error{"Waiter is full (" + std::to_string(CAPACITY) + " attachments)"};
    }
    for (const WatchedFd& watched : m_impl->fds) {
      if (watched.fd == fd) return Error{"Waiter: fd " + std::to_string(fd) + " already attached"};
    }
  }
  if (auto started = m_impl->startWatcher(); !started) return started;
  {
    std::lock_guard<std::mutex> lock(m_impl->mutex);
    m_impl->fds.push_back(WatchedFd{fd, id});
  }
  if (!m_impl->arm(fd, EPOLL_CTL_ADD)) {
    const int error = errno;
    std::lock_guard<std::mutex> lock(m_impl->mutex);
    m_impl->fds.pop_back();
    return Error{"Waiter: cannot watch fd " + std::to_string(fd) + ": " + std::strerror(error)};
  }
  return {};
}

void Waiter::detachFd(int fd) noexcept {
  std::lock_guard<std::mutex> lock(m_impl->mutex);
  const auto erased = std::erase_if(m_impl->fds, [fd](const WatchedFd& watched) { return watched.fd == fd; });
  if (erased > 0) ::epoll_ctl(m_impl->epollFd, EPOLL_CTL_DEL, fd, nullptr);
}

std::span<const std::uint64_t> Waiter::waitFor(std::chrono::nanoseconds timeout) noexcept {
  WaiterImpl& impl = *m_impl;

  // Fds reported by the previous wait have been handled by now: watch them again (one
  // epoll_ctl each, only for fds that fired; the watcher is not woken).
  if (impl.reportedCount > 0) {
    std::lock_guard<std::mutex> lock(impl.mutex);
    for (WatchedFd& watched : impl.fds) {
      if (watched.reported) {
        watched.reported = false;
        impl.arm(watched.fd, EPOLL_CTL_MOD);
      }
    }
    impl.reportedCount = 0;
  }

  const auto nanoseconds = std::max<std::int64_t>(0, timeout.count());
  const auto notifications = impl.waitSet.timedWait(iox::units::Duration::fromNanoseconds(nanoseconds));

  std::size_t count = 0;
  for (const auto* notification : notifications) {
    // The user trigger only says "look at the fds" (or wake()): it has no id of its own.
    if (!notification->doesOriginateFrom(&impl.trigger) && count < impl.ready.size()) {
      impl.ready[count++] = notification->getNotificationId();
    }
  }
  // Collect fired fds whether or not the trigger was seen yet: the watcher may fire between
  // the WaitSet returning and here; a trigger left over then only causes one empty wake.
  // A fd fired after the exchange below is collected by the next wait (its trigger ends it).
  if (impl.anyFired.exchange(false)) {
    std::lock_guard<std::mutex> lock(impl.mutex);
    for (WatchedFd& watched : impl.fds) {
      if (watched.fired && count < impl.ready.size()) {
        watched.fired = false;
        watched.reported = true;
        ++impl.reportedCount;
        impl.ready[count++] = watched.id;
      } else if (watched.fired) {
        impl.anyFired = true;  // no room in this wait: the next one reports it
        impl.trigger.trigger();
      }
    }
  }
  return {impl.ready.data(), count};
}

std::span<const std::uint64_t> Waiter::waitUntil(std::chrono::steady_clock::time_point deadline) noexcept {
  return waitFor(std::max(std::chrono::nanoseconds{0}, deadline - std::chrono::steady_clock::now()));
}

void Waiter::wake() noexcept {
  m_impl->trigger.trigger();
}

}  // namespace openvcu::ipc
