// cantx::planWait (how the transmit thread waits: sleep, or stay on the CPU for an SDM due
// soon, issue 27) and cantx::TxThread on the real clock with the HHEA schedule: the SDM
// never leaves before its delta, with and without the on-CPU wait. These tests check
// decisions and order, not timing figures (those come from bench/can-tx).

#include <doctest/doctest.h>

#include "vehicle_fixture.hpp"
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <string>
#include <thread>
#include <vector>

#include "openvcu/core/clock.hpp"
#include "scheduler.hpp"
#include "tx_thread.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t US = 1'000;
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t NOW = 7'000 * MS;
constexpr std::int64_t NONE = INT64_MAX;
constexpr std::int64_t SPIN = 500 * US;
const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";

constexpr std::uint32_t S1_ES = 0x0CEFF321;
constexpr std::uint32_t S1_ES_SHM = 0x0C0EF321;
constexpr std::int64_t S1_ES_DELTA = 292 * US;  // config/hhea/schedule.json
constexpr std::size_t PAIRS_WANTED = 10;

}  // namespace

TEST_CASE("planWait: something due now runs at once") {
  const auto sut = cantx::planWait(NOW, NOW, NOW + 100 * US, SPIN);
  CHECK(sut.kind == cantx::WaitPlan::Kind::None);
}

TEST_CASE("planWait: no SDM pending sleeps until the next deadline") {
  const auto sut = cantx::planWait(NOW, NOW + 3 * MS, NONE, SPIN);
  CHECK(sut.kind == cantx::WaitPlan::Kind::Sleep);
  CHECK(sut.untilNs == NOW + 3 * MS);
}

TEST_CASE("planWait: an SDM due within the spin time is waited for on the CPU, not by a second sleep") {
  const std::int64_t due = NOW + 292 * US;
  const auto sut = cantx::planWait(NOW, due, due, SPIN);
  CHECK(sut.kind == cantx::WaitPlan::Kind::Spin);
  CHECK(sut.untilNs == due);
}

TEST_CASE("planWait: a frame due before that SDM ends the spin at its own deadline") {
  const std::int64_t due = NOW + 292 * US;
  const auto sut = cantx::planWait(NOW, NOW + 100 * US, due, SPIN);
  CHECK(sut.kind == cantx::WaitPlan::Kind::Spin);
  CHECK(sut.untilNs == NOW + 100 * US);
}

TEST_CASE("planWait: a longer delta sleeps until the spin time before the SDM, then spins") {
  const std::int64_t due = NOW + 2 * MS;
  const auto first = cantx::planWait(NOW, due, due, SPIN);
  CHECK(first.kind == cantx::WaitPlan::Kind::Sleep);
  CHECK(first.untilNs == due - SPIN);
  const auto second = cantx::planWait(due - SPIN, due, due, SPIN);
  CHECK(second.kind == cantx::WaitPlan::Kind::Spin);
  CHECK(second.untilNs == due);
}

TEST_CASE("planWait: a spin time of 0 always sleeps, until the deadline itself") {
  const std::int64_t due = NOW + 292 * US;
  const auto sut = cantx::planWait(NOW, due, due, 0);
  CHECK(sut.kind == cantx::WaitPlan::Kind::Sleep);
  CHECK(sut.untilNs == due);
}

TEST_CASE("planWait: nothing scheduled sleeps without a deadline") {
  const auto sut = cantx::planWait(NOW, NONE, NONE, SPIN);
  CHECK(sut.kind == cantx::WaitPlan::Kind::Sleep);
  CHECK(sut.untilNs == NONE);
}

namespace {

/// Feeds `guard` one window of lateness `valueNs`, with `spikes` of them at `spikeNs`.
void feedWindow(cantx::WakeGuard& guard, std::int64_t valueNs, std::size_t spikes = 0, std::int64_t spikeNs = 0) {
  for (std::size_t i = 0; i < cantx::WakeGuard::WINDOW; ++i) guard.record(i < spikes ? spikeNs : valueNs);
}

}  // namespace

TEST_CASE("WakeGuard: the cap until a window is seen, then the platform's p99 lateness plus the margin") {
  cantx::WakeGuard guard(SPIN);
  CHECK(guard.guardNs() == SPIN);
  for (std::size_t i = 0; i + 1 < cantx::WakeGuard::WINDOW; ++i) guard.record(30 * US);
  CHECK(guard.guardNs() == SPIN);  // one short of a window
  guard.record(30 * US);
  CHECK(guard.guardNs() == 30 * US + cantx::WakeGuard::MARGIN_NS);
}

TEST_CASE("WakeGuard: a window with 11 late wake-ups raises it at once and it falls only after two quiet windows") {
  cantx::WakeGuard guard(SPIN);
  feedWindow(guard, 30 * US);
  feedWindow(guard, 30 * US, 11, 200 * US);  // 11 of 1,024: the p99 is the eleventh largest
  CHECK(guard.guardNs() == 200 * US + cantx::WakeGuard::MARGIN_NS);
  feedWindow(guard, 30 * US, 10, 900 * US);  // ten are beyond the p99
  CHECK(guard.guardNs() == 200 * US + cantx::WakeGuard::MARGIN_NS);
  feedWindow(guard, 30 * US);
  CHECK(guard.guardNs() == 30 * US + cantx::WakeGuard::MARGIN_NS);
}

TEST_CASE("WakeGuard: never above the cap (sdmSpinUs) and a cap of 0 keeps it 0") {
  cantx::WakeGuard capped(SPIN);
  feedWindow(capped, 2 * MS);
  CHECK(capped.guardNs() == SPIN);
  cantx::WakeGuard off(0);
  feedWindow(off, 10 * US);
  CHECK(off.guardNs() == 0);
  cantx::WakeGuard negative(-5);
  CHECK(negative.guardNs() == 0);
}

namespace {

struct RealClock final : cantx::Clock {
  std::int64_t monotonicNs() noexcept override { return clock::monotonicNs(); }
  std::int64_t realtimeNs() noexcept override { return clock::realtimeNs(); }
};

/// Stamps the S1_ES frames with CLOCK_MONOTONIC when the scheduler hands them over; room
/// reserved up front (the transmit thread writes, the test reads after stop()).
struct PairRecorder final : cantx::TxPort {
  struct Stamp {
    std::uint32_t id;
    std::int64_t atNs;
  };
  std::vector<Stamp> stamps;
  std::atomic<std::size_t> sdms{};
  PairRecorder() { stamps.reserve(4096); }
  can::SendStatus send(std::size_t, const can::Frame& frame) noexcept override {
    if ((frame.id == S1_ES || frame.id == S1_ES_SHM) && stamps.size() < stamps.capacity()) {
      stamps.push_back(Stamp{frame.id, clock::monotonicNs()});
      if (frame.id == S1_ES) sdms.fetch_add(1, std::memory_order_release);
    }
    return can::SendStatus::Sent;
  }
};

struct ThreadFixture : openvcu::testing::VehicleTable {
  cantx::Schedule schedule;
  RealClock clock;
  PairRecorder port;
  std::unique_ptr<cantx::Scheduler> scheduler;

  ThreadFixture() : VehicleTable(HHEA, "txthread-" + std::to_string(::getpid())) {
    auto scheduleResult = cantx::loadSchedule(vehicle, catalog);
    REQUIRE_MESSAGE(scheduleResult, (scheduleResult ? "" : scheduleResult.error().toString()));
    schedule = std::move(*scheduleResult);
    const auto keepAlive = catalog.indexOf("internal.tx.keepAlive");
    REQUIRE(keepAlive);
    table->writeCommand(*keepAlive, 1, clock::monotonicNs(), 3);
    auto created = cantx::Scheduler::create(vehicle, schedule, catalog, *table, port, clock, clock::monotonicNs());
    REQUIRE_MESSAGE(created, (created ? "" : created.error().toString()));
    scheduler = std::move(*created);
  }

  /// Runs the transmit thread until PAIRS_WANTED S1_ES SDMs went out (polled, 5 s at most).
  void runThread(cantx::TxThread& sut, std::int64_t spinNs) {
    (void)sut.start(0, spinNs);
    const auto giveUp = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (port.sdms.load(std::memory_order_acquire) < PAIRS_WANTED && std::chrono::steady_clock::now() < giveUp) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    sut.stop();
    REQUIRE(port.sdms.load() >= PAIRS_WANTED);
  }

  /// Every S1_ES SDM follows its SHM by at least the delta (never early); the pairs counted.
  std::size_t checkPairs() const {
    std::size_t pairs = 0;
    std::int64_t headerNs = -1;
    for (const PairRecorder::Stamp& stamp : port.stamps) {
      if (stamp.id == S1_ES_SHM) {
        headerNs = stamp.atNs;
        continue;
      }
      REQUIRE(headerNs >= 0);  // the SHM came first
      CHECK(stamp.atNs - headerNs >= S1_ES_DELTA);
      headerNs = -1;
      ++pairs;
    }
    return pairs;
  }
};

}  // namespace

TEST_CASE("TxThread: with sdmSpinUs above the delta the S1_ES SDM waits on the CPU and never leaves early") {
  ThreadFixture f;
  cantx::TxThread sut(*f.scheduler, {}, nullptr);
  f.runThread(sut, 500 * US);
  CHECK(f.checkPairs() >= PAIRS_WANTED);
  CHECK(sut.spins() > 0);
  CHECK(sut.spinNs() > 0);
}

TEST_CASE("TxThread: with sdmSpinUs 0 the thread sleeps for every SDM, which still never leaves early") {
  ThreadFixture f;
  cantx::TxThread sut(*f.scheduler, {}, nullptr);
  f.runThread(sut, 0);
  CHECK(f.checkPairs() >= PAIRS_WANTED);
  CHECK(sut.spins() == 0);
  CHECK(sut.spinNs() == 0);
}
