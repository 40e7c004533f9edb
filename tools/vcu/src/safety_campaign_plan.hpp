#pragma once
// Bringing a running vehicle to an FSM state through its own fsm.json (vcu safety campaign):
// a shortest path of transitions from the current state (breadth first); per step the
// operator signals (internal.operator.*) its condition compares with `eq` or `in` are set
// through the command path `vcu signal set` uses (the first operator branch of an `any`,
// every one of an `all`), and the FSM is waited for on the signal table's change futex.
// Conditions on the vehicle (the battery connecting) are waited for. A step that does not
// fire within the step timeout (plus its `after`) is avoided and the path planned again.
// The path:
//   - passes through no state whose entry raises a fault (Crash, Battery Fault, ...) unless
//     no other path exists: such a state is a target, never a way round;
//   - from each state takes first the transitions an operator input fires, then the ones
//     it waits for (Driving -> Disconnecting by ConnectDriving = Off, not by "the battery
//     no longer reports connected for 1 s");
//   - an operator switch left on that would fire an earlier transition of the same state
//     (fsm.json's order is its priority) is switched off first: ConnectDriving = Off before
//     ACCharging = AC charging in Ready.
//
//   StatePlanner planner(stack, machine, table, 15.0, streams.err);
//   std::string why = planner.reach({*machine.findState("Driving")});
//   // "" once in Driving: Standby -(StartStop=Start)-> Waking -> Ready
//   //    -(ConnectDriving=Connect for driving)-> Connecting Driving -> Driving
//   // else "stuck in Battery Timeout on the way to Ready"
//
// @note blocks (commands, waits); one thread.

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/signals/table.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

/// A slot as the stack sees it: the effective command when there is one, else the bus plane.
struct SlotReading {
  double value{};
  std::int64_t timestampNs{};  ///< CLOCK_MONOTONIC ns of the write
  std::uint64_t updates{};     ///< writes so far (command and bus planes)
};

class StatePlanner {
 public:
  /// Every reference must outlive the planner. Warnings (a command refused) go to `warnings`.
  StatePlanner(const Stack& stack, const fsm::Machine& machine, signals::SignalTable& table, double stepTimeoutSeconds,
               Sink& warnings);

  [[nodiscard]] std::optional<SlotReading> read(signals::SignalIndex index) const;
  /// The value vcu-fsm reads for the signal: as read(), else the machine's initial value of
  /// an internal signal nobody wrote yet; empty when neither is known.
  [[nodiscard]] std::optional<double> valueOf(signals::SignalIndex index) const;
  /// Waits on the table's change futex (looking at least every 100 ms) until `done` or
  /// `deadline`; true when done.
  bool waitUntil(const std::function<bool()>& done, std::chrono::steady_clock::time_point deadline);
  /// internal.fsm.state as a state index; empty when unknown.
  [[nodiscard]] std::optional<std::uint32_t> currentState() const;
  [[nodiscard]] std::string stateName(std::optional<std::uint32_t> state) const;
  /// `vcu signal set KEY VALUE`; false (and a warning) when not accepted.
  bool setSignal(const std::string& key, double value);
  /// Brings the vehicle to one of `targets`; empty when it is there, else why not.
  std::string reach(const std::vector<std::uint32_t>& targets);

 private:
  using Sets = std::vector<std::pair<std::string, double>>;
  bool operatorSets(std::uint32_t node, Sets& sets) const;
  /// Adds to `blocks` the operator switches to change so that condition `node` turns false
  /// once `sets` are applied; false when it reads no operator switch that would hold.
  bool operatorBlocks(std::uint32_t node, const Sets& sets, Sets& blocks) const;
  /// `condition` compares an operator switch, and holds once `sets` are applied.
  [[nodiscard]] bool operatorHolds(const fsm::ConditionNode& condition, double value) const;
  [[nodiscard]] std::optional<double> valueAfter(signals::SignalIndex index, const Sets& sets) const;
  /// Blocks for every transition of `state` before `wanted` (fsm.json's priority) to
  /// another state that an operator switch would fire once `sets` are applied.
  void blockEarlier(std::uint32_t state, const fsm::Transition* wanted, const Sets& sets, Sets& blocks) const;
  /// The transitions of a shortest path from `from` to any of `targets`; empty when none.
  [[nodiscard]] std::vector<const fsm::Transition*> pathTo(std::uint32_t from,
                                                           const std::vector<std::uint32_t>& targets,
                                                           const std::vector<const fsm::Transition*>& avoid,
                                                           bool throughFaultStates) const;
  [[nodiscard]] bool raisesFault(std::uint32_t state) const;
  std::optional<std::uint32_t> waitForStateChange(std::uint32_t state, std::chrono::steady_clock::time_point deadline);

  const Stack& m_stack;
  const fsm::Machine& m_machine;
  signals::SignalTable& m_table;
  double m_stepTimeoutSeconds;
  Sink& m_warnings;
};

}  // namespace openvcu::cli
