#include "openvcu/service/loop.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <ctime>
#include <cstring>
#include <optional>
#include <vector>

#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/waiter.hpp"

namespace openvcu::service {

namespace {

/// A wait without a deadline still returns now and then in the Waiter back end (it takes
/// only timeouts); an hour is "forever" and costs nothing.
constexpr auto WAITER_FOREVER = std::chrono::hours{1};
constexpr MonotonicTime NEVER = MonotonicTime::max();

enum class SourceKind : std::uint8_t { Fd, Timer, Subscriber, Deadline };

struct Source {
  SourceKind kind{SourceKind::Fd};
  int fd{-1};  ///< Fd: watched; Timer: the timer's fd, only to find it in removeFd (never watched)
  PeriodicTimer* timer{nullptr};
  ipc::SampleSubscriber* subscriber{nullptr};
  std::function<void()> onReadable;  ///< Fd, Subscriber, Deadline
  std::function<void(const TimerTick&)> onTick;
  MonotonicTime due{NEVER};  ///< Deadline: when onReadable runs; NEVER: not set
  std::uint64_t id{};
  bool removed{false};
};

timespec toTimespec(MonotonicTime time) noexcept {
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(time.time_since_epoch()).count();
  return timespec{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}

void sleepUntil(MonotonicTime deadline) noexcept {
  const timespec until = toTimespec(deadline);
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr) == EINTR) {
  }
}

}  // namespace

struct LoopImpl {
  LoopImpl() = default;
  LoopImpl(const LoopImpl&) = delete;
  LoopImpl& operator=(const LoopImpl&) = delete;
  ~LoopImpl() {
    waiterForWake = nullptr;
    if (waiter) {
      for (const auto& source : sources) {
        if (source->kind == SourceKind::Fd && !source->removed) waiter->detachFd(source->fd);
      }
      waiter.reset();
    }
    if (wakeFd >= 0) ::close(wakeFd);
  }

  Source* find(std::uint64_t id) noexcept {
    for (const auto& source : sources) {
      if (source->id == id && !source->removed) return source.get();
    }
    return nullptr;
  }
  bool hasFd(int fd) const noexcept {
    return std::any_of(sources.begin(), sources.end(), [fd](const auto& source) {
      return (source->kind == SourceKind::Fd || source->kind == SourceKind::Timer) && source->fd == fd &&
             !source->removed;
    });
  }
  Status add(std::unique_ptr<Source> source);
  void remove(Source& source) noexcept;
  [[nodiscard]] MonotonicTime earliestDeadline() const noexcept;
  void dispatch(Source& source) noexcept;
  bool dispatchDue(MonotonicTime now) noexcept;
  bool waitAndDispatch(MonotonicTime until) noexcept;
  void compact() noexcept;

  std::vector<std::unique_ptr<Source>> sources;  // unique_ptr: callbacks may add while we dispatch
  std::optional<ipc::Waiter> waiter;
  std::atomic<ipc::Waiter*> waiterForWake{nullptr};  // stop() from other threads
  int wakeFd{-1};  // poll back end: stop() makes it readable
  std::uint64_t nextId{1};
  bool anyRemoved{false};
  std::atomic<bool> stopRequested{false};
  std::atomic<int> exitCode{0};
  std::vector<pollfd> pollFds;  // reused between waits
  std::vector<std::uint64_t> pollIds;
  std::chrono::nanoseconds batchWindow{0};
  std::chrono::nanoseconds maxBatchWindow{0};
  std::chrono::nanoseconds currentWindow{0};
  MonotonicTime waitReturned{};  ///< when the last wait returned (before its callbacks)
  bool skipWindow{false};        ///< set by skipNextBatchWindow() during a dispatch
};

Status LoopImpl::add(std::unique_ptr<Source> source) {
  source->id = nextId++;
  if (waiter) {
    if (source->kind == SourceKind::Subscriber) {
      if (auto attached = waiter->attach(*source->subscriber, source->id); !attached) return attached;
    } else if (source->kind == SourceKind::Fd) {
      if (auto attached = waiter->attachFd(source->fd, source->id); !attached) return attached;
    }
  }
  sources.push_back(std::move(source));
  return {};
}

void LoopImpl::remove(Source& source) noexcept {
  source.removed = true;
  anyRemoved = true;
  if (waiter && source.kind == SourceKind::Fd) waiter->detachFd(source.fd);
}

MonotonicTime LoopImpl::earliestDeadline() const noexcept {
  MonotonicTime earliest = NEVER;
  for (const auto& source : sources) {
    if (source->removed) continue;
    if (source->kind == SourceKind::Timer) {
      earliest = std::min(earliest, source->timer->nextDeadline());
    } else if (source->kind == SourceKind::Deadline) {
      earliest = std::min(earliest, source->due);
    }
  }
  return earliest;
}

void LoopImpl::dispatch(Source& source) noexcept {
  try {
    source.onReadable();
  } catch (...) {
    // A service callback must not throw (STYLE.md 4); if one does, the loop stops with
    // failure rather than unwinding through the wait.
    exitCode = 1;
    stopRequested = true;
  }
}

// Timers and deadlines whose time has come, in the order they were added. Index loop:
// a callback may add sources (appended, looked at from the next wait on).
bool LoopImpl::dispatchDue(MonotonicTime now) noexcept {
  bool any = false;
  const std::size_t count = sources.size();
  for (std::size_t i = 0; i < count && !stopRequested; ++i) {
    Source& source = *sources[i];
    if (source.removed) continue;
    try {
      if (source.kind == SourceKind::Timer) {
        if (const auto maybeTick = source.timer->takeDue(now)) {
          any = true;
          source.onTick(*maybeTick);
        }
      } else if (source.kind == SourceKind::Deadline && source.due <= now) {
        any = true;
        source.due = NEVER;  // one shot: the callback may set the next one
        source.onReadable();
      }
    } catch (...) {
      exitCode = 1;
      stopRequested = true;
    }
  }
  return any;
}

// One wait until something is ready or `until` (or the earliest timer/deadline, if
// earlier), then the callbacks. Returns true when an fd or subscriber callback ran.
bool LoopImpl::waitAndDispatch(MonotonicTime until) noexcept {
  until = std::min(until, earliestDeadline());
  bool anyIo = false;
  if (waiter) {
    const auto ids = until == NEVER ? waiter->waitFor(WAITER_FOREVER) : waiter->waitUntil(until);
    for (const std::uint64_t id : ids) {
      if (stopRequested) break;
      if (Source* source = find(id)) {
        anyIo = true;
        dispatch(*source);
      }
    }
  } else {
    pollFds.clear();
    pollIds.clear();
    pollFds.push_back(pollfd{wakeFd, POLLIN, 0});
    pollIds.push_back(0);
    for (const auto& source : sources) {
      if (source->removed || source->kind != SourceKind::Fd) continue;
      pollFds.push_back(pollfd{source->fd, POLLIN, 0});
      pollIds.push_back(source->id);
    }
    timespec timeout{};
    const timespec* timeoutArg = nullptr;
    if (until != NEVER) {
      const auto left = std::max(std::chrono::nanoseconds{0}, until - std::chrono::steady_clock::now());
      timeout = timespec{static_cast<time_t>(left.count() / 1'000'000'000), static_cast<long>(left.count() % 1'000'000'000)};
      timeoutArg = &timeout;
    }
    const int rc = ::ppoll(pollFds.data(), static_cast<nfds_t>(pollFds.size()), timeoutArg, nullptr);
    if (rc > 0) {
      if (pollFds[0].revents != 0) {
        std::uint64_t count = 0;
        [[maybe_unused]] const auto got = ::read(wakeFd, &count, sizeof(count));
      }
      for (std::size_t i = 1; i < pollFds.size() && !stopRequested; ++i) {
        if (pollFds[i].revents == 0) continue;
        if (Source* source = find(pollIds[i])) {
          anyIo = true;
          dispatch(*source);
        }
      }
    }
  }
  waitReturned = std::chrono::steady_clock::now();
  if (!stopRequested) dispatchDue(waitReturned);
  if (anyRemoved) compact();
  return anyIo;
}

void LoopImpl::compact() noexcept {
  std::erase_if(sources, [](const auto& source) { return source->removed; });
  anyRemoved = false;
}

Result<Loop> Loop::create() {
  auto impl = std::make_unique<LoopImpl>();
  impl->wakeFd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (impl->wakeFd < 0) return Error{std::string("loop: eventfd failed: ") + std::strerror(errno)};
  impl->pollFds.reserve(16);
  impl->pollIds.reserve(16);
  return Loop(std::move(impl));
}

Loop::Loop(std::unique_ptr<LoopImpl> impl) noexcept : m_impl(std::move(impl)) {}
Loop::Loop(Loop&& other) noexcept = default;
Loop& Loop::operator=(Loop&& other) noexcept = default;
Loop::~Loop() = default;

Status Loop::addFd(int fd, std::function<void()> onReadable) {
  if (fd < 0) return Error{"loop: cannot watch fd " + std::to_string(fd)};
  if (m_impl->hasFd(fd)) return Error{"loop: fd " + std::to_string(fd) + " is already watched"};
  auto source = std::make_unique<Source>();
  source->fd = fd;
  source->onReadable = std::move(onReadable);
  return m_impl->add(std::move(source));
}

void Loop::removeFd(int fd) noexcept {
  for (const auto& source : m_impl->sources) {
    if (source->removed || source->fd != fd) continue;
    if (source->kind == SourceKind::Fd || source->kind == SourceKind::Timer) m_impl->remove(*source);
  }
}

Status Loop::addTimer(PeriodicTimer& timer, std::function<void(const TimerTick&)> onTick) {
  if (timer.fd() < 0) return Error{"loop: the timer has no fd (moved from?)"};
  if (m_impl->hasFd(timer.fd())) return Error{"loop: this timer is already added"};
  auto source = std::make_unique<Source>();
  source->kind = SourceKind::Timer;
  source->fd = timer.fd();
  source->timer = &timer;
  source->onTick = std::move(onTick);
  return m_impl->add(std::move(source));
}

Result<Loop::DeadlineId> Loop::addDeadline(std::function<void()> onDue) {
  auto source = std::make_unique<Source>();
  source->kind = SourceKind::Deadline;
  source->onReadable = std::move(onDue);
  Source* added = source.get();
  if (auto status = m_impl->add(std::move(source)); !status) return status.error();
  return DeadlineId{added->id};
}

void Loop::setDeadline(DeadlineId deadline, MonotonicTime due) noexcept {
  if (Source* source = m_impl->find(deadline.value); source != nullptr && source->kind == SourceKind::Deadline) {
    source->due = due;
  }
}

void Loop::removeDeadline(DeadlineId deadline) noexcept {
  if (Source* source = m_impl->find(deadline.value); source != nullptr && source->kind == SourceKind::Deadline) {
    m_impl->remove(*source);
  }
}

Status Loop::addSubscriber(ipc::SampleSubscriber& subscriber, std::function<void()> onData) {
  LoopImpl& impl = *m_impl;
  if (!impl.waiter) {
    // Switch back ends: every fd watched so far moves to the Waiter's fd watcher (timers
    // and deadlines are waited for with the WaitSet's timeout, never by the watcher).
    auto waiterResult = ipc::Waiter::create();
    if (!waiterResult) return waiterResult.error();
    for (const auto& source : impl.sources) {
      if (source->removed || source->kind != SourceKind::Fd) continue;
      if (auto attached = waiterResult->attachFd(source->fd, source->id); !attached) return attached;
    }
    impl.waiter.emplace(std::move(*waiterResult));
    impl.waiterForWake = &*impl.waiter;
  }
  auto source = std::make_unique<Source>();
  source->kind = SourceKind::Subscriber;
  source->subscriber = &subscriber;
  source->onReadable = std::move(onData);
  return impl.add(std::move(source));
}

Status Loop::addLink(can::Link& link, std::function<void()> onReadable) {
  const can::WaitHandle handle = link.waitHandle();
  if (handle.source == nullptr) return addFd(handle.fd, std::move(onReadable));
  auto* subscriber = dynamic_cast<ipc::SampleSubscriber*>(handle.source);
  if (subscriber == nullptr) return Error{"link " + link.name() + ": its wait source is not an iceoryx subscriber"};
  return addSubscriber(*subscriber, std::move(onReadable));
}

int Loop::run() {
  LoopImpl& impl = *m_impl;
  while (!impl.stopRequested) {
    const auto waitStart = std::chrono::steady_clock::now();
    impl.skipWindow = false;
    const bool anyIo = impl.waitAndDispatch(NEVER);
    if (impl.batchWindow.count() == 0 || !anyIo || impl.stopRequested) continue;
    if (impl.skipWindow) {
      impl.currentWindow = impl.batchWindow;
      continue;
    }
    // Let what arrives next gather for one window: one wake-up handles a batch. The window
    // grows (doubling, up to the maximum) while every wait finds work already waiting, and
    // falls back to the first window after a wait that blocked. Absolute deadline from the
    // end of this dispatch, never past the earliest timer or deadline.
    const bool keptComing = impl.waitReturned - waitStart < impl.batchWindow / 4;
    const auto now = std::chrono::steady_clock::now();
    impl.currentWindow = keptComing ? std::min(impl.maxBatchWindow, impl.currentWindow * 2) : impl.batchWindow;
    sleepUntil(std::min(now + impl.currentWindow, impl.earliestDeadline()));
  }
  return impl.exitCode;
}

void Loop::setBatchWindow(std::chrono::nanoseconds window, std::chrono::nanoseconds maxWindow) noexcept {
  m_impl->batchWindow = std::max(window, std::chrono::nanoseconds{0});
  m_impl->maxBatchWindow = std::max(maxWindow, m_impl->batchWindow);
  m_impl->currentWindow = m_impl->batchWindow;
}

void Loop::skipNextBatchWindow() noexcept {
  m_impl->skipWindow = true;
}

std::chrono::nanoseconds Loop::currentBatchWindow() const noexcept {
  return m_impl->currentWindow;
}

bool Loop::runOnce(std::chrono::nanoseconds timeout) {
  if (m_impl->stopRequested) return false;
  m_impl->waitAndDispatch(std::chrono::steady_clock::now() + std::max(timeout, std::chrono::nanoseconds{0}));
  return !m_impl->stopRequested;
}

void Loop::stop(int exitCode) noexcept {
  m_impl->exitCode = exitCode;
  m_impl->stopRequested = true;
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto written = ::write(m_impl->wakeFd, &one, sizeof(one));
  if (ipc::Waiter* waiter = m_impl->waiterForWake.load()) waiter->wake();
}

bool Loop::stopped() const noexcept {
  return m_impl->stopRequested;
}

bool Loop::usesWaiter() const noexcept {
  return m_impl->waiter.has_value();
}

}  // namespace openvcu::service
