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

enum class SourceKind : std::uint8_t { Fd, Timer, Subscriber };

struct Source {
  SourceKind kind{SourceKind::Fd};
  int fd{-1};
  PeriodicTimer* timer{nullptr};
  ipc::SampleSubscriber* subscriber{nullptr};
  std::function<void()> onReadable;
  std::function<void(const TimerTick&)> onTick;
  std::uint64_t id{};
  bool removed{false};
};

}  // namespace

struct LoopImpl {
  LoopImpl() = default;
  LoopImpl(const LoopImpl&) = delete;
  LoopImpl& operator=(const LoopImpl&) = delete;
  ~LoopImpl() {
    if (waiter) {
      for (const auto& source : sources) {
        if (source->fd >= 0 && !source->removed) waiter->detachFd(source->fd);
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
    return std::any_of(sources.begin(), sources.end(),
                       [fd](const auto& source) { return source->fd == fd && !source->removed; });
  }
  Status add(std::unique_ptr<Source> source);
  void dispatch(Source& source) noexcept;
  void waitAndDispatch(std::optional<std::chrono::nanoseconds> timeout) noexcept;
  void compact() noexcept;

  std::vector<std::unique_ptr<Source>> sources;  // unique_ptr: callbacks may add while we dispatch
  std::optional<ipc::Waiter> waiter;
  int wakeFd{-1};
  std::uint64_t nextId{1};
  bool anyRemoved{false};
  std::atomic<bool> stopRequested{false};
  std::atomic<int> exitCode{0};
  std::vector<pollfd> pollFds;  // reused between waits
  std::vector<std::uint64_t> pollIds;
  std::chrono::nanoseconds batchWindow{0};
};

Status LoopImpl::add(std::unique_ptr<Source> source) {
  source->id = nextId++;
  if (waiter) {
    if (source->kind == SourceKind::Subscriber) {
      if (auto attached = waiter->attach(*source->subscriber, source->id); !attached) return attached;
    } else if (auto attached = waiter->attachFd(source->fd, source->id); !attached) {
      return attached;
    }
  }
  sources.push_back(std::move(source));
  return {};
}

void LoopImpl::dispatch(Source& source) noexcept {
  try {
    switch (source.kind) {
      case SourceKind::Timer:
        if (const auto maybeTick = source.timer->take()) source.onTick(*maybeTick);
        break;
      case SourceKind::Fd:
      case SourceKind::Subscriber:
        source.onReadable();
        break;
    }
  } catch (...) {
    // A service callback must not throw (STYLE.md 4); if one does, the loop stops with
    // failure rather than unwinding through the wait.
    exitCode = 1;
    stopRequested = true;
  }
}

void LoopImpl::waitAndDispatch(std::optional<std::chrono::nanoseconds> timeout) noexcept {
  if (waiter) {
    for (const std::uint64_t id : waiter->waitFor(timeout.value_or(WAITER_FOREVER))) {
      if (Source* source = find(id)) dispatch(*source);
      if (stopRequested) break;
    }
  } else {
    pollFds.clear();
    pollIds.clear();
    for (const auto& source : sources) {
      if (source->removed) continue;
      pollFds.push_back(pollfd{source->fd, POLLIN, 0});
      pollIds.push_back(source->id);
    }
    int timeoutMs = -1;
    if (timeout) {
      timeoutMs = static_cast<int>(
          std::clamp<std::int64_t>(std::chrono::ceil<std::chrono::milliseconds>(*timeout).count(), 0, 1'000'000'000));
    }
    const int rc = ::poll(pollFds.data(), static_cast<nfds_t>(pollFds.size()), timeoutMs);
    if (rc > 0) {
      for (std::size_t i = 0; i < pollFds.size() && !stopRequested; ++i) {
        if (pollFds[i].revents == 0) continue;
        if (Source* source = find(pollIds[i])) dispatch(*source);
      }
    }
  }
  if (anyRemoved) compact();
}

void LoopImpl::compact() noexcept {
  std::erase_if(sources, [](const auto& source) { return source->removed; });
  anyRemoved = false;
}

Result<Loop> Loop::create() {
  auto impl = std::make_unique<LoopImpl>();
  impl->wakeFd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (impl->wakeFd < 0) return Error{std::string("loop: eventfd failed: ") + std::strerror(errno)};
  auto wake = std::make_unique<Source>();
  wake->fd = impl->wakeFd;
  wake->onReadable = [fd = impl->wakeFd] {
    std::uint64_t count = 0;
    [[maybe_unused]] const auto got = ::read(fd, &count, sizeof(count));
  };
  if (auto added = impl->add(std::move(wake)); !added) return added.error();
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
    if (source->fd != fd || source->removed || fd == m_impl->wakeFd) continue;
    source->removed = true;
    m_impl->anyRemoved = true;
    if (m_impl->waiter) m_impl->waiter->detachFd(fd);
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

Status Loop::addSubscriber(ipc::SampleSubscriber& subscriber, std::function<void()> onData) {
  LoopImpl& impl = *m_impl;
  if (!impl.waiter) {
    // Switch back ends: every fd watched so far moves to the Waiter's fd watcher.
    auto waiterResult = ipc::Waiter::create();
    if (!waiterResult) return waiterResult.error();
    for (const auto& source : impl.sources) {
      if (source->removed) continue;
      if (auto attached = waiterResult->attachFd(source->fd, source->id); !attached) return attached;
    }
    impl.waiter.emplace(std::move(*waiterResult));
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
  while (!m_impl->stopRequested) {
    m_impl->waitAndDispatch(std::nullopt);
    if (m_impl->batchWindow.count() > 0 && !m_impl->stopRequested) {
      // Let what arrives next gather for one window: one wake-up handles a batch.
      // Absolute deadline from the end of this dispatch (the wait itself is not batched).
      timespec deadline{};
      ::clock_gettime(CLOCK_MONOTONIC, &deadline);
      const std::int64_t ns = deadline.tv_nsec + m_impl->batchWindow.count();
      deadline.tv_sec += static_cast<time_t>(ns / 1'000'000'000);
      deadline.tv_nsec = static_cast<long>(ns % 1'000'000'000);
      while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
      }
    }
  }
  return m_impl->exitCode;
}

void Loop::setBatchWindow(std::chrono::nanoseconds window) noexcept {
  m_impl->batchWindow = std::max(window, std::chrono::nanoseconds{0});
}

bool Loop::runOnce(std::chrono::nanoseconds timeout) {
  if (m_impl->stopRequested) return false;
  m_impl->waitAndDispatch(timeout);
  return !m_impl->stopRequested;
}

void Loop::stop(int exitCode) noexcept {
  m_impl->exitCode = exitCode;
  m_impl->stopRequested = true;
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto written = ::write(m_impl->wakeFd, &one, sizeof(one));
}

bool Loop::stopped() const noexcept {
  return m_impl->stopRequested;
}

bool Loop::usesWaiter() const noexcept {
  return m_impl->waiter.has_value();
}

}  // namespace openvcu::service
