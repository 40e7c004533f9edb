// bench_wakeup: what one wake-up costs on this platform, with no work of ours in it, to
// set beside the services' CPU (docs/benchmarks.md "Platform: the cost of a wake-up").
//
//   bench_wakeup [--rate HZ] [--seconds S]
//
// 1. timer: one thread sleeps to absolute deadlines RATE times a second
//    (clock_nanosleep(TIMER_ABSTIME), as every openvcu loop waits) and does nothing else;
//    its CPU time (CLOCK_THREAD_CPUTIME_ID: user and kernel, the switch into it included)
//    per wake-up.
// 2. relay: the same timer thread writes an eventfd at each deadline and a second process,
//    blocked in read(), wakes for it (what a frame or event from another service costs the
//    receiver: a futex or eventfd wake-up from idle, on whichever core the kernel picks);
//    the sender's CPU per wake-up (timer + write) and the receiver's (its process CPU time
//    over the same wake-ups).
// Ends with one line
//   RESULT timer_wakeup_us=.. relay_sender_us=.. relay_receiver_us=.. rate=.. seconds=.. late_p99_us=..
// late_p99_us: how late the timer thread woke (phase 1), nearest-rank p99.

#include <sys/eventfd.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

constexpr std::int64_t NS_PER_S = 1'000'000'000;
constexpr std::uint64_t STOP = 1ull << 40;  ///< an eventfd value the receiver reads as "stop"

std::int64_t nowNs(clockid_t clock) {
  timespec ts{};
  ::clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * NS_PER_S + ts.tv_nsec;
}

void sleepUntil(std::int64_t deadlineNs) {
  const timespec ts{static_cast<time_t>(deadlineNs / NS_PER_S), static_cast<long>(deadlineNs % NS_PER_S)};
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

struct TimerResult {
  double cpuPerWakeUs{};
  double lateP99Us{};
};

/// Wakes `count` times, `periodNs` apart; after each wake-up calls `onWake()`.
template <typename OnWake>
TimerResult timerLoop(std::int64_t periodNs, std::int64_t count, std::vector<std::int64_t>& late, OnWake onWake) {
  late.clear();
  std::int64_t deadline = nowNs(CLOCK_MONOTONIC) + periodNs;
  const std::int64_t cpuStart = nowNs(CLOCK_THREAD_CPUTIME_ID);
  for (std::int64_t i = 0; i < count; ++i) {
    sleepUntil(deadline);
    late.push_back(nowNs(CLOCK_MONOTONIC) - deadline);
    onWake();
    deadline += periodNs;
  }
  const std::int64_t cpu = nowNs(CLOCK_THREAD_CPUTIME_ID) - cpuStart;
  std::sort(late.begin(), late.end());
  const auto rank = static_cast<std::size_t>((static_cast<double>(late.size()) * 0.99) + 0.999999);
  return TimerResult{static_cast<double>(cpu) / static_cast<double>(count) / 1e3,
                     static_cast<double>(late[std::min(late.size(), std::max<std::size_t>(rank, 1)) - 1]) / 1e3};
}

[[noreturn]] void usage() {
  std::fprintf(stderr, "usage: bench_wakeup [--rate HZ (1..20000, default 1000)] [--seconds S (1..600, default 20)]\n");
  std::exit(64);
}

}  // namespace

int main(int argc, char** argv) {
  long rate = 1000;
  long seconds = 20;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "--rate" || arg == "--seconds") && i + 1 < argc) {
      char* end = nullptr;
      const long value = std::strtol(argv[++i], &end, 10);
      if (end == nullptr || *end != '\0') usage();
      (arg == "--rate" ? rate : seconds) = value;
    } else {
      usage();
    }
  }
  if (rate < 1 || rate > 20000 || seconds < 1 || seconds > 600) usage();
  const std::int64_t periodNs = NS_PER_S / rate;
  const std::int64_t count = rate * seconds;
  std::vector<std::int64_t> late;
  late.reserve(static_cast<std::size_t>(count));

  std::printf("bench_wakeup: %ld wake-ups a second for %ld s per phase\n", rate, seconds);
  std::fflush(stdout);
  const TimerResult timer = timerLoop(periodNs, count, late, [] {});
  std::printf("  timer: %.2f us of CPU per wake-up, woke late by p99 %.1f us\n", timer.cpuPerWakeUs, timer.lateP99Us);
  std::fflush(stdout);

  const int event = ::eventfd(0, EFD_CLOEXEC);
  int report[2];
  if (event < 0 || ::pipe(report) != 0) {
    std::fprintf(stderr, "bench_wakeup: eventfd/pipe: %s\n", std::strerror(errno));
    return 1;
  }
  const pid_t child = ::fork();
  if (child < 0) {
    std::fprintf(stderr, "bench_wakeup: fork: %s\n", std::strerror(errno));
    return 1;
  }
  if (child == 0) {
    // the receiver: blocks in read() until the sender's STOP; reports its CPU and wake-ups
    std::int64_t wakes = 0;
    const std::int64_t cpuStart = nowNs(CLOCK_PROCESS_CPUTIME_ID);
    for (;;) {
      std::uint64_t value = 0;
      if (::read(event, &value, sizeof value) != static_cast<ssize_t>(sizeof value)) {
        if (errno == EINTR) continue;
        ::_exit(1);
      }
      if (value >= STOP) break;
      ++wakes;
    }
    const std::int64_t both[2] = {nowNs(CLOCK_PROCESS_CPUTIME_ID) - cpuStart, wakes};
    ::_exit(::write(report[1], both, sizeof both) == static_cast<ssize_t>(sizeof both) ? 0 : 1);
  }
  ::usleep(100'000);  // the receiver is blocked in read() before the first deadline
  const std::uint64_t one = 1;
  const TimerResult sender = timerLoop(periodNs, count, late, [&] {
    if (::write(event, &one, sizeof one) != static_cast<ssize_t>(sizeof one)) std::abort();
  });
  const std::uint64_t stop = STOP;
  ::usleep(10'000);  // the last wake-up is read before the stop
  if (::write(event, &stop, sizeof stop) != static_cast<ssize_t>(sizeof stop)) return 1;
  std::int64_t both[2] = {0, 0};
  const bool reported = ::read(report[0], both, sizeof both) == static_cast<ssize_t>(sizeof both);
  int status = 0;
  ::waitpid(child, &status, 0);
  if (!reported || both[1] <= 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "bench_wakeup: the receiver did not report\n");
    return 1;
  }
  const double receiverUs = static_cast<double>(both[0]) / static_cast<double>(both[1]) / 1e3;
  std::printf("  relay: sender %.2f us of CPU per wake-up (timer + eventfd write), receiver %.2f us per wake-up "
              "(%lld wake-ups for %lld writes: writes that came before the read are one wake-up)\n",
              sender.cpuPerWakeUs, receiverUs, static_cast<long long>(both[1]), static_cast<long long>(count));
  std::printf("RESULT timer_wakeup_us=%.2f relay_sender_us=%.2f relay_receiver_us=%.2f rate=%ld seconds=%ld "
              "late_p99_us=%.1f\n",
              timer.cpuPerWakeUs, sender.cpuPerWakeUs, receiverUs, rate, seconds, timer.lateP99Us);
  return 0;
}
