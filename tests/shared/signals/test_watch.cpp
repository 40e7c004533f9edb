// SignalTable::watch: a change epoch for chosen signals only (fsm and gpio sleep through
// can-rx's writes of everything else).

#include <doctest/doctest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <chrono>
#include <thread>
#include <vector>

#include "openvcu/signals/table.hpp"
#include "signals_test_support.hpp"

using namespace openvcu::signals;
using namespace std::chrono_literals;
using openvcu::signals::testing::makeNumberedCatalog;
using openvcu::signals::testing::ScopedInstance;

namespace {

constexpr std::int64_t TIME_NS = 1'234'567'890;
constexpr WriterId WRITER = 3;
constexpr std::size_t ENTRIES = 32;  // detail::MAX_WATCHES

SignalTable openTable(const Catalog& catalog, const std::string& instance) {
  auto openResult = SignalTable::open(catalog, instance);
  if (!openResult) FAIL(openResult.error().toString());
  return std::move(openResult).value();
}

}  // namespace

TEST_CASE("a watch's epoch moves for every plane and quality mark of its signals and for nothing else") {
  const ScopedInstance instance("watch-epoch");
  SignalTable sut = openTable(makeNumberedCatalog(4), instance.name());
  const std::array<SignalIndex, 2> watched{1, 3};
  SignalWatch watch = sut.watch(watched);
  REQUIRE(watch.dedicated());
  const std::uint32_t before = watch.epoch();

  for (int i = 0; i < 100; ++i) {
    sut.writeBus(0, i, TIME_NS, 0, Quality::Valid);
    sut.writeCommand(2, i, TIME_NS, WRITER);
  }
  CHECK(watch.epoch() == before);

  sut.writeBus(1, 1.0, TIME_NS, 0, Quality::Valid);
  sut.markBusQuality(1, Quality::Stale);
  sut.writeCommand(3, 1.0, TIME_NS, WRITER);
  sut.setOverride(3, 1.0, TIME_NS, WRITER);
  sut.clearOverride(3, TIME_NS, WRITER);
  CHECK(watch.epoch() == before + 5);
}

TEST_CASE("a watch wakes for a change of its signals, not for the same value written again (the table's epoch moves for both)") {
  const ScopedInstance instance("watch-change");
  SignalTable sut = openTable(makeNumberedCatalog(2), instance.name());
  const std::array<SignalIndex, 1> watched{1};
  SignalWatch watch = sut.watch(watched);
  REQUIRE(watch.dedicated());
  std::uint32_t epoch = watch.epoch();
  const auto moved = [&] {
    const std::uint32_t now = watch.epoch();
    const bool result = now != epoch;
    epoch = now;
    return result;
  };

  CHECK(sut.writeBus(1, 5.0, TIME_NS, 0x21, Quality::Valid));
  CHECK(moved());  // the first write
  const std::uint32_t tableBefore = sut.changeEpoch();
  for (int i = 1; i <= 20; ++i) sut.writeBus(1, 5.0, TIME_NS + i, 0x21, Quality::Valid);  // newer stamps only
  CHECK_FALSE(moved());
  CHECK(sut.changeEpoch() != tableBefore);  // `vcu signal watch` and fallback watches still see every write
  CHECK(sut.readBus(1)->timestampNs == TIME_NS + 20);

  sut.writeBus(1, 6.0, TIME_NS, 0x21, Quality::Valid);
  CHECK(moved());  // value
  sut.writeBus(1, 6.0, TIME_NS, 0x22, Quality::Valid);
  CHECK(moved());  // source
  sut.writeBus(1, 6.0, TIME_NS, 0x22, Quality::OutOfRange);
  CHECK(moved());  // quality
  sut.markBusQuality(1, Quality::Stale);
  CHECK(moved());
  sut.markBusQuality(1, Quality::Stale);
  CHECK_FALSE(moved());  // marked stale again: no change
  sut.writeBus(1, 6.0, TIME_NS, 0x22, Quality::OutOfRange);
  CHECK(moved());  // the write replaces a mark of Stale with OutOfRange
  sut.writeBus(1, std::nan(""), TIME_NS, 0x22, Quality::OutOfRange);
  CHECK(moved());
  sut.writeBus(1, std::nan(""), TIME_NS, 0x22, Quality::OutOfRange);
  CHECK_FALSE(moved());  // the same bits

  sut.writeCommand(1, 1.0, TIME_NS, WRITER);
  CHECK(moved());
  sut.writeCommand(1, 1.0, TIME_NS + 1, WRITER);
  CHECK_FALSE(moved());
  sut.writeCommand(1, 1.0, TIME_NS + 2, WRITER + 1);
  CHECK(moved());  // another writer
  sut.setOverride(1, 2.0, TIME_NS, WRITER);
  CHECK(moved());
  sut.setOverride(1, 2.0, TIME_NS, WRITER);
  CHECK_FALSE(moved());
  sut.clearOverride(1, TIME_NS, WRITER);
  CHECK(moved());
}

TEST_CASE("a watch's wait sleeps through other signals' writes and wakes for its own") {
  const ScopedInstance instance("watch-wait");
  SignalTable sut = openTable(makeNumberedCatalog(3), instance.name());
  const std::array<SignalIndex, 1> watched{2};
  SignalWatch watch = sut.watch(watched);
  const std::uint32_t before = watch.epoch();

  std::thread writer([&sut] {
    for (int i = 0; i < 50; ++i) {
      sut.writeBus(0, i, TIME_NS, 0, Quality::Valid);
      std::this_thread::sleep_for(1ms);  // pacing, so the waiter really sleeps through these writes; no assertion depends on it
    }
    sut.writeCommand(2, 7.0, TIME_NS, WRITER);
  });
  const std::uint32_t after = watch.wait(before, 10s);
  writer.join();

  CHECK(after == before + 1);
  CHECK(sut.readCommand(2)->value == 7.0);  // woken by the watched write, which it sees
  CHECK(watch.wait(after, 20ms) == after);  // and nothing since
}

TEST_CASE("the table has 32 watch entries, and the 33rd watch falls back to the table's epoch and still wakes") {
  const ScopedInstance instance("watch-full");
  SignalTable sut = openTable(makeNumberedCatalog(2), instance.name());
  const std::array<SignalIndex, 1> watched{0};
  std::vector<SignalWatch> watches;
  for (std::size_t i = 0; i < ENTRIES; ++i) {
    watches.push_back(sut.watch(watched));
    CHECK(watches.back().dedicated());
  }
  SignalWatch extra = sut.watch(watched);
  CHECK_FALSE(extra.dedicated());
  const std::uint32_t before = extra.epoch();
  sut.writeBus(1, 1.0, TIME_NS, 0, Quality::Valid);  // not its signal, but it falls back to every write
  CHECK(extra.epoch() != before);

  const int freed = watches[5].entry();
  watches.erase(watches.begin() + 5);  // released: its entry is free again
  SignalWatch again = sut.watch(watched);
  CHECK(again.dedicated());
  CHECK(again.entry() == freed);
}

TEST_CASE("a released watch leaves no bit behind: a new owner of its entry is not woken by the old signals") {
  const ScopedInstance instance("watch-release");
  SignalTable sut = openTable(makeNumberedCatalog(2), instance.name());
  int entry = -1;
  {
    const std::array<SignalIndex, 1> first{0};
    SignalWatch old = sut.watch(first);
    entry = old.entry();
  }
  const std::array<SignalIndex, 1> second{1};
  SignalWatch watch = sut.watch(second);
  REQUIRE(watch.entry() == entry);
  const std::uint32_t before = watch.epoch();
  sut.writeBus(0, 1.0, TIME_NS, 0, Quality::Valid);
  CHECK(watch.epoch() == before);
}

TEST_CASE("entries of a process that died are not taken while their lease runs") {
  const ScopedInstance instance("watch-dead");
  const Catalog catalog = makeNumberedCatalog(2);
  SignalTable sut = openTable(catalog, instance.name());
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    // the child takes every entry and dies without releasing them (as a SIGKILL would)
    std::vector<SignalWatch> watches;
    const std::array<SignalIndex, 1> watched{0};
    for (std::size_t i = 0; i < ENTRIES; ++i) watches.push_back(sut.watch(watched));
    ::_exit(watches.back().dedicated() ? 0 : 1);
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);

  const std::array<SignalIndex, 1> watched{1};
  SignalWatch watch = sut.watch(watched);
  CHECK_FALSE(watch.dedicated());  // WATCH_LEASE (10 s) has not passed
  const std::uint32_t before = watch.epoch();
  sut.writeBus(1, 1.0, TIME_NS, 0, Quality::Valid);
  CHECK(watch.epoch() != before);  // the fallback still sees its signal change
}
