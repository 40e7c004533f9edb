#pragma once
// Bringing a running vehicle to an FSM state through its own fsm.json (vcu safety campaign):
// a shortest path of transitions from the current state (breadth first); per step the
// operator signals (internal.operator.*) its condition compares with `eq` or `in` are set
// through the command path `vcu signal set` uses (the first operator branch of an `any`,
// every one of an `all`), and the FSM is waited for on the signal table's change futex.
// Conditions on the vehicle (the battery connecting) are waited for. A step that does not
// fire within the step timeout (plus its `after`) is avoided and the path planned again.
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
  /// internal.fsm.state as a state index; empty when unknown.
  [[nodiscard]] std::optional<std::uint32_t> currentState() const;
  [[nodiscard]] std::string stateName(std::optional<std::uint32_t> state) const;
  /// `vcu signal set KEY VALUE`; false (and a warning) when not accepted.
  bool setSignal(const std::string& key, double value);
  /// Brings the vehicle to one of `targets`; empty when it is there, else why not.
  std::string reach(const std::vector<std::uint32_t>& targets);

 private:
  bool operatorSets(std::uint32_t node, std::vector<std::pair<std::string, double>>& sets) const;
  [[nodiscard]] const fsm::Transition* firstStep(std::uint32_t from, const std::vector<std::uint32_t>& targets,
                                                 const std::vector<const fsm::Transition*>& avoid) const;
  std::optional<std::uint32_t> waitForStateChange(std::uint32_t state, std::chrono::steady_clock::time_point deadline);

  const Stack& m_stack;
  const fsm::Machine& m_machine;
  signals::SignalTable& m_table;
  double m_stepTimeoutSeconds;
  Sink& m_warnings;
};

}  // namespace openvcu::cli
