#include "openvcu/ipc/waiter.hpp"

#include "openvcu/ipc/frame_stream.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <array>
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

/// One watched fd. armed: the watcher polls it; reported: it fired, the caller was told,
/// and it is armed again at the start of the next wait.
struct WatchedFd {
  int fd{-1};
  std::uint64_t id{};
  bool armed{true};
  bool fired{false};
  bool reported{false};
};

}  // namespace

struct WaiterImpl {
  WaiterImpl() = default;
  WaiterImpl(const WaiterImpl&) = delete;
  WaiterImpl& operator=(const WaiterImpl&) = delete;
  ~WaiterImpl() { stopWatcher(); }

  Status startWatcher();
  void stopWatcher() noexcept;
  void watch() noexcept;
  void nudgeWatcher() noexcept {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto written = ::write(controlFd, &one, sizeof(one));
  }

  iox::popo::WaitSet<Waiter::CAPACITY + 1> waitSet;  // +1: the user trigger
  iox::popo::UserTrigger trigger;
  std::size_t subscriberCount{0};

  std::mutex mutex;            // guards fds and stopRequested (shared with the watcher)
  std::vector<WatchedFd> fds;  // capacity reserved at create(): no allocation in wait
  bool stopRequested{false};
  int controlFd{-1};  // eventfd: wakes the watcher (re-arm, attach, stop)
  std::thread watcher;

  std::array<std::uint64_t, Waiter::CAPACITY> ready{};
};

Status WaiterImpl::startWatcher() {
  if (watcher.joinable()) return {};
  controlFd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (controlFd < 0) return Error{std::string("Waiter: eventfd failed: ") + std::strerror(errno)};
  try {
    watcher = std::thread([this] { watch(); });
  } catch (const std::exception& e) {
    ::close(controlFd);
    controlFd = -1;
    return Error{std::string("Waiter: cannot start the fd watcher thread: ") + e.what()};
  }
  return {};
}

void WaiterImpl::stopWatcher() noexcept {
  if (!watcher.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex);
    stopRequested = true;
  }
  nudgeWatcher();
  watcher.join();
  ::close(controlFd);
  controlFd = -1;
}

// The watcher thread: poll the armed fds; when one is readable, disarm it, mark it fired
// and trigger the WaitSet. It blocks in poll() otherwise (never spins: a fired fd stays
// disarmed until the caller has had a chance to handle it).
void WaiterImpl::watch() noexcept {
  std::array<pollfd, Waiter::CAPACITY + 1> pollFds{};
  while (true) {
    std::size_t count = 0;
    pollFds[count++] = pollfd{controlFd, POLLIN, 0};
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (stopRequested) return;
      for (const WatchedFd& watched : fds) {
        if (watched.armed) pollFds[count++] = pollfd{watched.fd, POLLIN, 0};
      }
    }
    const int rc = ::poll(pollFds.data(), static_cast<nfds_t>(count), -1);
    if (rc < 0) {
      if (errno == EINTR) continue;
      return;  // cannot happen with valid arguments; the waits then simply time out
    }
    if ((pollFds[0].revents & POLLIN) != 0) {
      std::uint64_t counter = 0;
      [[maybe_unused]] const auto readBytes = ::read(controlFd, &counter, sizeof(counter));
    }
    bool anyFired = false;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (stopRequested) return;
      for (std::size_t i = 1; i < count; ++i) {
        if (pollFds[i].revents == 0) continue;
        for (WatchedFd& watched : fds) {
          if (watched.fd == pollFds[i].fd && watched.armed) {
            watched.armed = false;
            watched.fired = true;
            anyFired = true;
          }
        }
      }
    }
    if (anyFired) trigger.trigger();
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
  m_impl->nudgeWatcher();
  return {};
}

void Waiter::detachFd(int fd) noexcept {
  {
    std::lock_guard<std::mutex> lock(m_impl->mutex);
    std::erase_if(m_impl->fds, [fd](const WatchedFd& watched) { return watched.fd == fd; });
  }
  if (m_impl->watcher.joinable()) m_impl->nudgeWatcher();
}

std::span<const std::uint64_t> Waiter::waitFor(std::chrono::nanoseconds timeout) noexcept {
  WaiterImpl& impl = *m_impl;

  // Fds reported by the previous wait have been handled by now: watch them again.
  bool rearmed = false;
  if (impl.watcher.joinable()) {
    std::lock_guard<std::mutex> lock(impl.mutex);
    for (WatchedFd& watched : impl.fds) {
      if (watched.reported) {
        watched.reported = false;
        watched.armed = true;
        rearmed = true;
      }
    }
  }
  if (rearmed) impl.nudgeWatcher();

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
  if (impl.watcher.joinable()) {
    std::lock_guard<std::mutex> lock(impl.mutex);
    for (WatchedFd& watched : impl.fds) {
      if (watched.fired && count < impl.ready.size()) {
        watched.fired = false;
        watched.reported = true;
        impl.ready[count++] = watched.id;
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
