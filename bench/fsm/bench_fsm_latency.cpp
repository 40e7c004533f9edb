// The fsm benchmark (docs/benchmarks.md, section "fsm"): the latency from a signal change in
// the shared signal table to vcu-fsm's write of the commanded value. Run it through
// bench/fsm/run_fsm_bench.sh, which starts vcu-fsm on bench/fsm/bench_fsm.json in the
// sandbox; by hand:
//   bench_fsm_latency --config vehicle.json [--count 5000] [--noise 1300]
//   bench_fsm_latency --config vehicle.json --idle 30
//
// Latency mode (default). vcu-fsm runs a machine whose state "Bench" has two
// self-transitions: HS_FastUpdSOC gt 50 commands Disconnect_Rins_Meas = 1, le 50 commands 0.
// For each of --count samples:
//   1. sleep a random 2..10 ms (clock_nanosleep on an absolute CLOCK_MONOTONIC deadline), so
//      that vcu-fsm is asleep on the table's change futex when the change comes;
//   2. t = openvcu::clock::monotonicNs(); writeBus(trigger, 60 or 40 alternately, t);
//   3. wait (SignalTable::waitForChange on the change epoch: no busy loop) until the command
//      plane of the target has a new update (its update counter grew) with the expected value
//      (1 after 60, 0 after 40), or 1 s passed (a timeout, counted);
//   4. latency = command.timestampNs - t: vcu-fsm stamps a command with its own
//      CLOCK_MONOTONIC just before writing it, and every process shares that clock. Also
//      recorded: "observed" = when this program saw the command - t (includes its own wake-up).
// The first value is chosen opposite to the trigger's current bus value, so that a second
// run against the same vcu-fsm makes a transition from the first sample on.
//
// --noise RATE: a second thread writes RATE bus updates per second (absolute deadlines)
// rewriting the four HVLP InverterStatus signals with 8 in turn. The machine reads them (its
// fault transitions test them for 1 and 13) but their value does not change, so vcu-fsm wakes
// on every write, re-reads its signals and must filter them out without evaluating; that is
// the load a running can-rx puts on it (the HHEA bus carries ~1300 frames/s).
//
// --idle SECONDS: only sleeps SECONDS (the script measures vcu-fsm's CPU meanwhile) and
// reports how often the table's change epoch moved in that time (any writer: a moving epoch
// wakes vcu-fsm).
//
// Output: one "key value..." line per result, for the script to grep:
//   latency_us p50 .. p90 .. p99 .. p99.9 .. max .. mean ..
//   observed_us p50 .. (same keys)
//   samples N timeouts N unexpected N
//   noise writes N rate_hz R
// exit: 0 done (even with timeouts: the script judges), 1 start-up failure.

#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "openvcu/core/clock.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace {

using namespace openvcu;

constexpr std::int64_t NS_PER_MS = 1'000'000;
constexpr std::int64_t NS_PER_S = 1'000'000'000;

void sleepUntil(std::int64_t deadlineNs) {
  timespec deadline{};
  deadline.tv_sec = static_cast<time_t>(deadlineNs / NS_PER_S);
  deadline.tv_nsec = static_cast<long>(deadlineNs % NS_PER_S);
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) != 0) {
  }
}

/// The q-quantile (0..1) of sorted values (nearest rank).
double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  const auto rank = static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5);
  return sorted[std::min(rank, sorted.size() - 1)];
}

void printDistribution(const char* name, std::vector<double> values) {
  std::sort(values.begin(), values.end());
  double sum = 0;
  for (double v : values) sum += v;
  std::printf("%s p50 %.1f p90 %.1f p99 %.1f p99.9 %.1f max %.1f mean %.1f min %.1f\n", name,
              quantile(values, 0.50), quantile(values, 0.90), quantile(values, 0.99), quantile(values, 0.999),
              values.empty() ? 0.0 : values.back(), values.empty() ? 0.0 : sum / static_cast<double>(values.size()),
              values.empty() ? 0.0 : values.front());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fsm benchmark: latency from a table change to vcu-fsm's command (docs/benchmarks.md, fsm)"};
  std::string configPath;
  int count = 5000;
  double noiseRate = 0;
  double idleSeconds = 0;
  int minGapMs = 2;
  int maxGapMs = 10;
  int timeoutMs = 1000;
  unsigned seed = 1;
  std::string triggerKey = "VIC.HVESSD2_PGN61585.HS_FastUpdSOC";
  std::string targetKey = "Vehicle_Control_Unit.PDU_Rx_1.Disconnect_Rins_Meas";
  std::string dumpPath;
  app.add_option("--config", configPath, "vehicle configuration (vehicle.json) vcu-fsm runs with")->required();
  app.add_option("--count", count, "samples (default 5000)")->check(CLI::Range(1, 10'000'000));
  app.add_option("--noise", noiseRate, "bus writes/s of unchanged values to signals the machine reads (default 0)")
      ->check(CLI::Range(0.0, 1'000'000.0));
  app.add_option("--idle", idleSeconds, "only sleep this long and report the table's epoch changes")
      ->check(CLI::Range(0.0, 86'400.0));
  app.add_option("--min-gap-ms", minGapMs, "shortest random pause before a sample (default 2)")->check(CLI::Range(0, 10'000));
  app.add_option("--max-gap-ms", maxGapMs, "longest random pause before a sample (default 10)")->check(CLI::Range(0, 10'000));
  app.add_option("--timeout-ms", timeoutMs, "a sample without the command after this is a timeout (default 1000)")
      ->check(CLI::Range(1, 60'000));
  app.add_option("--seed", seed, "random seed of the pauses (default 1)");
  app.add_option("--trigger", triggerKey, "signal written (bus plane)");
  app.add_option("--target", targetKey, "signal whose command is awaited");
  app.add_option("--dump", dumpPath, "write every sample as CSV (index,value,latency_ns,observed_ns; -1 = timeout)");
  CLI11_PARSE(app, argc, argv);
  if (maxGapMs < minGapMs) maxGapMs = minGapMs;

  auto vehicleResult = config::loadVehicleConfig(configPath);
  if (!vehicleResult) {
    std::cerr << "error: " << vehicleResult.error().toString() << '\n';
    return 1;
  }
  auto catalogResult = config::buildCatalog(*vehicleResult);
  if (!catalogResult) {
    std::cerr << "error: " << catalogResult.error().toString() << '\n';
    return 1;
  }
  const signals::Catalog& catalog = *catalogResult;
  // AttachOnly: vcu-fsm must already have the table (else nobody answers).
  auto tableResult = signals::SignalTable::open(catalog, vehicleResult->instance, signals::OpenMode::AttachOnly);
  if (!tableResult) {
    std::cerr << "error: " << tableResult.error().toString() << '\n';
    return 1;
  }
  signals::SignalTable& table = *tableResult;

  if (idleSeconds > 0) {
    const std::uint32_t before = table.changeEpoch();
    const std::int64_t start = openvcu::clock::monotonicNs();
    sleepUntil(start + static_cast<std::int64_t>(idleSeconds * static_cast<double>(NS_PER_S)));
    const std::uint32_t after = table.changeEpoch();
    const std::uint32_t moved = (after - before) & 0x7FFF'FFFFu;  // 31 bits, wrapping
    std::printf("idle seconds %.3f epoch_changes %u\n",
                static_cast<double>(openvcu::clock::monotonicNs() - start) / static_cast<double>(NS_PER_S), moved);
    return 0;
  }

  auto triggerResult = catalog.find(triggerKey);
  auto targetResult = catalog.find(targetKey);
  if (!triggerResult || !targetResult) {
    std::cerr << "error: " << (!triggerResult ? triggerResult.error() : targetResult.error()).toString() << '\n';
    return 1;
  }
  const signals::SignalIndex trigger = *triggerResult;
  const signals::SignalIndex target = *targetResult;

  // ---- noise thread ---------------------------------------------------------------------
  std::vector<signals::SignalIndex> noiseSignals;
  for (const char* key : {"HVLP_SA71.HS2_Status_Feedback.InverterStatus", "HVLP_SA72.HS2_Status_Feedback_2.InverterStatus",
                          "HVLP_SA73.HS2_Status_Feedback_3.InverterStatus", "HVLP_SA74.HS2_Status_Feedback_4.InverterStatus"}) {
    auto index = catalog.find(key);
    if (!index) {
      std::cerr << "error: " << index.error().toString() << '\n';
      return 1;
    }
    noiseSignals.push_back(*index);
  }
  std::atomic<bool> stopNoise{false};
  std::atomic<std::uint64_t> noiseWrites{0};
  std::int64_t noiseStart = 0;
  std::int64_t noiseEnd = 0;
  std::thread noise;
  if (noiseRate > 0) {
    noiseStart = openvcu::clock::monotonicNs();
    noise = std::thread([&] {
      const auto period = static_cast<std::int64_t>(static_cast<double>(NS_PER_S) / noiseRate);
      std::int64_t next = openvcu::clock::monotonicNs();
      std::uint64_t n = 0;
      while (!stopNoise.load(std::memory_order_relaxed)) {
        const std::int64_t now = openvcu::clock::monotonicNs();
        table.writeBus(noiseSignals[n % noiseSignals.size()], 8.0, now, 0x71 + static_cast<std::uint16_t>(n % 4),
                       signals::Quality::Valid);
        ++n;
        noiseWrites.store(n, std::memory_order_relaxed);
        next += period;
        if (next < now - 100 * NS_PER_MS) next = now;  // far behind (the VM stalled): no burst
        sleepUntil(next);
      }
    });
    sleepUntil(openvcu::clock::monotonicNs() + 200 * NS_PER_MS);  // vcu-fsm sees the first noise change before we start
  }

  // ---- samples --------------------------------------------------------------------------
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::int64_t> gap(static_cast<std::int64_t>(minGapMs) * 1000,
                                                  static_cast<std::int64_t>(maxGapMs) * 1000);  // microseconds
  std::vector<double> latencies;
  std::vector<double> observed;
  latencies.reserve(static_cast<std::size_t>(count));
  observed.reserve(static_cast<std::size_t>(count));
  struct Row {
    double value;
    std::int64_t latencyNs;
    std::int64_t observedNs;
  };
  std::vector<Row> rows;
  if (!dumpPath.empty()) rows.reserve(static_cast<std::size_t>(count));
  int timeouts = 0;
  int unexpected = 0;

  const auto busNow = table.readBus(trigger);
  bool high = !(busNow && busNow->quality != signals::Quality::NeverReceived && busNow->value > 50);
  std::uint64_t lastUpdates = 0;
  if (const auto command = table.readCommand(target)) lastUpdates = command->updates;

  for (int i = 0; i < count; ++i, high = !high) {
    sleepUntil(openvcu::clock::monotonicNs() + gap(random) * 1000);
    const double value = high ? 60.0 : 40.0;
    const double expected = high ? 1.0 : 0.0;
    const std::int64_t t = openvcu::clock::monotonicNs();
    table.writeBus(trigger, value, t, 0xF3, signals::Quality::Valid);
    const std::int64_t giveUp = t + static_cast<std::int64_t>(timeoutMs) * NS_PER_MS;
    bool done = false;
    for (;;) {
      const std::uint32_t epoch = table.changeEpoch();
      if (const auto command = table.readCommand(target); command && command->updates != lastUpdates) {
        lastUpdates = command->updates;
        if (command->value == expected) {
          const std::int64_t seen = openvcu::clock::monotonicNs();
          latencies.push_back(static_cast<double>(command->timestampNs - t) / 1000.0);
          observed.push_back(static_cast<double>(seen - t) / 1000.0);
          if (!dumpPath.empty()) rows.push_back({value, command->timestampNs - t, seen - t});
          done = true;
          break;
        }
        ++unexpected;  // a command with the other value: not ours, keep waiting
      }
      const std::int64_t now = openvcu::clock::monotonicNs();
      if (now >= giveUp) break;
      (void)table.waitForChange(epoch, std::chrono::nanoseconds(giveUp - now));
    }
    if (!done) {
      ++timeouts;
      if (!dumpPath.empty()) rows.push_back({value, -1, -1});
    }
  }

  if (noise.joinable()) {
    stopNoise.store(true);
    noise.join();
    noiseEnd = openvcu::clock::monotonicNs();
  }

  printDistribution("latency_us", latencies);
  printDistribution("observed_us", observed);
  std::printf("samples %zu timeouts %d unexpected %d\n", latencies.size(), timeouts, unexpected);
  if (noiseRate > 0) {
    const double seconds = static_cast<double>(noiseEnd - noiseStart) / static_cast<double>(NS_PER_S);
    std::printf("noise writes %llu rate_hz %.1f\n", static_cast<unsigned long long>(noiseWrites.load()),
                seconds > 0 ? static_cast<double>(noiseWrites.load()) / seconds : 0.0);
  }
  if (!dumpPath.empty()) {
    std::ofstream out(dumpPath);
    out << "index,value,latency_ns,observed_ns\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      out << i << ',' << rows[i].value << ',' << rows[i].latencyNs << ',' << rows[i].observedNs << '\n';
    }
  }
  return 0;
}
