// bench_receiver: CPU time of canrx::Receiver::onFrame (link -> signal table) for one
// vehicle configuration, in process: no iceoryx, no LCM, no other process.
//
//   bench_receiver [--config config/hhea/vehicle.json] [--frames 2000000] [--repeat 7]
//                  [--seed 20240611] [--cpu 0]
//
// The frames are those of every message other nodes send on the configured buses (the
// messages whose transmitter is not the configured node), round robin over the messages,
// with random payloads drawn once from a fixed seed into a pool of POOL_FRAMES frames
// (5.8 MB, larger than L2) that the passes cycle through. Each frame is stamped 250 us after
// the previous one (4,000 frames/s, a saturated 500 kbit/s bus) so the bus-load meter and the
// period statistics see a plausible clock. The receiver writes into a private signal table
// "bench-canrx-<pid>" (POSIX shm), removed at the end; its outputs only count calls.
//
// Reported per pass: ns per frame in thread CPU time (CLOCK_THREAD_CPUTIME_ID) and in wall
// time (steady_clock); then the median and best pass and frames/s per core, and the cost of
// one part on its own: can::BusLoadMeter::add (the exact wire-bit count). Exit 1 when a
// frame was not decoded (an unknown ID, a wrong bus): the figures would not mean anything.
// Results and the command: docs/benchmarks.md, section "can-rx".

#include <sched.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "openvcu/config/catalog.hpp"
#include "openvcu/can/wire_time.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/signals/table.hpp"
#include "receiver.hpp"

namespace {

using namespace openvcu;
using Clock = std::chrono::steady_clock;

constexpr std::size_t POOL_FRAMES = 1u << 16;
constexpr std::int64_t FRAME_SPACING_NS = 250'000;  // 4,000 frames/s
constexpr std::int64_t START_NS = 1'000'000'000;
constexpr double NS_PER_S = 1e9;

/// ReceiverOutputs that only count: the app's iceoryx/LCM publishing is not measured here.
struct CountingOutputs final : canrx::ReceiverOutputs {
  std::uint64_t receivedCount{};
  std::uint64_t requestCount{};
  std::uint64_t forwardCount{};
  std::uint64_t transmitCount{};
  std::uint64_t faultCount{};
  void received(std::size_t, const can::ReceivedFrame&) noexcept override { ++receivedCount; }
  void request(std::size_t, const j1939::Request&, std::int64_t) noexcept override { ++requestCount; }
  void network(std::size_t, const can::ReceivedFrame&) noexcept override {}
  void forward(std::size_t, const can::Frame&) noexcept override { ++forwardCount; }
  bool transmit(std::size_t, const can::Frame&) noexcept override {
    ++transmitCount;
    return true;
  }
  void fault(const ipc::FaultEvent&) override { ++faultCount; }
  void dm1(const ipc::NodeDm1&) override {}
};

/// One pre-built frame and the bus it arrives on.
struct PoolFrame {
  std::size_t bus{};
  can::ReceivedFrame received{};
};

struct Pass {
  double cpuNsPerFrame{};
  double wallNsPerFrame{};
};

std::int64_t threadCpuNs() noexcept {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

bool pinToCpu(int cpu) noexcept {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return sched_setaffinity(0, sizeof set, &set) == 0;
}

/// Frames of every message another node sends, round robin, random payloads (fixed seed).
std::vector<PoolFrame> buildPool(const config::VehicleConfig& vehicle, std::uint64_t seed, std::size_t& messageCount,
                                 double& signalsPerFrame) {
  std::vector<std::pair<std::size_t, const dbc::Message*>> received;  // (bus, message)
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    for (const std::size_t messageIndex : vehicle.buses[b].messages) {
      const dbc::Message& message = vehicle.database.messages[messageIndex];
      if (message.transmitter == vehicle.node || message.pseudo) continue;
      if (message.length > can::CLASSIC_DATA_LENGTH) continue;  // TP messages: not a single frame
      received.emplace_back(b, &message);
    }
  }
  messageCount = received.size();
  std::vector<PoolFrame> pool;
  if (received.empty()) return pool;
  std::mt19937_64 random(seed);
  pool.resize(POOL_FRAMES);
  std::size_t signalSum = 0;
  for (std::size_t i = 0; i < pool.size(); ++i) {
    const auto& [bus, message] = received[i % received.size()];
    PoolFrame& slot = pool[i];
    slot.bus = bus;
    slot.received.frame.id = message->id;
    slot.received.frame.flags = message->extended ? can::FLAG_EXTENDED : 0;
    slot.received.frame.length = static_cast<std::uint8_t>(message->length);
    for (std::size_t byte = 0; byte < message->length; ++byte) {
      slot.received.frame.data[byte] = static_cast<std::uint8_t>(random() & 0xFF);
    }
    signalSum += message->signals.size();
  }
  signalsPerFrame = static_cast<double>(signalSum) / static_cast<double>(pool.size());
  return pool;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t middle = values.size() / 2;
  return values.size() % 2 == 1 ? values[middle] : (values[middle - 1] + values[middle]) / 2.0;
}

/// The bench itself; the table is opened and removed by main.
int run(const config::VehicleConfig& vehicle, const signals::Catalog& catalog, signals::SignalTable& table,
        std::uint64_t frames, int repeat, std::uint64_t seed) {
  auto receiveResult = config::loadReceiveConfig(vehicle);
  if (!receiveResult) {
    std::cerr << "bench_receiver: " << receiveResult.error().toString() << '\n';
    return 1;
  }
  CountingOutputs outputs;
  auto receiverResult = canrx::Receiver::create(vehicle, std::move(*receiveResult), catalog, table, outputs, START_NS);
  if (!receiverResult) {
    std::cerr << "bench_receiver: " << receiverResult.error().toString() << '\n';
    return 1;
  }
  canrx::Receiver& sut = *receiverResult;

  std::size_t messageCount = 0;
  double signalsPerFrame = 0.0;
  std::vector<PoolFrame> pool = buildPool(vehicle, seed, messageCount, signalsPerFrame);
  if (pool.empty()) {
    std::cerr << "bench_receiver: no message of another node on any bus of " << vehicle.path << '\n';
    return 1;
  }
  std::printf("%zu received messages (other nodes) on %zu bus(es), %.2f signals per frame, pool %zu frames, seed %llu\n",
              messageCount, vehicle.buses.size(), signalsPerFrame, pool.size(),
              static_cast<unsigned long long>(seed));

  std::int64_t nowNs = START_NS;
  std::size_t next = 0;
  auto feed = [&](std::uint64_t count) {
    for (std::uint64_t i = 0; i < count; ++i) {
      PoolFrame& slot = pool[next];
      next = next + 1 == pool.size() ? 0 : next + 1;
      nowNs += FRAME_SPACING_NS;
      slot.received.monotonicNs = nowNs;
      sut.onFrame(slot.bus, slot.received);
    }
  };

  feed(pool.size());  // warm-up: caches, branch predictors, every table slot touched once
  std::vector<Pass> passes;
  for (int r = 0; r < repeat; ++r) {
    const std::int64_t cpuStart = threadCpuNs();
    const auto wallStart = Clock::now();
    feed(frames);
    const auto wallNs = std::chrono::duration<double, std::nano>(Clock::now() - wallStart).count();
    const auto cpuNs = static_cast<double>(threadCpuNs() - cpuStart);
    const Pass pass{cpuNs / static_cast<double>(frames), wallNs / static_cast<double>(frames)};
    passes.push_back(pass);
    std::printf("pass %d: CPU %7.1f ns/frame (%6.2f Mframes/s)   wall %7.1f ns/frame (%6.2f Mframes/s)\n", r + 1,
                pass.cpuNsPerFrame, NS_PER_S / pass.cpuNsPerFrame / 1e6, pass.wallNsPerFrame,
                NS_PER_S / pass.wallNsPerFrame / 1e6);
  }

  std::vector<double> cpu, wall;
  for (const Pass& pass : passes) {
    cpu.push_back(pass.cpuNsPerFrame);
    wall.push_back(pass.wallNsPerFrame);
  }
  const double cpuMedian = median(cpu);
  const double cpuBest = *std::min_element(cpu.begin(), cpu.end());
  const double wallMedian = median(wall);
  const double wallBest = *std::min_element(wall.begin(), wall.end());
  std::printf("onFrame, %llu frames x %d passes:\n", static_cast<unsigned long long>(frames), repeat);
  std::printf("  CPU  median %7.1f ns/frame = %6.2f Mframes/s per core (best %.1f ns)\n", cpuMedian,
              NS_PER_S / cpuMedian / 1e6, cpuBest);
  std::printf("  wall median %7.1f ns/frame = %6.2f Mframes/s (best %.1f ns)\n", wallMedian,
              NS_PER_S / wallMedian / 1e6, wallBest);
  std::printf("  at 4,000 frames/s (a saturated 500 kbit/s bus): %.4f %% of one core (CPU median)\n",
              cpuMedian * 4000.0 / NS_PER_S * 100.0);

  // One part of onFrame on its own: the bus-load meter (exact wire bits per frame: the bit
  // stream, its CRC-15 and the stuff bits), which onFrame runs for every frame.
  can::BusLoadMeter meter(vehicle.buses.front().bitrate, vehicle.buses.front().dataBitrate);
  std::vector<double> meterCpu;
  for (int r = 0; r < repeat; ++r) {
    const std::int64_t cpuStart = threadCpuNs();
    for (std::uint64_t i = 0; i < frames; ++i) {
      PoolFrame& slot = pool[next];
      next = next + 1 == pool.size() ? 0 : next + 1;
      nowNs += FRAME_SPACING_NS;
      meter.add(slot.received.frame, nowNs);
    }
    meterCpu.push_back(static_cast<double>(threadCpuNs() - cpuStart) / static_cast<double>(frames));
  }
  const double meterMedian = median(meterCpu);
  std::printf("  of which can::BusLoadMeter::add alone: CPU median %.1f ns/frame (%.0f %% of onFrame; %llu frames "
              "counted)\n",
              meterMedian, meterMedian / cpuMedian * 100.0, static_cast<unsigned long long>(meter.totalFrames()));

  // Sanity: every frame reached the table or the request path; nothing unknown.
  std::uint64_t total = 0, decoded = 0, requests = 0, unknown = 0, decodeErrors = 0, outOfRange = 0;
  for (std::size_t b = 0; b < sut.busCount(); ++b) {
    const canrx::BusCounters& counters = sut.counters(b);
    total += counters.frames;
    decoded += counters.decoded;
    requests += counters.requests;
    unknown += counters.unknownIds + counters.ownFrames;
    decodeErrors += counters.decodeErrors;
    outOfRange += counters.outOfRange;
  }
  std::printf("receiver counters: frames %llu, decoded %llu, requests %llu, unknown/own %llu, decode errors %llu, "
              "out-of-range values %llu; outputs: received %llu, faults %llu\n",
              static_cast<unsigned long long>(total), static_cast<unsigned long long>(decoded),
              static_cast<unsigned long long>(requests), static_cast<unsigned long long>(unknown),
              static_cast<unsigned long long>(decodeErrors), static_cast<unsigned long long>(outOfRange),
              static_cast<unsigned long long>(outputs.receivedCount), static_cast<unsigned long long>(outputs.faultCount));
  if (unknown != 0 || decoded + requests < total) {  // requests the DBC defines are also decoded
    std::cerr << "bench_receiver: some frames were neither decoded nor requests: the figures are not valid\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"CPU time of canrx::Receiver::onFrame (link -> signal table), in process"};
  std::string configPath = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
  std::uint64_t frames = 2'000'000;
  int repeat = 7;
  std::uint64_t seed = 20240611;
  int cpu = -1;
  app.add_option("--config", configPath, "vehicle configuration (default: config/hhea/vehicle.json)");
  app.add_option("--frames", frames, "frames per measured pass (default 2000000)")->check(CLI::PositiveNumber);
  app.add_option("--repeat", repeat, "measured passes (default 7)")->check(CLI::Range(1, 1000));
  app.add_option("--seed", seed, "payload random seed (default 20240611)");
  app.add_option("--cpu", cpu, "pin to this CPU (default -1: do not pin)");
  CLI11_PARSE(app, argc, argv);

  auto vehicleResult = config::loadVehicleConfig(configPath);
  if (!vehicleResult) {
    std::cerr << "bench_receiver: " << vehicleResult.error().toString() << '\n';
    return 1;
  }
  const config::VehicleConfig& vehicle = *vehicleResult;
  auto catalogResult = config::buildCatalog(vehicle);
  if (!catalogResult) {
    std::cerr << "bench_receiver: " << catalogResult.error().toString() << '\n';
    return 1;
  }
  if (cpu >= 0 && !pinToCpu(cpu)) std::cerr << "bench_receiver: warning: cannot pin to CPU " << cpu << '\n';

  const std::string instance = "bench-canrx-" + std::to_string(::getpid());
  (void)signals::SignalTable::remove(instance);
  int exitCode = 1;
  {
    auto tableResult = signals::SignalTable::open(*catalogResult, instance);
    if (!tableResult) {
      std::cerr << "bench_receiver: " << tableResult.error().toString() << '\n';
    } else {
      std::printf("config %s: instance table %s (%zu signals), %s\n", configPath.c_str(),
                  signals::SignalTable::segmentPath(instance).c_str(), catalogResult->size(),
                  cpu >= 0 ? ("pinned to CPU " + std::to_string(cpu)).c_str() : "not pinned");
      exitCode = run(vehicle, *catalogResult, *tableResult, frames, repeat, seed);
    }
  }
  if (auto removed = signals::SignalTable::remove(instance); !removed) {
    std::cerr << "bench_receiver: " << removed.error().toString() << '\n';
  }
  return exitCode;
}
