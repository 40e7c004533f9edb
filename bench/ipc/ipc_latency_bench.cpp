// Latency of the two IPC planes between two processes, measured the way services use them:
//   frames: FramePublisher::publish -> Waiter wakes the subscriber process -> take()
//   events: EventBus::publish (udpm) -> the other process's callback, waiting (a) in
//           EventBus::handle and (b) in Waiter::attachFd (the fd-watcher thread path).
// Publishing is paced (one sample per period) so each sample measures a wake-up from
// idle, not queue throughput. Both processes read the same clocks (frames: CLOCK_MONOTONIC
// stamped by publish; events: CLOCK_REALTIME stamped by publish).
//
// Run it isolated (it starts its own iox-roudi and uses multicast on lo):
//   tests/harness/run_isolated.sh --keep BUILD -- BUILD/bench/ipc/ipc_latency_bench [--samples N] [--period-us P]

#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "ipc_test_support.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/ipc/waiter.hpp"

namespace ipc = openvcu::ipc;
namespace ipctest = openvcu::ipctest;
using namespace std::chrono_literals;

namespace {

constexpr std::size_t WARM_UP_SAMPLES = 200;  // first wake-ups fault pages in: not counted
constexpr std::uint64_t READY_ID = 1;
const std::string INSTANCE = "bench";

struct Options {
  std::size_t samples{10'000};
  std::int64_t periodUs{200};
};

std::int64_t nowNs(clockid_t clock) {
  timespec now{};
  ::clock_gettime(clock, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

/// Sleeps until start + index * period (absolute deadlines: no drift).
void pace(const timespec& start, std::int64_t periodUs, std::size_t index) {
  const std::int64_t targetNs = static_cast<std::int64_t>(start.tv_sec) * 1'000'000'000 + start.tv_nsec +
                                static_cast<std::int64_t>(index) * periodUs * 1000;
  timespec target{static_cast<time_t>(targetNs / 1'000'000'000), static_cast<long>(targetNs % 1'000'000'000)};
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &target, nullptr) == EINTR) {
  }
}

/// The final RESULT line's fields (key prefix per measurement).
std::string g_result;

void report(const std::string& title, const char* key, std::vector<std::int64_t> latenciesNs, std::size_t expected) {
  std::sort(latenciesNs.begin(), latenciesNs.end());
  auto percentile = [&](double p) {
    if (latenciesNs.empty()) return 0.0;
    const auto index = static_cast<std::size_t>(p * static_cast<double>(latenciesNs.size() - 1) + 0.5);
    return static_cast<double>(latenciesNs[index]) / 1000.0;
  };
  std::printf("%-58s n=%zu/%zu  p50 %7.1f us  p90 %7.1f us  p99 %7.1f us  max %8.1f us\n", title.c_str(),
              latenciesNs.size(), expected, percentile(0.50), percentile(0.90), percentile(0.99),
              latenciesNs.empty() ? 0.0 : static_cast<double>(latenciesNs.back()) / 1000.0);
  char fields[160];
  std::snprintf(fields, sizeof fields, " %s_n=%zu %s_p50_us=%.1f %s_p99_us=%.1f", key, latenciesNs.size(), key,
                percentile(0.50), key, percentile(0.99));
  g_result += fields;
  std::fflush(stdout);
}

// ---- the publishing side (a child process: this program with --role) ----------------

int runFramePublisher(const Options& options) {
  if (!ipc::Runtime::init("ipc_bench_publisher-" + std::to_string(::getpid()), 5000ms)) return 2;
  auto publisher = ipc::FramePublisher::create({INSTANCE, "vehicle", ipc::FrameStream::Received});
  if (!publisher || !publisher->waitForSubscribers(10s)) return 2;
  timespec start{};
  ::clock_gettime(CLOCK_MONOTONIC, &start);
  for (std::size_t i = 0; i < WARM_UP_SAMPLES + options.samples; ++i) {
    pace(start, options.periodUs, i + 1);
    ipc::FrameSample sample{};  // monotonicNs 0: publish() stamps it right before publishing
    sample.frame.id = static_cast<std::uint32_t>(i & 0x7FF);
    sample.frame.length = 8;
    publisher->publish(sample);
  }
  return 0;
}

int runEventPublisher(const Options& options) {
  auto events = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, INSTANCE);
  if (!events) return 2;
  timespec start{};
  ::clock_gettime(CLOCK_MONOTONIC, &start);
  for (std::size_t i = 0; i < WARM_UP_SAMPLES + options.samples; ++i) {
    pace(start, options.periodUs, i + 1);
    events->publish(ipc::LogRecord{nowNs(CLOCK_REALTIME), "bench", ipc::LogLevel::Info, std::to_string(i)});
  }
  return 0;
}

// ---- the measuring side ---------------------------------------------------------------

std::optional<ipctest::ChildProcess> spawnPublisher(const std::string& role, const Options& options) {
  return ipctest::ChildProcess::spawn({"/proc/self/exe", "--role", role, "--samples", std::to_string(options.samples),
                                       "--period-us", std::to_string(options.periodUs)});
}

std::chrono::nanoseconds runTime(const Options& options) {
  return std::chrono::microseconds{options.periodUs} * static_cast<std::int64_t>(WARM_UP_SAMPLES + options.samples) +
         10s;
}

bool measureFrames(const Options& options) {
  auto subscriber = ipc::FrameSubscriber::create({INSTANCE, "vehicle", ipc::FrameStream::Received});
  auto waiter = ipc::Waiter::create();
  if (!subscriber || !waiter || !waiter->attach(*subscriber, READY_ID)) return false;
  auto publisher = spawnPublisher("frames", options);
  if (!publisher) return false;
  std::vector<std::int64_t> latencies;
  latencies.reserve(options.samples);
  std::size_t received = 0;
  std::size_t batchedWakes = 0;
  const auto deadline = std::chrono::steady_clock::now() + runTime(options);
  while (received < WARM_UP_SAMPLES + options.samples && std::chrono::steady_clock::now() < deadline) {
    if (waiter->waitUntil(deadline).empty()) continue;
    const std::int64_t wokeNs = nowNs(CLOCK_MONOTONIC);
    std::size_t takenThisWake = 0;
    while (auto sample = subscriber->take()) {
      ++takenThisWake;
      if (received++ >= WARM_UP_SAMPLES) latencies.push_back(wokeNs - sample->monotonicNs);
    }
    if (takenThisWake > 1) ++batchedWakes;
  }
  publisher->wait(10s);
  report("frames: publish -> Waiter wake -> take (iceoryx)", "frames", std::move(latencies), options.samples);
  std::printf("  (wake-ups that found more than one sample, i.e. the reader was late: %zu)\n", batchedWakes);
  return true;
}

bool measureEvents(const Options& options, bool throughWaiter) {
  auto events = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, INSTANCE);
  if (!events) {
    std::cerr << events.error().toString() << '\n';
    return false;
  }
  std::vector<std::int64_t> latencies;
  latencies.reserve(options.samples);
  std::size_t received = 0;
  auto subscription = events->onLog([&](const ipc::LogRecord& record) {
    const std::int64_t arrivedNs = nowNs(CLOCK_REALTIME);
    if (received++ >= WARM_UP_SAMPLES) latencies.push_back(arrivedNs - record.timestampNs);
  });
  if (!subscription) return false;
  std::optional<ipc::Waiter> waiter;
  if (throughWaiter) {
    auto waiterResult = ipc::Waiter::create();
    if (!waiterResult || !waiterResult->attachFd(events->fileno(), READY_ID)) return false;
    waiter.emplace(std::move(*waiterResult));
  }
  auto publisher = spawnPublisher("events", options);
  if (!publisher) return false;
  const auto deadline = std::chrono::steady_clock::now() + runTime(options);
  while (received < WARM_UP_SAMPLES + options.samples && std::chrono::steady_clock::now() < deadline) {
    if (waiter) {
      if (!waiter->waitUntil(deadline).empty()) events->handleAll();
    } else {
      events->handle(100ms);
    }
    if (!publisher->running()) {  // done (or failed): take what is still on its way, then stop
      while (events->handle(100ms) == ipc::HandleResult::Handled) {
      }
      break;
    }
  }
  publisher->wait(10s);
  report(throughWaiter ? "events: publish -> Waiter::attachFd wake -> callback (LCM udpm)"
                       : "events: publish -> EventBus::handle -> callback (LCM udpm)",
         throughWaiter ? "events_waiter" : "events", std::move(latencies), options.samples);
  return true;
}

std::optional<std::int64_t> parseNumber(std::string_view text) {
  std::int64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size() || value <= 0) return std::nullopt;
  return value;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  std::string role;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string_view flag = argv[i];
    const auto number = parseNumber(argv[i + 1]);
    if (flag == "--role") {
      role = argv[i + 1];
    } else if (flag == "--samples" && number) {
      options.samples = static_cast<std::size_t>(*number);
    } else if (flag == "--period-us" && number) {
      options.periodUs = *number;
    } else {
      std::cerr << "usage: ipc_latency_bench [--samples N] [--period-us P]  (inside run_isolated.sh)\n";
      return 1;
    }
  }
  if (role == "frames") return runFramePublisher(options);
  if (role == "events") return runEventPublisher(options);

  if (!ipctest::isolated()) {
    std::cerr << "ipc_latency_bench starts its own iox-roudi and uses multicast: run it inside\n"
                 "  tests/harness/run_isolated.sh --keep <build dir> -- <this program>\n";
    return 1;
  }
  const std::string config = std::string(OPENVCU_SOURCE_DIR) + "/config/iceoryx/roudi.toml";
  if (!ipctest::startIsolatedRoudi(config)) {
    std::cerr << "iox-roudi did not start (see /tmp/iox-roudi.log)\n";
    return 1;
  }
  if (auto initResult = ipc::Runtime::init("ipc_bench-" + std::to_string(::getpid()), 5000ms); !initResult) {
    std::cerr << initResult.error().toString() << '\n';
    return 1;
  }
  std::printf("%zu samples after %zu warm-up, one every %lld us, two processes\n", options.samples, WARM_UP_SAMPLES,
              static_cast<long long>(options.periodUs));
  const bool ok = measureFrames(options) && measureEvents(options, false) && measureEvents(options, true);
  std::printf("RESULT ok=%d%s\n", ok ? 1 : 0, g_result.c_str());
  return ok ? 0 : 1;
}
