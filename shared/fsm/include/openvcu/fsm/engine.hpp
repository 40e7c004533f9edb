#pragma once
// The state machine at run time (docs/fsm.md, "Semantics"): a compiled Machine over the
// signals it reads, stepped by the caller whenever the table changed or a deadline passed.
//
//   fsm::TableAccess access(table, FSM_WRITER);
//   auto slotsResult = fsm::StatusSlots::find(catalog);
//   fsm::Engine engine(std::move(machine), catalog, access, *slotsResult);
//   engine.start(monoNs, realNs, fsm::StartMode::Resume);
//   for (;;) { engine.step(monoNs, realNs); publish(engine.outputs()); engine.clearOutputs();
//              sleep until a table change or engine.nextDeadlineNs(); }
//
// step() re-reads only the signals the machine reads, evaluates the current state's
// transitions only when one of its signals changed value or quality or a deadline passed,
// and after a transition evaluates again until nothing more fires (at most MAX_FIRINGS).
// Commands are written before anything is formatted or published.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/core/clock.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::fsm {

/// vcu-fsm's writer id in the signal table.
inline constexpr signals::WriterId FSM_WRITER = config::writerOf(config::ServiceId::Fsm);
/// Transitions taken in one step before the loop guard stops it and raises "fsm_loop". The
/// stopped machine evaluates again only when one of its state's signals changes or one of
/// its deadlines passes (never because of its own writes), so a machine that does not settle
/// costs at most MAX_FIRINGS transitions per input change, never a spinning core.
inline constexpr std::uint32_t MAX_FIRINGS = 32;
inline constexpr std::int64_t NO_DEADLINE = std::numeric_limits<std::int64_t>::max();
/// After the table lost its values (issue 18: truncated or overwritten), how long an input
/// that reads as never written keeps its previous sample: long enough for the slowest
/// input (1 s cycle) to be written again, so the wipe is not taken for a sensor dropout.
inline constexpr std::int64_t DAMAGE_GRACE_NS = 1'500'000'000;

/// How the engine reads and writes signals: the shared table in the service, plain memory
/// in `vcu fsm replay` and in tests.
class SignalAccess {
 public:
  virtual ~SignalAccess() = default;
  [[nodiscard]] virtual std::optional<signals::SlotSnapshot> read(signals::SignalIndex index) noexcept = 0;
  virtual void writeCommand(signals::SignalIndex index, double value, std::int64_t nowNs) noexcept = 0;
  /// The FSM's own status slots (bus plane).
  virtual void writeStatus(signals::SignalIndex index, double value, std::int64_t nowNs) noexcept = 0;
};

class TableAccess final : public SignalAccess {
 public:
  TableAccess(signals::SignalTable& table, signals::WriterId writer) noexcept : m_table(table), m_writer(writer) {}
  std::optional<signals::SlotSnapshot> read(signals::SignalIndex index) noexcept override { return m_table.read(index); }
  /// Stamped with the time of the write itself (not the step's start), so that readers and
  /// the latency benchmark see when the command really changed.
  void writeCommand(signals::SignalIndex index, double value, std::int64_t /*stepNs*/) noexcept override {
    m_table.writeCommand(index, value, clock::monotonicNs(), m_writer);
  }
  void writeStatus(signals::SignalIndex index, double value, std::int64_t nowNs) noexcept override {
    m_table.writeBus(index, value, nowNs, m_writer, signals::Quality::Valid);
  }

 private:
  signals::SignalTable& m_table;
  signals::WriterId m_writer;
};

/// Every slot in memory (replay, tests): set bus values, read back commands.
class MemoryAccess final : public SignalAccess {
 public:
  explicit MemoryAccess(std::size_t size) : m_slots(size) {}
  std::optional<signals::SlotSnapshot> read(signals::SignalIndex index) noexcept override;
  void writeCommand(signals::SignalIndex index, double value, std::int64_t nowNs) noexcept override;
  void writeStatus(signals::SignalIndex index, double value, std::int64_t nowNs) noexcept override;
  void setBus(signals::SignalIndex index, double value, std::int64_t nowNs,
              signals::Quality quality = signals::Quality::Valid) noexcept;
  void setQuality(signals::SignalIndex index, signals::Quality quality) noexcept;
  void setCommand(signals::SignalIndex index, double value, std::int64_t nowNs, signals::WriterId writer) noexcept;
  [[nodiscard]] const signals::SlotSnapshot& slot(signals::SignalIndex index) const { return m_slots.at(index); }

 private:
  std::vector<signals::SlotSnapshot> m_slots;
};

/// The table slots where the FSM keeps what a restarted vcu-fsm needs.
struct StatusSlots {
  signals::SignalIndex state{};         ///< internal.fsm.state: state index
  signals::SignalIndex stateSince{};    ///< internal.fsm.stateSince: CLOCK_REALTIME s (for people)
  signals::SignalIndex stateEntered{};  ///< internal.fsm.stateEntered: CLOCK_MONOTONIC s (for `after`)
  signals::SignalIndex machine{};       ///< internal.fsm.machine: Machine::hash
  std::vector<signals::SignalIndex> timers;  ///< internal.fsm.timer.<i>: CLOCK_MONOTONIC s a `for` began, 0 idle

  /// Fails when the catalog lacks one of them (a catalog not built by config::buildCatalog).
  static Result<StatusSlots> find(const signals::Catalog& catalog);
};

enum class StartMode : std::uint8_t {
  Resume,  ///< continue the state the table holds if it was left by this same machine
  Fresh,   ///< always enter the initial state (and run its entry actions)
};

/// What a step produced, for the caller to publish (allocated after the commands were written).
struct Outputs {
  std::vector<ipc::FsmTransition> transitions;
  std::vector<ipc::FaultEvent> faults;
  std::vector<ipc::LogRecord> events;
  [[nodiscard]] bool empty() const noexcept { return transitions.empty() && faults.empty() && events.empty(); }
};

struct EngineCounters {
  std::uint64_t steps{};        ///< step() calls
  std::uint64_t evaluations{};  ///< evaluations of the current state's transitions
  std::uint64_t transitions{};  ///< to another state
  std::uint64_t selfTransitions{};
  std::uint64_t commandsWritten{};
  std::uint64_t loopGuards{};   ///< evaluations stopped by MAX_FIRINGS
};

/// @note restricted thread-safe: one thread. step() does not allocate unless a transition
///       fires (then it formats the outputs).
class Engine {
 public:
  Engine(Machine machine, const signals::Catalog& catalog, SignalAccess& access, StatusSlots slots);

  /// Enters the initial state (running its entry actions) or resumes the table's state,
  /// then evaluates once.
  void start(std::int64_t monoNs, std::int64_t realNs, StartMode mode);
  /// Reads the machine's signals; evaluates when one of the current state's changed or a
  /// deadline passed (or `force`). Returns true when it evaluated.
  bool step(std::int64_t monoNs, std::int64_t realNs, bool force = false);
  /// Switches to `machine` keeping the current state (by name) and its entry time; `for`
  /// timers restart. Refused, with the old machine kept, when the state does not exist in it.
  Status replace(Machine machine, std::int64_t monoNs, std::int64_t realNs);
  /// After the table lost its values (docs/design/signal-table.md, "Damage"): writes back
  /// everything the FSM keeps there (machine hash, state, entry time, `for` timers) and the
  /// last command of every signal the FSM (its actions, or commands answered by vcu-fsm)
  /// commanded and nobody else commanded since, and starts the DAMAGE_GRACE_NS window in
  /// which an input that reads as never written keeps its previous sample. Returns the
  /// number of commands written back.
  /// @note noexcept, allocation-free.
  std::size_t restoreTable(std::int64_t monoNs, std::int64_t realNs) noexcept;

  /// The earliest CLOCK_MONOTONIC time a timer (`for`, `after`, `ageGt`) or the end of a
  /// damage grace window can change an evaluation; NO_DEADLINE when none runs.
  [[nodiscard]] std::int64_t nextDeadlineNs() const noexcept {
    return m_graceUntilNs > 0 ? std::min(m_deadline, m_graceUntilNs) : m_deadline;
  }
  /// true while inputs that read as never written keep their previous samples.
  [[nodiscard]] bool inDamageGrace(std::int64_t monoNs) const noexcept { return monoNs < m_graceUntilNs; }
  [[nodiscard]] std::uint32_t state() const noexcept { return m_state; }
  [[nodiscard]] const std::string& stateName() const noexcept { return m_machine.states[m_state].name; }
  [[nodiscard]] std::int64_t enteredNs() const noexcept { return m_enteredNs; }
  [[nodiscard]] const Machine& machine() const noexcept { return m_machine; }
  [[nodiscard]] const EngineCounters& counters() const noexcept { return m_counters; }
  [[nodiscard]] Outputs& outputs() noexcept { return m_outputs; }
  void clearOutputs() noexcept;

 private:
  struct Sample {
    double value{};
    std::int64_t timestampNs{};
    signals::Quality quality{signals::Quality::NeverReceived};
    bool present{};
    /// The update counters of the planes read (bus; + command + override for ReadPlane::
    /// Command): they only grow, unless the table lost its values.
    std::uint64_t written{};
  };
  /// The last command of a signal the FSM commands or reads on the command plane.
  struct OwnedCommand {
    signals::SignalIndex index{};
    double value{};
    bool ours{};  ///< the newest command seen was the FSM's (FSM_WRITER)
  };

  void resize();
  bool refresh(std::int64_t monoNs) noexcept;
  /// Notes, per owned signal, whether its newest command is the FSM's (one read each).
  void trackCommands() noexcept;
  void remember(signals::SignalIndex index, double value, bool ours) noexcept;
  void evaluate(std::int64_t monoNs, std::int64_t realNs);
  bool evalNode(std::uint32_t node, std::int64_t monoNs) noexcept;
  bool evalRaw(const ConditionNode& node, std::int64_t monoNs) noexcept;
  bool runActions(const std::vector<Action>& actions, std::int64_t monoNs);
  /// A `from` action's value: the source's command (override first), else its bus value,
  /// clamped to the target's range; false while the source has neither.
  bool copiedValue(const Action& action, double& value) noexcept;
  void enter(std::uint32_t state, std::int64_t monoNs, std::int64_t realNs);
  void setTimer(std::uint32_t timer, std::int64_t sinceNs, std::int64_t monoNs) noexcept;
  void writeState(std::int64_t monoNs, std::int64_t realNs) noexcept;
  std::string cause(const Transition& transition) const;
  void describeValues(std::uint32_t node, std::string& out) const;

  Machine m_machine;
  const signals::Catalog& m_catalog;
  SignalAccess& m_access;
  StatusSlots m_slots;
  std::vector<Sample> m_samples;
  std::vector<std::uint8_t> m_changed;
  std::vector<std::int64_t> m_timers;      ///< per `for` timer: CLOCK_MONOTONIC start, 0 idle
  std::vector<std::uint8_t> m_held;        ///< per transition of the current state: true at the last evaluation
  std::vector<std::uint8_t> m_conditions;  ///< scratch: this evaluation's results
  std::vector<OwnedCommand> m_owned;       ///< action targets and command-plane inputs, once each
  std::vector<std::uint32_t> m_ownedOf;    ///< per catalog index: its entry in m_owned, or NONE
  std::uint32_t m_state{};
  std::int64_t m_enteredNs{};
  std::int64_t m_deadline{NO_DEADLINE};
  std::int64_t m_pendingDeadline{NO_DEADLINE};
  std::int64_t m_graceUntilNs{};  ///< CLOCK_MONOTONIC end of the damage grace window; 0: none
  bool m_looping{};  ///< the last evaluation was stopped by the loop guard (fsm_loop raised)
  Outputs m_outputs;
  EngineCounters m_counters;
};

}  // namespace openvcu::fsm
