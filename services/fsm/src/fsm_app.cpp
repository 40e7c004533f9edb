#include "fsm_app.hpp"

#include "openvcu/service/app_impl.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <thread>

#include "reload_file.hpp"
#include "reload_worker.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/fsm/engine.hpp"
#include "openvcu/fsm/machine.hpp"

namespace openvcu::fsm {
namespace {

/// The longest the engine thread sleeps without a table change or a deadline: it also
/// bounds how long stop() waits.
constexpr std::chrono::milliseconds LONGEST_SLEEP{250};
/// The reload diagnostics quote the file: they go to stderr only (journal), in one burst.
constexpr std::uint32_t RELOAD_LOG_BURST = 200;

}  // namespace

struct FsmAppImpl {
  service::Service& runtime;
  TableAccess access;
  std::optional<Engine> engine;
  std::thread thread;
  std::atomic<bool> stopping{false};
  // Engine counters, mirrored for the heartbeat (loop thread).
  std::atomic<std::int64_t> transitions{};
  std::atomic<std::int64_t> selfTransitions{};
  std::atomic<std::int64_t> evaluations{};
  std::atomic<std::int64_t> steps{};
  std::atomic<std::int64_t> commands{};
  std::atomic<std::int64_t> loopGuards{};
  std::atomic<std::int64_t> state{};
  // A reload (docs/fsm.md "Reload"): the loop thread hands the path to the worker, which
  // reads and checks the file; back on the loop thread the machine goes to the engine
  // thread, which switches (or not) and answers; the loop thread answers the command. Each
  // hand-over back to the loop thread writes reloadFd.
  std::vector<std::string> folders;        ///< where a reload may read (reload_file.hpp)
  service::Logger localLog;                ///< stderr only: reload diagnostics quote the file
  int reloadFd{-1};                        ///< eventfd: the worker or the engine thread finished
  std::optional<service::CommandReply> reloadReply;  ///< loop thread: the reload in progress
  std::string switchingFile;                         ///< loop thread: the file handed to the engine
  std::optional<ReloadWorker> reloader;
  std::mutex reloadMutex;
  std::optional<Machine> pendingMachine;  ///< for the engine thread
  std::int64_t pendingDeadlineNs{};       ///< the command's deadline: never switched after it
  struct Switched {
    bool expired{};
    Status status;
  };
  std::optional<Switched> reloadResult;  ///< from the engine thread
  std::uint64_t reloadRequests{};

  explicit FsmAppImpl(service::Service& service)
      : runtime(service),
        access(service.table(), FSM_WRITER),
        localLog(service.program(), service::LoggerOptions{.threshold = ipc::LogLevel::Info,
                                                           .ratePerSecond = 20.0,
                                                           .burst = RELOAD_LOG_BURST,
                                                           .journalFormat = std::getenv("JOURNAL_STREAM") != nullptr}) {}

  ~FsmAppImpl() {
    if (reloadFd >= 0) runtime.loop().removeFd(reloadFd);
    reloader.reset();     // waits for a job in progress: a bounded read and check
    stopping.store(true);  // the engine thread sees it within LONGEST_SLEEP
    if (thread.joinable()) thread.join();
    if (reloadReply) reloadReply->refuse("vcu-fsm is stopping; nothing was switched");
    if (reloadFd >= 0) ::close(reloadFd);
  }

  /// Counts a reload request in internal.fsm.reloads, which also wakes the engine thread
  /// out of waitForChange at once.
  void wakeEngine() {
    if (const auto index = runtime.catalog().indexOf("internal.fsm.reloads")) {
      runtime.table().writeBus(*index, static_cast<double>(reloadRequests), clock::monotonicNs(), FSM_WRITER,
                               signals::Quality::Valid);
    }
  }

  void report(const std::vector<Error>& diagnostics) {
    for (const Error& diagnostic : diagnostics) {
      if (diagnostic.severity == Severity::Warning) runtime.log().warning(diagnostic.toString());
    }
  }

  Status open() {
    const config::VehicleConfig& vehicle = runtime.config();
    if (vehicle.fsmFile.empty()) {
      return Error{"the configuration names no FSM file (\"fsm\" in " + vehicle.path + ")"};
    }
    std::vector<Error> diagnostics;
    auto machineResult = loadMachine(vehicle.fsmFile, vehicle, runtime.catalog(), &diagnostics);
    if (!machineResult) return machineResult.error();
    report(diagnostics);
    auto slotsResult = StatusSlots::find(runtime.catalog());
    if (!slotsResult) return slotsResult.error();
    runtime.log().info(std::to_string(machineResult->states.size()) + " states from " + vehicle.fsmFile);
    engine.emplace(std::move(*machineResult), runtime.catalog(), access, std::move(*slotsResult));
    engine->start(clock::monotonicNs(), clock::realtimeNs(), StartMode::Resume);
    publishOutputs();
    mirrorCounters();

    folders = reloadFolders(vehicle);
    reloadFd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (reloadFd < 0) return Error{std::string("eventfd: ") + std::strerror(errno)};
    if (Status added = runtime.loop().addFd(reloadFd, [this] { onReloadProgress(); }); !added) return added.error();
    if (Status answering = runtime.answerCommands(commandPolicy()); !answering) return answering.error();
    registerCounters();
    reloader.emplace([this](const std::string& path) { return loadForReload(path); }, [this] { signalLoop(); });
    thread = std::thread([this] { runEngine(); });
    return {};
  }

  /// Wakes the loop thread (onReloadProgress); any thread.
  void signalLoop() const noexcept {
    const std::uint64_t one = 1;
    (void)!::write(reloadFd, &one, sizeof one);
  }

  // ---- engine thread ----------------------------------------------------------------------

  /// A table watch on the signals the machine's conditions read and on the reload key, so
  /// the engine sleeps through every other write of the table (can-rx writes thousands a
  /// second, almost none of them the machine's).
  signals::SignalWatch watchMachine() {
    std::vector<signals::SignalIndex> indexes;
    for (const SignalRef& ref : engine->machine().signals) indexes.push_back(ref.index);
    if (const auto reloads = runtime.catalog().indexOf("internal.fsm.reloads")) indexes.push_back(*reloads);
    signals::SignalWatch watch = runtime.table().watch(indexes);
    if (!watch.dedicated()) {
      runtime.log().warning("no free watch entry in the signal table: woken by every table write");
    }
    return watch;
  }

  void runEngine() {
    signals::SignalTable& table = runtime.table();
    std::uint64_t seenDamage = table.damageCount();
    signals::SignalWatch watch = watchMachine();
    while (!stopping.load(std::memory_order_relaxed)) {
      restoreAfterDamage(seenDamage, watch);
      const std::uint32_t epoch = watch.epoch();
      if (takeReload()) {
        watch = watchMachine();  // the new machine reads other signals
        continue;
      }
      engine->step(clock::monotonicNs(), clock::realtimeNs());
      publishOutputs();
      mirrorCounters();
      // Damage met during the step is repaired before sleeping, not after the next wake-up.
      if (table.damageCount() != seenDamage) continue;
      const std::int64_t now = clock::monotonicNs();
      const std::int64_t deadline = engine->nextDeadlineNs();
      std::chrono::nanoseconds timeout = LONGEST_SLEEP;
      if (deadline != NO_DEADLINE) timeout = std::min(timeout, std::chrono::nanoseconds(std::max<std::int64_t>(deadline - now, 0)));
      if (timeout.count() > 0) (void)watch.wait(epoch, timeout);
    }
  }

  /// The table lost its values since `seenDamage` (docs/design/signal-table.md, "Damage"):
  /// the watch's entry and bits went with the header, so it is made again; the engine
  /// writes back its state, timers and commands and keeps its input samples for a while.
  void restoreAfterDamage(std::uint64_t& seenDamage, signals::SignalWatch& watch) {
    const std::uint64_t damage = runtime.table().damageCount();
    if (damage == seenDamage) return;
    seenDamage = damage;
    watch = {};  // leaves the entry untouched: it may be another process's by now
    watch = watchMachine();
    const std::size_t restored = engine->restoreTable(clock::monotonicNs(), clock::realtimeNs());
    runtime.log().warning("the signal table lost its values: state '" + engine->stateName() + "' and " +
                          std::to_string(restored) + " commands written back; inputs not received since keep " +
                          "their last value for " + formatDuration(DAMAGE_GRACE_NS));
  }

  /// true when a new machine was taken (switched, refused or past its deadline) for a
  /// pending reload.
  bool takeReload() {
    std::unique_lock lock(reloadMutex);
    if (!pendingMachine) return false;
    Machine machine = std::move(*pendingMachine);
    pendingMachine.reset();
    const std::int64_t deadline = pendingDeadlineNs;
    lock.unlock();
    Switched result;
    const std::int64_t now = clock::monotonicNs();
    if (now > deadline) {
      result.expired = true;  // a command past its deadline is never applied
    } else {
      result.status = engine->replace(std::move(machine), now, clock::realtimeNs());
    }
    lock.lock();
    reloadResult = std::move(result);
    lock.unlock();
    signalLoop();
    return true;
  }

  // ---- reload worker thread ---------------------------------------------------------------

  /// The checked machine, or a refusal that names the path and never quotes the file; the
  /// diagnostics, which do, go to the local log only (stderr, not the bus).
  Result<Machine> loadForReload(const std::string& path) {
    std::vector<Error> diagnostics;
    auto machineResult = loadReloadMachine(path, folders, runtime.config(), runtime.catalog(), &diagnostics);
    for (const Error& diagnostic : diagnostics) {
      localLog.log(diagnostic.severity == Severity::Error ? ipc::LogLevel::Error : ipc::LogLevel::Warning,
                   "reload: " + diagnostic.toString());
    }
    return machineResult;
  }

  void publishOutputs() {
    Outputs& outputs = engine->outputs();
    if (outputs.empty()) return;
    ipc::EventBus& events = runtime.events();
    for (const ipc::FsmTransition& transition : outputs.transitions) {
      events.publish(transition);
      runtime.log().info((transition.fromState.empty() ? std::string("-") : transition.fromState) + " -> " +
                         transition.toState + ": " + transition.cause);
    }
    for (const ipc::FaultEvent& fault : outputs.faults) {
      events.publish(fault);
      const std::string line = std::string(fault.active ? "fault raised: " : "fault cleared: ") + fault.name +
                               (fault.text.empty() ? "" : ": " + fault.text);
      if (fault.active) {
        runtime.log().error(line);
      } else {
        runtime.log().info(line);
      }
    }
    for (const ipc::LogRecord& event : outputs.events) runtime.log().info(event.text);
    engine->clearOutputs();
  }

  void mirrorCounters() {
    const EngineCounters& counters = engine->counters();
    transitions.store(static_cast<std::int64_t>(counters.transitions), std::memory_order_relaxed);
    selfTransitions.store(static_cast<std::int64_t>(counters.selfTransitions), std::memory_order_relaxed);
    evaluations.store(static_cast<std::int64_t>(counters.evaluations), std::memory_order_relaxed);
    steps.store(static_cast<std::int64_t>(counters.steps), std::memory_order_relaxed);
    commands.store(static_cast<std::int64_t>(counters.commandsWritten), std::memory_order_relaxed);
    loopGuards.store(static_cast<std::int64_t>(counters.loopGuards), std::memory_order_relaxed);
    state.store(engine->state(), std::memory_order_relaxed);
  }

  void registerCounters() {
    const auto add = [this](const char* name, std::atomic<std::int64_t>& value) {
      runtime.heartbeat().addCounterSource(name, [&value] { return value.load(std::memory_order_relaxed); });
    };
    add("state", state);
    add("transitions", transitions);
    add("self_transitions", selfTransitions);
    add("evaluations", evaluations);
    add("wakeups", steps);
    add("commands_written", commands);
    add("loop_guards", loopGuards);
  }

  // ---- commands (loop thread) -------------------------------------------------------------

  service::CommandPolicy commandPolicy() {
    // The internal signals the catalog gives vcu-fsm (shared/config/catalog.hpp).
    service::CommandPolicy policy = service::CommandPolicy::byOwner(runtime.catalog(), FSM_WRITER);
    policy.veto = [](const ipc::CommandRequest&, const signals::SignalInfo& info) { return service::statusRefusal(info); };
    policy.deferredKinds = {ipc::CommandKind::FsmReload};
    policy.defer = [this](const ipc::CommandRequest& request, service::CommandReply reply) {
      startReload(request.key, std::move(reply));
    };
    return policy;
  }

  /// Hands the file to the worker and returns at once; one reload at a time.
  void startReload(const std::string& requested, service::CommandReply reply) {
    if (reloadReply) {
      reply.refuse("a reload is already in progress; the running machine is kept");
      return;
    }
    std::string path = requested;
    if (path.empty()) {
      std::error_code error;
      path = std::filesystem::absolute(runtime.config().fsmFile, error).lexically_normal().string();
    }
    runtime.log().info("reload of " + path + " requested");
    reloadReply.emplace(std::move(reply));
    reloader->start(std::move(path));
  }

  /// Loop thread, when reloadFd is readable: a checked file goes to the engine thread (unless
  /// the command's deadline passed), the engine's answer goes to the command.
  void onReloadProgress() {
    std::uint64_t count = 0;
    (void)!::read(reloadFd, &count, sizeof count);
    std::optional<Result<Machine>> loaded = reloader->take();
    if (loaded && reloadReply) {
      if (!*loaded) {
        const std::string reason = loaded->error().message;
        runtime.log().warning("reload refused: " + reason);
        finishReload([&](service::CommandReply& reply) { reply.refuse(reason + "; the running machine is kept"); });
      } else if (reloadReply->expired()) {
        runtime.log().warning("reload of " + (*loaded)->file + " not switched: its deadline passed");
        finishReload([](service::CommandReply& reply) { reply.expire(); });
      } else {
        switchingFile = (*loaded)->file;
        std::lock_guard lock(reloadMutex);
        pendingMachine = std::move(**loaded);
        pendingDeadlineNs = reloadReply->deadlineNs();
        reloadResult.reset();
        ++reloadRequests;
        wakeEngine();
      }
    }
    std::optional<Switched> switched;
    {
      std::lock_guard lock(reloadMutex);
      switched = std::move(reloadResult);
      reloadResult.reset();
    }
    if (switched && reloadReply) {
      if (switched->expired) {
        runtime.log().warning("reload not switched: its deadline passed");
        finishReload([](service::CommandReply& reply) { reply.expire(); });
      } else if (!switched->status) {
        runtime.log().warning("reload refused: " + switched->status.error().message);
        finishReload([&](service::CommandReply& reply) { reply.refuse(switched->status.error().message); });
      } else {
        runtime.log().info("reloaded " + switchingFile);
        finishReload([](service::CommandReply& reply) { reply.accept(); });
      }
    }
  }

  template <typename Answer>
  void finishReload(Answer answer) {
    service::CommandReply reply = std::move(*reloadReply);
    reloadReply.reset();
    answer(reply);
  }
};

}  // namespace openvcu::fsm

template class openvcu::service::App<openvcu::fsm::FsmAppImpl>;
