// bench_signal_table: cost of the signal table's operations and latency of its change
// notification (docs/design/signal-table.md; results go into docs/benchmarks.md).
//
//   bench_signal_table [--quick]
//
// Prints one line per measurement. Uses the instance "bench-<pid>" and removes it at the end.
// The multi-process cases fork; each process attaches by name like a service.

#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "openvcu/core/clock.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

using namespace openvcu::signals;

namespace {

constexpr std::size_t SIGNALS = 1000;  // about the HHEA's configuration
constexpr SignalIndex HOT_SLOT = 7;
constexpr SignalIndex NOTIFY_SLOT = 8;
constexpr SignalIndex OTHER_SLOT = 9;
constexpr std::int64_t NS_PER_US = 1000;
constexpr std::int64_t NS_PER_MS = 1'000'000;

struct Options {
  std::uint64_t operations = 20'000'000;  // per single-process measurement
  std::uint64_t notifications = 20'000;
};

/// Shared between the benchmark and its children (MAP_SHARED | MAP_ANONYMOUS).
struct Shared {
  std::atomic<int> stop{0};
  std::atomic<int> ready{0};
  std::atomic<int> go{0};
  std::atomic<std::int64_t> childNsPerOp100{0};  ///< a measuring child's result, ns/op * 100
  std::atomic<std::uint64_t> latencyCount{0};
  std::int64_t latencyNs[200'000];
};

Shared* g_shared = nullptr;

void sleepNs(std::int64_t ns) {
  timespec duration{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  while (nanosleep(&duration, &duration) != 0) {
  }
}

SignalTable attach(const Catalog& catalog, const std::string& instance) {
  auto openResult = SignalTable::open(catalog, instance, OpenMode::AttachOnly);
  if (!openResult) {
    std::fprintf(stderr, "bench_signal_table: %s\n", openResult.error().toString().c_str());
    _exit(2);
  }
  return std::move(openResult).value();
}

/// The final RESULT line's fields, gathered as the passes run.
std::string g_result;

void addResult(const char* key, double value) {
  char field[96];
  std::snprintf(field, sizeof field, " %s=%.1f", key, value);
  g_result += field;
}

void report(const char* what, double nsPerOp, const char* key = nullptr) {
  std::printf("  %-58s %8.1f ns/op\n", what, nsPerOp);
  if (key != nullptr) addResult(key, nsPerOp);
}

/// Runs `operation(i)` `count` times; ns per call.
template <typename Operation>
double timePerOp(std::uint64_t count, Operation&& operation) {
  const std::int64_t start = openvcu::clock::monotonicNs();
  for (std::uint64_t i = 0; i < count; ++i) operation(i);
  return static_cast<double>(openvcu::clock::monotonicNs() - start) / static_cast<double>(count);
}

volatile double g_sink = 0;  // keeps reads from being optimised away

// ---- single process ---------------------------------------------------------------------

void singleProcess(SignalTable& table, const Options& options) {
  std::printf("uncontended, one process (%zu signals):\n", SIGNALS);
  const std::uint64_t n = options.operations;
  report("writeBus, same slot", timePerOp(n, [&](std::uint64_t i) {
           table.writeBus(HOT_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 0xF3, Quality::Valid);
         }), "write_ns");
  report("writeBus, 1000 slots round robin", timePerOp(n, [&](std::uint64_t i) {
           table.writeBus(static_cast<SignalIndex>(i % SIGNALS), static_cast<double>(i), static_cast<std::int64_t>(i),
                          0xF3, Quality::Valid);
         }));
  report("writeCommand, same slot", timePerOp(n, [&](std::uint64_t i) {
           table.writeCommand(HOT_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 3);
         }));
  report("markBusQuality, same slot", timePerOp(n, [&](std::uint64_t i) {
           table.markBusQuality(HOT_SLOT, (i & 1) != 0 ? Quality::Stale : Quality::Valid);
         }));
  report("readBus, same slot", timePerOp(n, [&](std::uint64_t) { g_sink = table.readBus(HOT_SLOT)->value; }), "read_ns");
  report("readBus, 1000 slots round robin",
         timePerOp(n, [&](std::uint64_t i) { g_sink = table.readBus(static_cast<SignalIndex>(i % SIGNALS))->value; }));
  report("read (all three planes), same slot",
         timePerOp(n, [&](std::uint64_t) { g_sink = table.read(HOT_SLOT)->bus.value; }));
  report("changeEpoch", timePerOp(n, [&](std::uint64_t) { g_sink = table.changeEpoch(); }));
}

// ---- two processes ----------------------------------------------------------------------

enum class ChildRole { Write, WriteOtherSlot, Read, MeasureWrite };

pid_t spawnChild(const Catalog& catalog, const std::string& instance, ChildRole role, std::uint64_t operations) {
  const pid_t pid = fork();
  if (pid != 0) return pid;
  SignalTable table = attach(catalog, instance);
  g_shared->ready.fetch_add(1);
  while (g_shared->go.load() == 0) {
  }
  switch (role) {
    case ChildRole::Write:
      for (std::uint64_t i = 0; g_shared->stop.load(std::memory_order_relaxed) == 0; ++i) {
        table.writeBus(HOT_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 1, Quality::Valid);
      }
      break;
    case ChildRole::WriteOtherSlot:
      for (std::uint64_t i = 0; g_shared->stop.load(std::memory_order_relaxed) == 0; ++i) {
        table.writeBus(OTHER_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 1, Quality::Valid);
      }
      break;
    case ChildRole::Read:
      while (g_shared->stop.load(std::memory_order_relaxed) == 0) g_sink = table.readBus(HOT_SLOT)->value;
      break;
    case ChildRole::MeasureWrite: {
      const double nsPerOp = timePerOp(operations, [&](std::uint64_t i) {
        table.writeBus(HOT_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 2, Quality::Valid);
      });
      g_shared->childNsPerOp100.store(static_cast<std::int64_t>(nsPerOp * 100));
      break;
    }
  }
  _exit(0);
}

/// Starts `roles`, lets them run while `measure` runs in this process, then stops them.
template <typename Measure>
void withChildren(const Catalog& catalog, const std::string& instance, std::vector<ChildRole> roles,
                  std::uint64_t operations, Measure&& measure) {
  g_shared->stop.store(0);
  g_shared->ready.store(0);
  g_shared->go.store(0);
  std::vector<pid_t> children;
  for (const ChildRole role : roles) children.push_back(spawnChild(catalog, instance, role, operations));
  while (g_shared->ready.load() < static_cast<int>(children.size())) sleepNs(100 * NS_PER_US);
  g_shared->go.store(1);
  measure();
  g_shared->stop.store(1);
  for (const pid_t pid : children) waitpid(pid, nullptr, 0);
}

void twoProcesses(SignalTable& table, const Catalog& catalog, const std::string& instance, const Options& options) {
  const std::uint64_t n = options.operations / 2;
  std::printf("two processes (on separate CPUs when the machine has them):\n");
  withChildren(catalog, instance, {ChildRole::Write}, n, [&] {
    report("readBus while another process writes that slot",
           timePerOp(n, [&](std::uint64_t) { g_sink = table.readBus(HOT_SLOT)->value; }), "read_contended_ns");
  });
  withChildren(catalog, instance, {ChildRole::Read}, n, [&] {
    report("writeBus while another process reads that slot", timePerOp(n, [&](std::uint64_t i) {
             table.writeBus(HOT_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 0, Quality::Valid);
           }), "write_contended_ns");
  });
  withChildren(catalog, instance, {ChildRole::WriteOtherSlot}, n, [&] {
    report("writeBus while another process writes another slot", timePerOp(n, [&](std::uint64_t i) {
             table.writeBus(HOT_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 0, Quality::Valid);
           }));
  });
  double parentNsPerOp = 0;
  withChildren(catalog, instance, {ChildRole::MeasureWrite}, n, [&] {
    parentNsPerOp = timePerOp(n, [&](std::uint64_t i) {
      table.writeBus(HOT_SLOT, static_cast<double>(i), static_cast<std::int64_t>(i), 0, Quality::Valid);
    });
  });
  report("writeBus, two processes writing one slot (process 1)", parentNsPerOp);
  report("writeBus, two processes writing one slot (process 2)",
         static_cast<double>(g_shared->childNsPerOp100.load()) / 100.0);
}

// ---- notification latency --------------------------------------------------------------

std::int64_t percentile(std::vector<std::int64_t>& sorted, double fraction) {
  const auto index = static_cast<std::size_t>(fraction * static_cast<double>(sorted.size() - 1));
  return sorted[index];
}

void notificationLatency(SignalTable& table, const Catalog& catalog, const std::string& instance,
                         const Options& options) {
  g_shared->stop.store(0);
  g_shared->ready.store(0);
  g_shared->latencyCount.store(0);
  const pid_t waiter = fork();
  if (waiter == 0) {
    SignalTable waiting = attach(catalog, instance);
    std::uint32_t epoch = waiting.changeEpoch();
    std::uint64_t lastUpdates = 0;
    g_shared->ready.store(1);
    for (;;) {
      const std::uint32_t next = waiting.waitForChange(epoch, std::chrono::milliseconds(100));
      const std::int64_t wokeNs = openvcu::clock::monotonicNs();
      if (g_shared->stop.load() != 0) break;
      if (next == epoch) continue;
      epoch = next;
      // One sample per write seen; writes that came while it was awake are coalesced.
      const auto maybeCommand = waiting.readCommand(NOTIFY_SLOT);
      if (!maybeCommand || maybeCommand->updates == lastUpdates) continue;
      lastUpdates = maybeCommand->updates;
      const std::uint64_t index = g_shared->latencyCount.load();
      if (index < std::size(g_shared->latencyNs)) {
        g_shared->latencyNs[index] = wokeNs - maybeCommand->timestampNs;
        g_shared->latencyCount.store(index + 1);
      }
    }
    _exit(0);
  }
  while (g_shared->ready.load() == 0) sleepNs(100 * NS_PER_US);
  // Spaced writes, so the waiter is asleep in FUTEX_WAIT each time (the case that matters).
  std::uint64_t state = 12345;
  for (std::uint64_t i = 0; i < options.notifications; ++i) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    sleepNs(200 * NS_PER_US + static_cast<std::int64_t>((state >> 33) % (200 * NS_PER_US)));
    table.writeCommand(NOTIFY_SLOT, static_cast<double>(i), openvcu::clock::monotonicNs(), 1);
  }
  sleepNs(10 * NS_PER_MS);
  g_shared->stop.store(1);
  table.writeCommand(OTHER_SLOT, 0, 0, 1);  // wake it to see the stop flag
  waitpid(waiter, nullptr, 0);

  std::vector<std::int64_t> latencies(g_shared->latencyNs, g_shared->latencyNs + g_shared->latencyCount.load());
  if (latencies.empty()) {
    std::printf("notification latency: no samples\n");
    return;
  }
  std::sort(latencies.begin(), latencies.end());
  std::printf("notification latency, write -> waiter awake in another process (%zu samples of %llu writes):\n",
              latencies.size(), static_cast<unsigned long long>(options.notifications));
  addResult("notify_p50_us", static_cast<double>(percentile(latencies, 0.50)) / 1e3);
  addResult("notify_p99_us", static_cast<double>(percentile(latencies, 0.99)) / 1e3);
  std::printf("  p50 %.1f us, p90 %.1f us, p99 %.1f us, p99.9 %.1f us, max %.1f us\n",
              static_cast<double>(percentile(latencies, 0.50)) / 1e3,
              static_cast<double>(percentile(latencies, 0.90)) / 1e3,
              static_cast<double>(percentile(latencies, 0.99)) / 1e3,
              static_cast<double>(percentile(latencies, 0.999)) / 1e3, static_cast<double>(latencies.back()) / 1e3);
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      options.operations = 1'000'000;
      options.notifications = 2'000;
    } else {
      std::fprintf(stderr, "usage: bench_signal_table [--quick]\n");
      return 2;
    }
  }
  void* memory = mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (memory == MAP_FAILED) return 1;
  g_shared = new (memory) Shared{};

  std::vector<SignalInfo> infos(SIGNALS);
  for (std::size_t i = 0; i < SIGNALS; ++i) infos[i].key = "bench.signal" + std::to_string(i);
  auto catalogResult = Catalog::create(std::move(infos));
  if (!catalogResult) return 1;
  const Catalog& catalog = *catalogResult;
  const std::string instance = "bench-" + std::to_string(getpid());
  auto openResult = SignalTable::open(catalog, instance);
  if (!openResult) {
    std::fprintf(stderr, "bench_signal_table: %s\n", openResult.error().toString().c_str());
    return 1;
  }
  SignalTable& table = *openResult;
  std::printf("signal table benchmark: %zu signals, %zu bytes, %ld CPUs\n", table.size(), table.info().bytes,
              sysconf(_SC_NPROCESSORS_ONLN));

  singleProcess(table, options);
  twoProcesses(table, catalog, instance, options);
  notificationLatency(table, catalog, instance, options);

  (void)SignalTable::remove(instance);
  std::printf("RESULT%s\n", g_result.c_str());
  return 0;
}
