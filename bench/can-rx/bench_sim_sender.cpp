// bench_sim_sender: load generator for the can-rx benchmark. Sends the frames of the DBC
// messages other nodes send on one bus of a vehicle configuration onto its sim:NAME link,
// at a fixed rate, for a fixed time, then prints what it sent.
//
//   bench_sim_sender --config vehicle.json --bus vehicle --rate 4000 --seconds 30
//
// Needs a running iox-roudi (run it inside tests/harness/run_isolated.sh; see
// bench/can-rx/run_can_rx_bench.sh). Frames: round robin over the bus's messages whose
// transmitter is not the configured node, with the DBC identifier as is (29-bit IDs carry the
// message's source address) and the DBC length, payloads random from --seed, drawn once into
// a pool before sending. Pacing: absolute 1 ms deadlines (clock_nanosleep TIMER_ABSTIME on
// CLOCK_MONOTONIC); at each wake-up the frames due by then (rate x whole milliseconds since
// the start / 1000) go out in one batch, so a late wake-up is caught up at once and the
// long-run rate is exact. The largest batch is reported: a batch larger than a receiver's
// queue (256 samples on a sim link) cannot all arrive, whatever the receiver's speed.
// No busy loop. A send that returns Busy (no iceoryx chunk) is counted and not retried.
//
// After opening the link it waits --connect-ms (default 1000) before the first frame:
// RouDi connects new ports within ~100 ms and frames sent before that are not delivered.
// That wait is connection set-up, not part of any measurement. After the last frame the
// link stays open --linger-ms (default 500) so the receiver can take the last samples.
//
// Output (stdout): a line "sending ..." when the first batch goes out (the run script starts
// its CPU window there) and a final line of key=value pairs: sent, busy, failed, elapsed,
// achieved rate, late deadlines, largest batch. Exit 0, or 1 on a start-up error.

#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "openvcu/can_links/open_link.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace {

using namespace openvcu;

constexpr std::int64_t NS_PER_MS = 1'000'000;
constexpr std::int64_t NS_PER_S = 1'000'000'000;
constexpr std::size_t POOL_FRAMES = 4096;
constexpr std::size_t DRAIN_BATCH = 64;

std::int64_t monotonicNs() noexcept {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * NS_PER_S + now.tv_nsec;
}

void sleepUntil(std::int64_t deadlineNs) noexcept {
  const timespec deadline{static_cast<time_t>(deadlineNs / NS_PER_S), static_cast<long>(deadlineNs % NS_PER_S)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) != 0) {
  }
}

/// Takes what the link received (our own frames come back through its subscriber and are
/// dropped there; taking them keeps the queue short). Nothing is done with them.
void drain(can::Link& link) noexcept {
  std::array<can::ReceivedFrame, DRAIN_BATCH> sink{};
  while (link.receive(sink) == sink.size()) {
  }
}

/// Frames of the messages others send on `bus`, round robin, random payloads.
std::vector<can::Frame> buildPool(const config::VehicleConfig& vehicle, const config::BusConfig& bus,
                                  std::uint64_t seed, std::size_t& messageCount) {
  std::vector<const dbc::Message*> messages;
  for (const std::size_t messageIndex : bus.messages) {
    const dbc::Message& message = vehicle.database.messages[messageIndex];
    if (message.transmitter == vehicle.node || message.pseudo) continue;
    if (message.length > can::CLASSIC_DATA_LENGTH && !bus.fd) continue;  // TP-sized: not one frame
    messages.push_back(&message);
  }
  messageCount = messages.size();
  std::vector<can::Frame> pool;
  if (messages.empty()) return pool;
  std::mt19937_64 random(seed);
  pool.resize(POOL_FRAMES);
  for (std::size_t i = 0; i < pool.size(); ++i) {
    const dbc::Message& message = *messages[i % messages.size()];
    can::Frame& frame = pool[i];
    frame.id = message.id;
    frame.flags = message.extended ? can::FLAG_EXTENDED : 0;
    if (message.length > can::CLASSIC_DATA_LENGTH) frame.flags |= can::FLAG_FD;
    frame.length = message.length > can::CLASSIC_DATA_LENGTH ? can::roundUpFdLength(message.length)
                                                             : static_cast<std::uint8_t>(message.length);
    for (std::size_t byte = 0; byte < frame.length; ++byte) frame.data[byte] = static_cast<std::uint8_t>(random() & 0xFF);
  }
  return pool;
}

struct Totals {
  std::uint64_t attempted{};
  std::uint64_t sent{};
  std::uint64_t busy{};
  std::uint64_t failed{};  ///< Down, Invalid, NotSupported
  std::uint64_t lateDeadlines{};  ///< woke more than one period after the deadline
  std::int64_t maxLateNs{};
  std::uint64_t maxBatch{};  ///< most frames sent in one batch (catching up after a late wake-up)
  std::int64_t elapsedNs{};
};

Totals sendPaced(can::Link& link, const std::vector<can::Frame>& pool, std::uint64_t rate, std::uint64_t seconds) {
  Totals totals;
  const std::uint64_t ticks = seconds * 1000;
  const std::uint64_t total = rate * seconds;
  std::size_t next = 0;
  const std::int64_t start = monotonicNs();
  std::uint64_t tick = 0;
  for (;;) {
    const std::int64_t deadline = start + static_cast<std::int64_t>(tick) * NS_PER_MS;
    sleepUntil(deadline);
    const std::int64_t now = monotonicNs();
    const std::int64_t late = now - deadline;
    if (late > NS_PER_MS) ++totals.lateDeadlines;
    totals.maxLateNs = std::max(totals.maxLateNs, late);
    // Everything due by now goes out in this batch (one batch even after a late wake-up).
    const std::uint64_t elapsedTicks = std::min(ticks, static_cast<std::uint64_t>((now - start) / NS_PER_MS));
    const std::uint64_t due = elapsedTicks == ticks ? total : rate * elapsedTicks / 1000;
    totals.maxBatch = std::max(totals.maxBatch, due - totals.attempted);
    while (totals.attempted < due) {
      const can::SendStatus status = link.send(pool[next]);
      next = next + 1 == pool.size() ? 0 : next + 1;
      ++totals.attempted;
      if (status == can::SendStatus::Sent) {
        ++totals.sent;
      } else if (status == can::SendStatus::Busy) {
        ++totals.busy;
      } else {
        ++totals.failed;
      }
    }
    drain(link);
    if (elapsedTicks == ticks) break;
    tick = elapsedTicks + 1;
  }
  totals.elapsedNs = monotonicNs() - start;
  return totals;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Load generator for the can-rx benchmark: paced frames of the other nodes' messages on one sim bus"};
  std::string configPath, busName;
  std::uint64_t rate = 4000;
  std::uint64_t seconds = 30;
  std::uint64_t seed = 1;
  int connectMs = 1000;
  int lingerMs = 500;
  app.add_option("--config", configPath, "vehicle configuration (vehicle.json)")->required();
  app.add_option("--bus", busName, "bus name in the configuration (its link must be sim:NAME)")->required();
  app.add_option("--rate", rate, "frames per second (default 4000)")->check(CLI::Range(1ull, 10'000'000ull));
  app.add_option("--seconds", seconds, "seconds of sending (default 30)")->check(CLI::Range(1ull, 3600ull));
  app.add_option("--seed", seed, "payload random seed (default 1)");
  app.add_option("--connect-ms", connectMs, "wait after opening the link, before sending (default 1000)")
      ->check(CLI::Range(0, 60'000));
  app.add_option("--linger-ms", lingerMs, "keep the link open after the last frame (default 500)")
      ->check(CLI::Range(0, 60'000));
  CLI11_PARSE(app, argc, argv);

  auto vehicleResult = config::loadVehicleConfig(configPath);
  if (!vehicleResult) {
    std::cerr << "bench_sim_sender: " << vehicleResult.error().toString() << '\n';
    return 1;
  }
  const config::VehicleConfig& vehicle = *vehicleResult;
  const config::BusConfig* bus = vehicle.findBus(busName);
  if (bus == nullptr) {
    std::cerr << "bench_sim_sender: " << configPath << ": no bus '" << busName << "'\n";
    return 1;
  }
  if (bus->link.kind != config::LinkKind::Sim) {
    std::cerr << "bench_sim_sender: bus '" << busName << "' is " << bus->link.toString() << ", not sim:NAME\n";
    return 1;
  }
  std::size_t messageCount = 0;
  const std::vector<can::Frame> pool = buildPool(vehicle, *bus, seed, messageCount);
  if (pool.empty()) {
    std::cerr << "bench_sim_sender: bus '" << busName << "' carries no message of another node\n";
    return 1;
  }

  const std::string runtimeName = "bench-sim-sender-" + busName + "-" + std::to_string(::getpid());
  if (auto initResult = ipc::Runtime::init(runtimeName, std::chrono::seconds{5}); !initResult) {
    std::cerr << "bench_sim_sender: " << initResult.error().toString() << '\n';
    return 1;
  }
  can::LinkOptions options;
  options.bitrate = bus->bitrate;
  options.dataBitrate = bus->dataBitrate;
  options.fd = bus->fd;
  auto linkResult = can::openLink(can::LinkKind::Sim, bus->link.target, options);
  if (!linkResult) {
    std::cerr << "bench_sim_sender: " << linkResult.error().toString() << '\n';
    return 1;
  }
  can::Link& link = **linkResult;

  // Connection set-up (not measured): RouDi connects the new ports to the receivers.
  const std::int64_t connected = monotonicNs() + connectMs * NS_PER_MS;
  while (monotonicNs() < connected) {
    drain(link);
    sleepUntil(std::min(connected, monotonicNs() + 10 * NS_PER_MS));
  }

  std::printf("sending on %s: %llu frames/s for %llu s, %zu messages round robin, seed %llu\n", link.name().c_str(),
              static_cast<unsigned long long>(rate), static_cast<unsigned long long>(seconds), messageCount,
              static_cast<unsigned long long>(seed));
  std::fflush(stdout);
  const Totals totals = sendPaced(link, pool, rate, seconds);
  const double elapsed = static_cast<double>(totals.elapsedNs) / static_cast<double>(NS_PER_S);
  std::printf("bench_sim_sender: bus=%s rate=%llu seconds=%llu attempted=%llu sent=%llu busy=%llu failed=%llu "
              "elapsed_s=%.3f achieved_fps=%.1f late_deadlines=%llu max_late_us=%lld max_batch=%llu\n",
              busName.c_str(), static_cast<unsigned long long>(rate), static_cast<unsigned long long>(seconds),
              static_cast<unsigned long long>(totals.attempted), static_cast<unsigned long long>(totals.sent),
              static_cast<unsigned long long>(totals.busy), static_cast<unsigned long long>(totals.failed), elapsed,
              static_cast<double>(totals.sent) / elapsed, static_cast<unsigned long long>(totals.lateDeadlines),
              static_cast<long long>(totals.maxLateNs / 1000), static_cast<unsigned long long>(totals.maxBatch));
  std::fflush(stdout);

  const std::int64_t lingerEnd = monotonicNs() + lingerMs * NS_PER_MS;
  while (monotonicNs() < lingerEnd) {
    drain(link);
    sleepUntil(std::min(lingerEnd, monotonicNs() + 10 * NS_PER_MS));
  }
  return 0;
}
