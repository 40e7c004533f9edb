#include "watchdog_app.hpp"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "board_watchdog.hpp"
#include "openvcu/config/faults.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/service/app_impl.hpp"
#include "openvcu/service/heartbeat.hpp"
#include "openvcu/service/timer.hpp"
#include "policy.hpp"
#include "process_finder.hpp"
#include "silence_watch.hpp"

namespace openvcu::watchdog {
namespace {

constexpr std::int64_t NS_PER_MS = 1'000'000;

/// "1.6 s" for a duration in ns (tenths of a second).
std::string seconds(std::int64_t ns) {
  const std::int64_t tenths = (ns + 50'000'000) / 100'000'000;
  return std::to_string(tenths / 10) + "." + std::to_string(tenths % 10) + " s";
}

}  // namespace

/// One watched service.
struct Watched {
  std::string name;     ///< "fsm"
  std::string program;  ///< "vcu-fsm"
  signals::SignalIndex slot{};
  SilenceWatch watch;
  bool reportedNoProcess{};  ///< in this silence: "nothing to kill" logged once
};

struct WatchdogAppImpl {
  service::Service& runtime;
  WatchedPolicy policy;
  std::vector<Watched> watched;
  ProcessFinder finder;
  std::optional<BoardWatchdog> board;
  std::optional<service::PeriodicTimer> watchTimer;
  std::optional<service::PeriodicTimer> feedTimer;
  pid_t parent{};  ///< the supervisor that started us (and the services)
  service::CounterRef silences;
  service::CounterRef kills;
  service::CounterRef feeds;
  service::CounterRef feedFailures;
  bool feedFailing{};  ///< a failed feed was logged; the next good one is logged too

  explicit WatchdogAppImpl(service::Service& service) : runtime(service) {}

  ~WatchdogAppImpl() {
    if (watchTimer) runtime.loop().removeFd(watchTimer->fd());
    if (feedTimer) runtime.loop().removeFd(feedTimer->fd());
    if (!board) return;
    // An orderly stop by our supervisor disarms the board watchdog. A SIGTERM because the
    // supervisor died (PR_SET_PDEATHSIG: we now have another parent) leaves it running, so
    // that the board resets unless a new feeder takes over.
    if (::getppid() == parent) {
      if (board->disarm()) {
        runtime.log().info("board watchdog " + board->path() + " disarmed (magic close)");
      } else {
        runtime.log().error("board watchdog " + board->path() + ": magic close failed: " + std::strerror(errno));
      }
    } else {
      runtime.log().error("supervisor (pid " + std::to_string(parent) + ") gone: board watchdog " + board->path() +
                          " left running (closed without the magic character)");
    }
  }

  Status open() {
    auto policyResult = policyOf(runtime.config(), runtime.catalog());
    if (!policyResult) return policyResult.error();
    policy = std::move(*policyResult);
    parent = ::getppid();
    const std::int64_t now = clock::monotonicNs();
    const std::int64_t silentAfterNs = policy.silentAfterMs * NS_PER_MS;
    std::string names;
    for (const std::string& name : policy.services) {
      const auto slot = runtime.catalog().indexOf(service::heartbeatKey(name));
      if (!slot) return Error{"no heartbeat slot for service '" + name + "'"};  // policyOf checked it
      watched.push_back(Watched{name, "vcu-" + name, *slot, SilenceWatch(silentAfterNs, now), false});
      names += (names.empty() ? "" : ", ") + name;
    }
    if (!policy.device.empty()) {
      auto boardResult = BoardWatchdog::open(policy.device);
      if (!boardResult) return Error{"board watchdog: " + boardResult.error().message};
      board.emplace(std::move(*boardResult));
      board->feed();
    }
    silences = runtime.addCounter("silences");
    kills = runtime.addCounter("kills");
    feeds = runtime.addCounter("feeds");
    feedFailures = runtime.addCounter("feed_failures");

    auto watchResult = service::PeriodicTimer::create(WATCH_PERIOD);
    if (!watchResult) return watchResult.error();
    watchTimer.emplace(std::move(*watchResult));
    if (Status added = runtime.loop().addTimer(*watchTimer, [this](const service::TimerTick&) { onWatchTick(); });
        !added)
      return added.error();
    if (board) {
      auto feedResult = service::PeriodicTimer::create(FEED_PERIOD);
      if (!feedResult) return feedResult.error();
      feedTimer.emplace(std::move(*feedResult));
      if (Status added = runtime.loop().addTimer(*feedTimer, [this](const service::TimerTick&) { onFeedTick(); });
          !added)
        return added.error();
    }
    runtime.log().info("watching " + names + ": silent after " + std::to_string(policy.silentAfterMs) + " ms, " +
                       (policy.restart ? "killed for parent pid " + std::to_string(parent) + " to restart"
                                       : "not killed (restart off)") +
                       ", board watchdog " +
                       (board ? board->path() + (board->timeoutSeconds()
                                                     ? " (timeout " + std::to_string(*board->timeoutSeconds()) + " s)"
                                                     : std::string(" (timeout unknown)"))
                              : std::string("none")) +
                       " (" + policy.origin + ")");
    onWatchTick();  // the first read now: the status says what was read, not what is hoped
    updateStatus();
    return {};
  }

  // ---- loop thread ------------------------------------------------------------------------

  void onWatchTick() {
    bool changed = false;
    for (Watched& entry : watched) {
      const std::int64_t now = clock::monotonicNs();
      const std::int64_t beatBefore = entry.watch.lastBeatNs();
      switch (entry.watch.update(runtime.table().readBus(entry.slot), now)) {
        case SilenceChange::Silent:
          silences.increment();
          fault(entry, true,
                entry.program + " silent for " + seconds(entry.watch.silentForNs(now)) + " (no beat in " +
                    service::heartbeatKey(entry.name) + "; limit " + std::to_string(policy.silentAfterMs) + " ms)");
          changed = true;
          break;
        case SilenceChange::Beating:
          fault(entry, false,
                entry.program + " beats again after " + seconds(entry.watch.lastBeatNs() - beatBefore) + " of silence");
          entry.reportedNoProcess = false;
          changed = true;
          break;
        case SilenceChange::None:
          break;
      }
      if (policy.restart && entry.watch.killDue(now)) killSilent(entry, now);
    }
    if (changed) updateStatus();
  }

  void onFeedTick() {
    for (const Watched& entry : watched) {
      if (entry.watch.silent()) return;  // no feed: the board resets unless the service comes back
    }
    if (board->feed()) {
      feeds.increment();
      if (feedFailing) runtime.log().info("board watchdog " + board->path() + " fed again");
      feedFailing = false;
      return;
    }
    feedFailures.increment();
    if (!feedFailing) runtime.log().error("board watchdog " + board->path() + ": feed failed: " + std::strerror(errno));
    feedFailing = true;
  }

  /// Kills the silent service's process: the one sibling (same parent as us) whose
  /// executable is vcu-<name>, and only when the silence is its own (SilenceWatch::mayKill).
  void killSilent(Watched& entry, std::int64_t now) {
    entry.watch.killAttempted(now);
    if (::getppid() != parent) return;  // our supervisor is gone: it would restart nothing
    const FindResult found = finder.find(entry.program, parent, ::getpid());
    if (found.processes.size() != 1) {
      if (!entry.reportedNoProcess) {
        runtime.log().warning(
            entry.program + " is silent and " +
            (found.processes.empty()
                 ? std::string("no process ") + entry.program + " runs"
                 : std::to_string(found.processes.size()) + " processes " + entry.program + " run") +
            " beside vcu-watchdog under parent pid " + std::to_string(parent) +
            (found.unreadable > 0 ? " (" + std::to_string(found.unreadable) + " not readable)" : std::string()) +
            ": nothing killed");
        entry.reportedNoProcess = true;
      }
      return;
    }
    const FoundProcess& process = found.processes.front();
    if (!entry.watch.mayKill(process.startNs, now)) return;  // started after the silence began
    if (::kill(process.pid, SIGKILL) != 0) {
      runtime.log().error("kill " + entry.program + " (pid " + std::to_string(process.pid) +
                          "): " + std::strerror(errno));
      return;
    }
    kills.increment();
    runtime.log().error("killed " + entry.program + " (pid " + std::to_string(process.pid) + ", state " +
                        std::string(1, process.state) + ", silent for " + seconds(entry.watch.silentForNs(now)) +
                        ") with SIGKILL for its supervisor (pid " + std::to_string(parent) + ") to restart it");
  }

  void fault(const Watched& entry, bool active, const std::string& text) {
    const std::string name = faults::serviceSilent(entry.name);
    runtime.events().publish(ipc::FaultEvent{0, name, runtime.program(), ipc::FaultSeverity::Critical, active, text});
    if (active) {
      runtime.log().critical("fault raised: " + name + ": " + text);
    } else {
      runtime.log().info("fault cleared: " + name + ": " + text);
    }
  }

  void updateStatus() {
    std::string silent;
    for (const Watched& entry : watched) {
      if (entry.watch.silent()) silent += (silent.empty() ? "" : ", ") + entry.name;
    }
    runtime.setStatus(silent.empty() ? "all " + std::to_string(watched.size()) + " services beating"
                                     : "silent: " + silent);
  }
};

}  // namespace openvcu::watchdog

template class openvcu::service::App<openvcu::watchdog::WatchdogAppImpl>;
