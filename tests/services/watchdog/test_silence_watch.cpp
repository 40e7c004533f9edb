// vcu-watchdog's decisions on a set clock: when a service counts as silent, when it beats
// again, when its process may be killed (never a copy its supervisor just started).

#include <doctest/doctest.h>

#include <optional>

#include "silence_watch.hpp"

using namespace openvcu;
using watchdog::SilenceChange;
using watchdog::SilenceWatch;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0 = 1'000'000 * MS;
constexpr std::int64_t SILENT_AFTER = 1500 * MS;

/// The heartbeat slot after its `updates`-th write, stamped `stampNs`.
signals::BusValue beat(std::uint64_t updates, std::int64_t stampNs) {
  signals::BusValue value;
  value.value = static_cast<double>(updates);
  value.timestampNs = stampNs;
  value.quality = signals::Quality::Valid;
  value.updates = updates;
  return value;
}

}  // namespace

TEST_CASE("a service beating once a second is never silent") {
  SilenceWatch sut(SILENT_AFTER, T0);
  for (std::uint64_t n = 1; n <= 10; ++n) {
    const std::int64_t stamp = T0 + static_cast<std::int64_t>(n) * 1000 * MS;
    for (std::int64_t tick = 0; tick < 1000 * MS; tick += 100 * MS) {
      CHECK(sut.update(beat(n, stamp), stamp + tick) == SilenceChange::None);
    }
  }
  CHECK_FALSE(sut.silent());
  CHECK_FALSE(sut.killDue(T0 + 11'000 * MS));
}

TEST_CASE("a slot that stops counting is silent once its newest beat is older than silentAfter") {
  SilenceWatch sut(SILENT_AFTER, T0);
  const std::int64_t lastBeat = T0 + 200 * MS;
  REQUIRE(sut.update(beat(7, lastBeat), lastBeat + 10 * MS) == SilenceChange::None);
  // the same write read again and again: no new beat
  CHECK(sut.update(beat(7, lastBeat), lastBeat + SILENT_AFTER) == SilenceChange::None);
  CHECK(sut.update(beat(7, lastBeat), lastBeat + SILENT_AFTER + 1) == SilenceChange::Silent);
  CHECK(sut.silent());
  CHECK(sut.silentForNs(lastBeat + SILENT_AFTER + 1) == SILENT_AFTER + 1);
  // reported once
  CHECK(sut.update(beat(7, lastBeat), lastBeat + 5 * SILENT_AFTER) == SilenceChange::None);
}

TEST_CASE("a silent service that beats again is cleared at its next new write") {
  SilenceWatch sut(SILENT_AFTER, T0);
  REQUIRE(sut.update(beat(3, T0), T0) == SilenceChange::None);
  REQUIRE(sut.update(beat(3, T0), T0 + 2 * SILENT_AFTER) == SilenceChange::Silent);
  const std::int64_t back = T0 + 4000 * MS;
  CHECK(sut.update(beat(4, back), back + 50 * MS) == SilenceChange::Beating);
  CHECK_FALSE(sut.silent());
  CHECK(sut.lastBeatNs() == back);
  CHECK_FALSE(sut.killDue(back + 50 * MS));
}

TEST_CASE("a restarted service whose count starts again counts as beating") {
  SilenceWatch sut(SILENT_AFTER, T0);
  REQUIRE(sut.update(beat(900, T0), T0) == SilenceChange::None);
  REQUIRE(sut.update(beat(900, T0), T0 + 2 * SILENT_AFTER) == SilenceChange::Silent);
  // the table lost its values: the new process's first beat is write number 1
  CHECK(sut.update(beat(1, T0 + 3500 * MS), T0 + 3500 * MS) == SilenceChange::Beating);
}

TEST_CASE("a slot never written is silent silentAfter after the watch started") {
  SilenceWatch sut(SILENT_AFTER, T0);
  const std::optional<signals::BusValue> never = signals::BusValue{};
  CHECK(sut.update(never, T0 + SILENT_AFTER) == SilenceChange::None);
  CHECK(sut.update(never, T0 + SILENT_AFTER + 1) == SilenceChange::Silent);
}

TEST_CASE("a failed read changes nothing but the time") {
  SilenceWatch sut(SILENT_AFTER, T0);
  REQUIRE(sut.update(beat(1, T0), T0) == SilenceChange::None);
  CHECK(sut.update(std::nullopt, T0 + 1000 * MS) == SilenceChange::None);
  CHECK(sut.update(std::nullopt, T0 + SILENT_AFTER + 1) == SilenceChange::Silent);
}

TEST_CASE("a beat older than the watch counts from the watch's start, a future stamp from the read") {
  SilenceWatch sut(SILENT_AFTER, T0);
  // written long before the watchdog started (it may have hung then): silentAfter from T0
  REQUIRE(sut.update(beat(5, T0 - 60'000 * MS), T0 + 100 * MS) == SilenceChange::None);
  CHECK(sut.lastBeatNs() == T0);
  CHECK(sut.update(beat(5, T0 - 60'000 * MS), T0 + SILENT_AFTER + 1) == SilenceChange::Silent);
  // a stamp in the future cannot postpone the next silence
  const std::int64_t read = T0 + 3000 * MS;
  REQUIRE(sut.update(beat(6, read + 3'600'000 * MS), read) == SilenceChange::Beating);
  CHECK(sut.lastBeatNs() == read);
  CHECK(sut.update(beat(6, read + 3'600'000 * MS), read + SILENT_AFTER + 1) == SilenceChange::Silent);
}

TEST_CASE("a kill is due once per silence, again only silentAfter after the last attempt") {
  SilenceWatch sut(SILENT_AFTER, T0);
  REQUIRE(sut.update(beat(1, T0), T0) == SilenceChange::None);
  CHECK_FALSE(sut.killDue(T0 + 100 * MS));
  const std::int64_t detected = T0 + SILENT_AFTER + 50 * MS;
  REQUIRE(sut.update(beat(1, T0), detected) == SilenceChange::Silent);
  CHECK(sut.killDue(detected));
  sut.killAttempted(detected);
  CHECK_FALSE(sut.killDue(detected + SILENT_AFTER - 1));
  CHECK(sut.killDue(detected + SILENT_AFTER));
}

TEST_CASE("the hung process may be killed, the copy its supervisor just started may not") {
  SilenceWatch sut(SILENT_AFTER, T0);
  const std::int64_t hungStart = T0 - 60'000 * MS;
  const std::int64_t lastBeat = T0 + 500 * MS;
  REQUIRE(sut.update(beat(2, lastBeat), lastBeat) == SilenceChange::None);
  const std::int64_t now = lastBeat + 2 * SILENT_AFTER;
  REQUIRE(sut.update(beat(2, lastBeat), now) == SilenceChange::Silent);
  // it wrote the newest beat: the silence is its own
  CHECK(sut.mayKill(hungStart, now));
  CHECK(sut.mayKill(lastBeat, now));
  // started after the newest beat and not beaten yet: its start-up has START_GRACE_NS
  const std::int64_t restarted = now - 1000 * MS;
  CHECK_FALSE(sut.mayKill(restarted, now));
  CHECK_FALSE(sut.mayKill(restarted, restarted + watchdog::START_GRACE_NS));
  CHECK(sut.mayKill(restarted, restarted + watchdog::START_GRACE_NS + 1));
}

TEST_CASE("a service still starting when the watchdog starts gets the start-up grace, not silentAfter") {
  SilenceWatch sut(SILENT_AFTER, T0);
  const std::int64_t started = T0 - 200 * MS;  // started just before the watchdog, no beat yet
  const std::optional<signals::BusValue> never = signals::BusValue{};
  REQUIRE(sut.update(never, T0 + SILENT_AFTER + 1) == SilenceChange::Silent);  // reported
  CHECK_FALSE(sut.mayKill(started, T0 + SILENT_AFTER + 1));                    // not killed yet
  CHECK(sut.mayKill(started, started + watchdog::START_GRACE_NS + 1));
  // the slot still holds a beat of a predecessor, stamped before this process started
  SilenceWatch other(SILENT_AFTER, T0);
  REQUIRE(other.update(beat(40, T0 - 5000 * MS), T0) == SilenceChange::None);
  REQUIRE(other.update(beat(40, T0 - 5000 * MS), T0 + SILENT_AFTER + 1) == SilenceChange::Silent);
  CHECK_FALSE(other.mayKill(started, T0 + SILENT_AFTER + 1));
}
