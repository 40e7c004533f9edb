// The loop's poll back end (no iceoryx): fds, timers, deadlines, batch windows, stop, removal. The iceoryx back end
// (frame subscribers through ipc::Waiter) is tested in test_service_runtime with a real RouDi.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

#include "openvcu/service/loop.hpp"

namespace service = openvcu::service;
using namespace std::chrono_literals;

namespace {

/// A pipe whose read end a loop watches.
struct Pipe {
  Pipe() { REQUIRE(::pipe(fds) == 0); }
  Pipe(const Pipe&) = delete;
  Pipe& operator=(const Pipe&) = delete;
  ~Pipe() {
    ::close(fds[0]);
    ::close(fds[1]);
  }
  void put() const {
    const char byte = 'x';
    REQUIRE(::write(fds[1], &byte, 1) == 1);
  }
  void take() const {
    char byte = 0;
    REQUIRE(::read(fds[0], &byte, 1) == 1);
  }
  [[nodiscard]] int readEnd() const { return fds[0]; }
  int fds[2]{-1, -1};
};

service::Loop makeLoop() {
  auto loopResult = service::Loop::create();
  REQUIRE(loopResult.ok());
  return std::move(*loopResult);
}

}  // namespace

TEST_CASE("a readable fd calls its callback, and an idle loop waits without calling anything") {
  service::Loop sut = makeLoop();
  Pipe pipe;
  int calls = 0;
  REQUIRE(sut.addFd(pipe.readEnd(),
                    [&] {
                      ++calls;
                      pipe.take();
                    })
              .ok());

  pipe.put();
  CHECK(sut.runOnce(5s));
  CHECK(calls == 1);
  CHECK(sut.runOnce(20ms));  // nothing ready: the wait times out
  CHECK(calls == 1);
  CHECK_FALSE(sut.usesWaiter());
}

TEST_CASE("a timer ticks through the loop with its deadline and cycle number") {
  service::Loop sut = makeLoop();
  auto timerResult = service::PeriodicTimer::create(2ms);
  REQUIRE(timerResult.ok());
  std::vector<service::TimerTick> ticks;
  REQUIRE(sut.addTimer(*timerResult,
                       [&](const service::TimerTick& tick) {
                         ticks.push_back(tick);
                         if (ticks.size() == 3) sut.stop(0);
                       })
              .ok());

  const int exitCode = sut.run();

  CHECK(exitCode == 0);
  REQUIRE(ticks.size() == 3);
  CHECK(ticks[0].cycle >= 1);
  CHECK(ticks[2].cycle > ticks[1].cycle);
  CHECK(ticks[2].deadline > ticks[1].deadline);
}

TEST_CASE("stop from another thread ends run with its exit code") {
  service::Loop sut = makeLoop();
  constexpr int EXIT_CODE = 3;

  std::thread stopper([&] {
    std::this_thread::sleep_for(10ms);
    sut.stop(EXIT_CODE);
  });
  const int exitCode = sut.run();
  stopper.join();

  CHECK(exitCode == EXIT_CODE);
  CHECK(sut.stopped());
  CHECK_FALSE(sut.runOnce(0ns));
}

TEST_CASE("an fd removed inside its own callback is not called again") {
  service::Loop sut = makeLoop();
  Pipe pipe;
  int calls = 0;
  REQUIRE(sut.addFd(pipe.readEnd(),
                    [&] {
                      ++calls;
                      sut.removeFd(pipe.readEnd());  // leaves the byte unread: level-triggered would call again
                    })
              .ok());

  pipe.put();
  sut.runOnce(1s);
  sut.runOnce(20ms);

  CHECK(calls == 1);
}

TEST_CASE("fds are refused when negative or already watched") {
  service::Loop sut = makeLoop();
  Pipe pipe;
  REQUIRE(sut.addFd(pipe.readEnd(), [] {}).ok());

  const auto duplicate = sut.addFd(pipe.readEnd(), [] {});
  const auto negative = sut.addFd(-1, [] {});

  REQUIRE_FALSE(duplicate.ok());
  CHECK(duplicate.error().message.find("already watched") != std::string::npos);
  CHECK_FALSE(negative.ok());
}

TEST_CASE("a callback that throws stops the loop with exit code 1 instead of unwinding through the wait") {
  service::Loop sut = makeLoop();
  Pipe pipe;
  REQUIRE(sut.addFd(pipe.readEnd(), [] { throw std::runtime_error("bug"); }).ok());

  pipe.put();
  const int exitCode = sut.run();

  CHECK(exitCode == 1);
}

TEST_CASE("with a batch window, what arrives during the window is handled in one dispatch") {
  service::Loop sut = makeLoop();
  sut.setBatchWindow(200ms);
  Pipe pipe;
  std::vector<int> batches;
  std::thread writer;
  REQUIRE(sut.addFd(pipe.readEnd(),
                    [&] {
                      char bytes[16];
                      const ssize_t got = ::read(pipe.readEnd(), bytes, sizeof bytes);
                      batches.push_back(static_cast<int>(got));
                      if (batches.size() == 1) {
                        // Three more bytes arrive while the loop sits out its window.
                        writer = std::thread([&pipe] {
                          for (int i = 0; i < 3; ++i) pipe.put();
                        });
                      } else {
                        sut.stop(0);
                      }
                    })
              .ok());
  pipe.put();
  const auto start = std::chrono::steady_clock::now();
  CHECK(sut.run() == 0);
  const auto elapsed = std::chrono::steady_clock::now() - start;
  writer.join();
  REQUIRE(batches.size() == 2);
  CHECK(batches[0] == 1);
  CHECK(batches[1] == 3);  // one wake-up for the three bytes written during the window
  CHECK(elapsed >= 200ms);
}

// ---- timers and deadlines without fds in the wait (docs/design/loop-wakeups.md) ----------

TEST_CASE("a timer ends a wait at its deadline, never before it, although the wait watches no timer fd") {
  service::Loop sut = makeLoop();
  constexpr auto PERIOD = 20ms;
  const auto first = std::chrono::steady_clock::now() + PERIOD;
  auto timerResult = service::PeriodicTimer::create(PERIOD, first);
  REQUIRE(timerResult.ok());
  std::vector<service::TimerTick> ticks;
  std::vector<std::chrono::steady_clock::time_point> calledAt;
  REQUIRE(sut.addTimer(*timerResult,
                       [&](const service::TimerTick& tick) {
                         ticks.push_back(tick);
                         calledAt.push_back(std::chrono::steady_clock::now());
                       })
              .ok());

  const auto start = std::chrono::steady_clock::now();
  CHECK(sut.runOnce(10s));  // the timer, not the 10 s timeout, ends this wait
  const auto elapsed = std::chrono::steady_clock::now() - start;

  REQUIRE(ticks.size() == 1);
  CHECK(ticks[0].cycle == 1);
  CHECK(ticks[0].deadline == first);
  CHECK(calledAt[0] >= first);  // never early
  CHECK(elapsed < 5s);
}

TEST_CASE("a loop that was late gets one tick that counts the missed deadlines") {
  service::Loop sut = makeLoop();
  constexpr auto PERIOD = 2ms;
  constexpr auto LATE = 30ms;  // >= 14 deadlines pass while the callback below blocks
  auto timerResult = service::PeriodicTimer::create(PERIOD);
  REQUIRE(timerResult.ok());
  std::vector<service::TimerTick> ticks;
  REQUIRE(sut.addTimer(*timerResult,
                       [&](const service::TimerTick& tick) {
                         ticks.push_back(tick);
                         if (ticks.size() == 1) std::this_thread::sleep_for(LATE);
                       })
              .ok());

  while (ticks.size() < 2) REQUIRE(sut.runOnce(5s));

  CHECK(ticks[1].missed >= 10);
  CHECK(ticks[1].cycle == ticks[0].cycle + ticks[1].missed + 1);
  CHECK(timerResult->missedCycles() == ticks[0].missed + ticks[1].missed);
}

TEST_CASE("a deadline runs once at its time, again only when set again, and not after removal") {
  service::Loop sut = makeLoop();
  int calls = 0;
  auto deadlineResult = sut.addDeadline([&] { ++calls; });
  REQUIRE(deadlineResult.ok());
  const service::Loop::DeadlineId sut_deadline = *deadlineResult;

  CHECK(sut.runOnce(20ms));  // unset: nothing due
  CHECK(calls == 0);

  const auto due = std::chrono::steady_clock::now() + 10ms;
  sut.setDeadline(sut_deadline, due);
  CHECK(sut.runOnce(10s));
  CHECK(calls == 1);
  CHECK(std::chrono::steady_clock::now() >= due);
  CHECK(sut.runOnce(20ms));  // one shot
  CHECK(calls == 1);

  sut.setDeadline(sut_deadline, std::chrono::steady_clock::now());
  sut.removeDeadline(sut_deadline);
  CHECK(sut.runOnce(20ms));
  CHECK(calls == 1);
}

TEST_CASE("an fd, a timer and a deadline share one loop, each called for its own reason") {
  service::Loop sut = makeLoop();
  Pipe pipe;
  int fdCalls = 0;
  std::uint64_t ticks = 0;
  int deadlineCalls = 0;
  REQUIRE(sut.addFd(pipe.readEnd(),
                    [&] {
                      ++fdCalls;
                      pipe.take();
                    })
              .ok());
  auto timerResult = service::PeriodicTimer::create(5ms);
  REQUIRE(timerResult.ok());
  REQUIRE(sut.addTimer(*timerResult, [&](const service::TimerTick& tick) { ticks += 1 + tick.missed; }).ok());
  auto deadlineResult = sut.addDeadline([&] { ++deadlineCalls; });
  REQUIRE(deadlineResult.ok());
  sut.setDeadline(*deadlineResult, std::chrono::steady_clock::now() + 12ms);

  pipe.put();
  const auto until = std::chrono::steady_clock::now() + 40ms;
  while (std::chrono::steady_clock::now() < until) REQUIRE(sut.runOnce(until - std::chrono::steady_clock::now()));

  CHECK(fdCalls == 1);
  CHECK(deadlineCalls == 1);
  CHECK(ticks >= 7);  // deadlines at 5, 10, ..., 35 ms passed; each counted once, ticked or missed
  CHECK(ticks == timerResult->cycles());
}

TEST_CASE("a timer removed by its fd is not called again") {
  service::Loop sut = makeLoop();
  auto timerResult = service::PeriodicTimer::create(1ms);
  REQUIRE(timerResult.ok());
  int calls = 0;
  REQUIRE(sut.addTimer(*timerResult, [&](const service::TimerTick&) { ++calls; }).ok());
  REQUIRE(sut.runOnce(5s));
  REQUIRE(calls == 1);

  sut.removeFd(timerResult->fd());
  CHECK(sut.runOnce(20ms));

  CHECK(calls == 1);
}

TEST_CASE("stop from another thread wakes a run that waits for a far timer") {
  service::Loop sut = makeLoop();
  auto timerResult = service::PeriodicTimer::create(1h);
  REQUIRE(timerResult.ok());
  REQUIRE(sut.addTimer(*timerResult, [](const service::TimerTick&) {}).ok());
  constexpr int EXIT_CODE = 4;
  // run() has started when a deadline due at once has run; then only the far timer is left
  std::atomic<bool> running{false};
  auto started = sut.addDeadline([&] { running.store(true); });
  REQUIRE(started.ok());
  sut.setDeadline(*started, std::chrono::steady_clock::now());

  std::thread stopper([&] {
    const auto giveUp = std::chrono::steady_clock::now() + 5s;
    while (!running.load() && std::chrono::steady_clock::now() < giveUp) std::this_thread::yield();
    sut.stop(EXIT_CODE);
  });
  const auto start = std::chrono::steady_clock::now();
  const int exitCode = sut.run();
  stopper.join();

  CHECK(running.load());
  CHECK(exitCode == EXIT_CODE);
  CHECK(std::chrono::steady_clock::now() - start < 5s);
}

TEST_CASE("a batch window never delays a timer past its deadline") {
  service::Loop sut = makeLoop();
  sut.setBatchWindow(10s);  // far longer than the timer's deadline below
  Pipe pipe;
  REQUIRE(sut.addFd(pipe.readEnd(), [&] { pipe.take(); }).ok());
  const auto first = std::chrono::steady_clock::now() + 30ms;
  auto timerResult = service::PeriodicTimer::create(1h, first);
  REQUIRE(timerResult.ok());
  std::chrono::steady_clock::time_point tickedAt{};
  REQUIRE(sut.addTimer(*timerResult,
                       [&](const service::TimerTick&) {
                         tickedAt = std::chrono::steady_clock::now();
                         sut.stop(0);
                       })
              .ok());

  pipe.put();  // the fd dispatch starts a 10 s window; the timer must cut it short
  CHECK(sut.run() == 0);

  CHECK(tickedAt >= first);
  CHECK(tickedAt < first + 5s);
}

TEST_CASE("the batch window doubles up to its maximum while work keeps coming and falls back after a wait that blocked") {
  service::Loop sut = makeLoop();
  constexpr auto FIRST = 1ms;
  constexpr auto MAX = 4ms;
  constexpr int BUSY_CALLS = 10;  // each finds the next byte already waiting
  sut.setBatchWindow(FIRST, MAX);
  Pipe pipe;
  std::vector<std::chrono::nanoseconds> windows;  // the window chosen before each call
  std::thread writer;
  REQUIRE(sut.addFd(pipe.readEnd(),
                    [&] {
                      pipe.take();
                      windows.push_back(sut.currentBatchWindow());
                      const auto calls = static_cast<int>(windows.size());
                      if (calls < BUSY_CALLS) {
                        pipe.put();
                      } else if (calls == BUSY_CALLS) {
                        writer = std::thread([&pipe] {
                          std::this_thread::sleep_for(20ms);  // the loop's next wait blocks
                          pipe.put();
                        });
                      } else if (calls == BUSY_CALLS + 1) {
                        pipe.put();
                      } else {
                        sut.stop(0);
                      }
                    })
              .ok());

  pipe.put();
  CHECK(sut.run() == 0);
  writer.join();

  REQUIRE(windows.size() == BUSY_CALLS + 2);
  CHECK(windows.front() == FIRST);
  CHECK(*std::max_element(windows.begin(), windows.end()) == MAX);  // never more than the maximum
  CHECK(windows.back() == FIRST);  // the wait before the previous call blocked for ~20 ms
}
