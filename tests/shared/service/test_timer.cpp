// The absolute-deadline periodic timer. Timing figures are only asserted with generous
// bounds: a sleep never returns early, so "at least N deadlines passed" is safe; "at most"
// bounds are kept wide (hundreds of milliseconds of slack).

#include <doctest/doctest.h>

#include <thread>

#include "openvcu/service/timer.hpp"

namespace service = openvcu::service;
using namespace std::chrono_literals;

TEST_CASE("ticks fall on the absolute deadlines first, first + period, first + 2 period") {
  constexpr auto PERIOD = 5ms;
  const auto first = std::chrono::steady_clock::now() + PERIOD;
  auto timerResult = service::PeriodicTimer::create(PERIOD, first);
  REQUIRE(timerResult.ok());
  service::PeriodicTimer& sut = *timerResult;

  for (std::uint64_t expected = 1; expected <= 3;) {
    const auto maybeTick = sut.waitFor(5s);
    REQUIRE(maybeTick);
    CHECK(std::chrono::steady_clock::now() >= maybeTick->deadline);  // never early
    CHECK(maybeTick->deadline ==
          first + PERIOD * static_cast<std::int64_t>(maybeTick->cycle - 1));  // exactly on the grid
    CHECK(maybeTick->cycle >= expected);
    expected = maybeTick->cycle + 1;
  }
  CHECK(sut.nextDeadline() == first + PERIOD * static_cast<std::int64_t>(sut.cycles()));
}

TEST_CASE("a late reader gets one tick that counts the missed deadlines, and no catch-up burst") {
  constexpr auto PERIOD = 1s;
  constexpr std::int64_t DEADLINES_PASSED = 11;  // at -10.5 s, -9.5 s, ..., -0.5 s
  const auto first = std::chrono::steady_clock::now() - 10500ms;
  auto timerResult = service::PeriodicTimer::create(PERIOD, first);
  REQUIRE(timerResult.ok());
  service::PeriodicTimer& sut = *timerResult;

  const auto maybeTick = sut.take();
  const auto maybeBurst = sut.take();

  REQUIRE(maybeTick);
  CHECK(maybeTick->cycle == DEADLINES_PASSED);
  CHECK(maybeTick->missed == DEADLINES_PASSED - 1);
  CHECK(maybeTick->deadline == first + PERIOD * (DEADLINES_PASSED - 1));
  CHECK_FALSE(maybeBurst.has_value());  // the next tick waits for the next deadline (0.5 s away)
  CHECK(sut.missedCycles() == DEADLINES_PASSED - 1);
  CHECK(sut.nextDeadline() > std::chrono::steady_clock::now() - 100ms);
}

TEST_CASE("a reader that sleeps through several periods is told it missed at least those") {
  constexpr auto PERIOD = 2ms;
  constexpr auto SLEEP = 20ms;  // >= 9 further deadlines; asserted generously
  auto timerResult = service::PeriodicTimer::create(PERIOD);
  REQUIRE(timerResult.ok());
  service::PeriodicTimer& sut = *timerResult;

  std::this_thread::sleep_for(SLEEP);
  const auto maybeTick = sut.take();

  REQUIRE(maybeTick);
  CHECK(maybeTick->missed >= 5);
  CHECK(sut.missedCycles() == maybeTick->missed);
}

TEST_CASE("take returns nothing before the first deadline") {
  auto timerResult = service::PeriodicTimer::create(10s);
  REQUIRE(timerResult.ok());

  CHECK_FALSE(timerResult->take().has_value());
  CHECK_FALSE(timerResult->waitFor(1ms).has_value());
}

TEST_CASE("a period of zero is refused") {
  const auto timerResult = service::PeriodicTimer::create(0ns);

  REQUIRE_FALSE(timerResult.ok());
  CHECK(timerResult.error().message == "periodic timer: the period must be positive");
}

TEST_CASE("takeDue counts the deadlines at or before the given time, each once, without reading the fd") {
  constexpr auto PERIOD = 10ms;
  const auto first = std::chrono::steady_clock::now() + 1h;  // the kernel never fires during the test
  auto timerResult = service::PeriodicTimer::create(PERIOD, first);
  REQUIRE(timerResult.ok());
  service::PeriodicTimer& sut = *timerResult;

  const auto beforeFirst = sut.takeDue(first - 1ns);
  const auto atFirst = sut.takeDue(first);
  const auto again = sut.takeDue(first + PERIOD - 1ns);
  const auto late = sut.takeDue(first + PERIOD * 4);  // deadlines 2, 3, 4 and 5 passed

  CHECK_FALSE(beforeFirst.has_value());
  REQUIRE(atFirst);
  CHECK(atFirst->cycle == 1);
  CHECK(atFirst->deadline == first);
  CHECK(atFirst->missed == 0);
  CHECK_FALSE(again.has_value());
  REQUIRE(late);
  CHECK(late->cycle == 5);
  CHECK(late->missed == 3);
  CHECK(late->deadline == first + PERIOD * 4);
  CHECK(sut.missedCycles() == 3);
  CHECK(sut.nextDeadline() == first + PERIOD * 5);
}
