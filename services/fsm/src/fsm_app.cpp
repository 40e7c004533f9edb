#include "fsm_app.hpp"

#include <atomic>
#include <condition_variable>
#include <ctime>
#include <mutex>
#include <thread>

#include "engine.hpp"
#include "machine.hpp"

namespace openvcu::fsm {
namespace {

/// The longest the engine thread sleeps without a table change or a deadline: it also
/// bounds how long stop() and a reload wait.
constexpr std::chrono::milliseconds LONGEST_SLEEP{250};
constexpr std::chrono::seconds RELOAD_WAIT{3};
/// Keys vcu-fsm answers commands for: the internal signals except can-tx's send groups and
/// vcu-gpio's keys (internal.gpio.* and the signals of input lines).
constexpr std::string_view OWNED_PREFIX = "internal.";
constexpr std::string_view CAN_TX_PREFIX = "internal.tx.";
constexpr std::string_view GPIO_PREFIX = "internal.gpio.";
constexpr std::string_view STATUS_PREFIXES[] = {"internal.fsm.", "internal.service.", "internal.bus.",
                                                "internal.dm1."};

std::int64_t realtimeNs() noexcept {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

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
  // A reload handed from the loop thread to the engine thread.
  std::mutex reloadMutex;
  std::condition_variable reloadDone;
  std::optional<Machine> pendingMachine;
  std::optional<Status> reloadResult;
  std::uint64_t reloadRequests{};

  explicit FsmAppImpl(service::Service& service) : runtime(service), access(service.table(), FSM_WRITER) {}

  ~FsmAppImpl() {
    stopping.store(true);  // the engine thread sees it within LONGEST_SLEEP
    if (thread.joinable()) thread.join();
  }

  /// Counts a reload request in internal.fsm.reloads, which also wakes the engine thread
  /// out of waitForChange at once.
  void wakeEngine() {
    if (const auto index = runtime.catalog().indexOf("internal.fsm.reloads")) {
      runtime.table().writeBus(*index, static_cast<double>(reloadRequests), signals::monotonicNowNs(), FSM_WRITER,
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
    engine->start(signals::monotonicNowNs(), realtimeNs(), StartMode::Resume);
    publishOutputs();
    mirrorCounters();

    if (Status answering = runtime.answerCommands(commandPolicy()); !answering) return answering.error();
    registerCounters();
    thread = std::thread([this] { runEngine(); });
    return {};
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
    signals::SignalWatch watch = watchMachine();
    while (!stopping.load(std::memory_order_relaxed)) {
      const std::uint32_t epoch = watch.epoch();
      if (takeReload()) {
        watch = watchMachine();  // the new machine reads other signals
        continue;
      }
      engine->step(signals::monotonicNowNs(), realtimeNs());
      publishOutputs();
      mirrorCounters();
      const std::int64_t now = signals::monotonicNowNs();
      const std::int64_t deadline = engine->nextDeadlineNs();
      std::chrono::nanoseconds timeout = LONGEST_SLEEP;
      if (deadline != NO_DEADLINE) timeout = std::min(timeout, std::chrono::nanoseconds(std::max<std::int64_t>(deadline - now, 0)));
      if (timeout.count() > 0) (void)watch.wait(epoch, timeout);
    }
  }

  /// true when a new machine was taken (or refused) for a pending reload.
  bool takeReload() {
    std::unique_lock lock(reloadMutex);
    if (!pendingMachine) return false;
    Machine machine = std::move(*pendingMachine);
    pendingMachine.reset();
    lock.unlock();
    Status result = engine->replace(std::move(machine), signals::monotonicNowNs(), realtimeNs());
    lock.lock();
    reloadResult = std::move(result);
    reloadDone.notify_all();
    return true;
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
    service::CommandPolicy policy;
    const config::GpioMap& gpio = runtime.config().gpio;
    policy.owns = [&gpio](std::string_view key) {
      return key.starts_with(OWNED_PREFIX) && !key.starts_with(CAN_TX_PREFIX) && !key.starts_with(GPIO_PREFIX) &&
             gpio.inputBoundTo(key) == nullptr;
    };
    policy.veto = [](const ipc::CommandRequest&, const signals::SignalInfo& info) -> std::optional<std::string> {
      for (const std::string_view prefix : STATUS_PREFIXES) {
        if (info.key.starts_with(prefix)) return "'" + info.key + "' is a status the stack reports; it cannot be commanded";
      }
      return std::nullopt;
    };
    policy.customKinds = {ipc::CommandKind::FsmReload};
    policy.custom = [this](const ipc::CommandRequest& request) { return reload(request.key); };
    return policy;
  }

  /// Loads and checks the file here (the engine keeps running), then hands it to the engine
  /// thread, which switches between two steps. The reason when refused.
  std::optional<std::string> reload(const std::string& requested) {
    const std::string path = requested.empty() ? runtime.config().fsmFile : requested;
    std::vector<Error> diagnostics;
    auto machineResult = loadMachine(path, runtime.config(), runtime.catalog(), &diagnostics);
    if (!machineResult) return machineResult.error().toString() + "; the running machine is kept";
    report(diagnostics);
    std::unique_lock lock(reloadMutex);
    pendingMachine = std::move(*machineResult);
    reloadResult.reset();
    ++reloadRequests;
    lock.unlock();
    wakeEngine();
    lock.lock();
    if (!reloadDone.wait_for(lock, RELOAD_WAIT, [this] { return reloadResult.has_value(); })) {
      pendingMachine.reset();
      return "the engine did not take the new machine within " + std::to_string(RELOAD_WAIT.count()) +
             " s; the running machine is kept";
    }
    if (!*reloadResult) return reloadResult->error().message;
    runtime.log().info("reloaded " + path);
    return std::nullopt;
  }
};

Result<std::unique_ptr<FsmApp>> FsmApp::create(service::Service& runtime) {
  auto impl = std::make_unique<FsmAppImpl>(runtime);
  if (Status opened = impl->open(); !opened) return opened.error();
  return std::unique_ptr<FsmApp>(new FsmApp(std::move(impl)));
}

FsmApp::FsmApp(std::unique_ptr<FsmAppImpl> impl) noexcept : m_impl(std::move(impl)) {}
FsmApp::~FsmApp() = default;

}  // namespace openvcu::fsm
