// Bringing the vehicle to an FSM state through fsm.json's transitions (vcu safety campaign).
#include "safety_campaign_plan.hpp"

#include <algorithm>
#include <deque>

#include "command_request.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::cli {
namespace {

using namespace std::chrono_literals;

constexpr std::string_view OPERATOR_PREFIX = "internal.operator.";
/// At most this many FSM steps to bring the vehicle to a state.
constexpr int MAX_STEPS = 24;

}  // namespace

StatePlanner::StatePlanner(const Stack& stack, const fsm::Machine& machine, signals::SignalTable& table,
                           double stepTimeoutSeconds, Sink& warnings)
    : m_stack(stack),
      m_machine(machine),
      m_table(table),
      m_stepTimeoutSeconds(stepTimeoutSeconds),
      m_warnings(warnings) {}

/// A slot as the stack sees it: the effective command when there is one, else the bus plane.
std::optional<SlotReading> StatePlanner::read(signals::SignalIndex index) const {
  const auto slot = m_table.read(index);
  if (!slot) return std::nullopt;
  if (const auto command = signals::effectiveCommand(*slot)) {
    return SlotReading{command->value, command->timestampNs, slot->command.updates + slot->bus.updates};
  }
  if (slot->bus.updates > 0) return SlotReading{slot->bus.value, slot->bus.timestampNs, slot->bus.updates};
  return std::nullopt;
}

std::optional<std::uint32_t> StatePlanner::currentState() const {
  const auto index = m_stack.catalog.indexOf("internal.fsm.state");
  if (!index) return std::nullopt;
  const auto reading = read(*index);
  if (!reading || reading->value < 0 || reading->value >= static_cast<double>(m_machine.states.size())) {
    return std::nullopt;
  }
  return static_cast<std::uint32_t>(reading->value);
}

std::string StatePlanner::stateName(std::optional<std::uint32_t> state) const {
  return state ? m_machine.states[*state].name : std::string("(unknown)");
}

bool StatePlanner::setSignal(const std::string& key, double value) {
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::SetSignal;
  request.key = key;
  request.value = value;
  StringSink out;
  StringSink err;
  const ExitCode code = sendCommandRequest(m_stack.config, request, DEFAULT_ACK_TIMEOUT_SECONDS, Streams{out, err});
  if (code != ExitCode::Ok) {
    m_warnings.write("vcu: warning: " + key + " = " + formatNumber(value) + " not accepted: " + out.text() +
                     err.text());
  }
  return code == ExitCode::Ok;
}

/// The operator signals to set for condition `node` to hold (the first operator branch of
/// an `any`, every one of an `all`); false when the condition reads none.
bool StatePlanner::operatorSets(std::uint32_t node, Sets& sets) const {
  if (node == fsm::NONE) return false;
  const fsm::ConditionNode& condition = m_machine.nodes[node];
  switch (condition.kind) {
    case fsm::NodeKind::Compare: {
      const std::string& key = m_stack.catalog[m_machine.signals[condition.signal].index].key;
      if (!key.starts_with(OPERATOR_PREFIX)) return false;
      if (condition.op == fsm::CompareOp::Eq) {
        sets.emplace_back(key, condition.value);
        return true;
      }
      if (condition.op == fsm::CompareOp::In && condition.count > 0) {
        sets.emplace_back(key, m_machine.constants[condition.first]);
        return true;
      }
      return false;
    }
    case fsm::NodeKind::All: {
      bool any = false;
      for (std::uint32_t i = 0; i < condition.count; ++i) {
        any = operatorSets(m_machine.children[condition.first + i], sets) || any;
      }
      return any;
    }
    case fsm::NodeKind::Any:
      for (std::uint32_t i = 0; i < condition.count; ++i) {
        if (operatorSets(m_machine.children[condition.first + i], sets)) return true;
      }
      return false;
    default:
      return false;
  }
}

std::optional<double> StatePlanner::valueAfter(signals::SignalIndex index, const Sets& sets) const {
  const std::string& key = m_stack.catalog[index].key;
  for (auto it = sets.rbegin(); it != sets.rend(); ++it) {
    if (it->first == key) return it->second;
  }
  return valueOf(index);
}

bool StatePlanner::operatorHolds(const fsm::ConditionNode& condition, double value) const {
  switch (condition.op) {
    case fsm::CompareOp::Eq:
      return value == condition.value;
    case fsm::CompareOp::Ne:
      return value != condition.value;
    case fsm::CompareOp::Lt:
      return value < condition.value;
    case fsm::CompareOp::Gt:
      return value > condition.value;
    case fsm::CompareOp::Le:
      return value <= condition.value;
    case fsm::CompareOp::Ge:
      return value >= condition.value;
    case fsm::CompareOp::In:
      for (std::uint32_t i = 0; i < condition.count; ++i) {
        if (value == m_machine.constants[condition.first + i]) return true;
      }
      return false;
  }
  return false;
}

/// An `all` turns false with one operator branch false, an `any` only with every operator
/// branch false (its vehicle branches are not the planner's to change).
bool StatePlanner::operatorBlocks(std::uint32_t node, const Sets& sets, Sets& blocks) const {
  if (node == fsm::NONE) return false;
  const fsm::ConditionNode& condition = m_machine.nodes[node];
  switch (condition.kind) {
    case fsm::NodeKind::Compare: {
      const signals::SignalIndex index = m_machine.signals[condition.signal].index;
      const signals::SignalInfo& info = m_stack.catalog[index];
      if (!info.key.starts_with(OPERATOR_PREFIX)) return false;
      const auto value = valueAfter(index, sets);
      if (!value || !operatorHolds(condition, *value)) return false;
      // the switch's first named value for which the comparison fails (0 / 1 without names)
      std::vector<double> candidates;
      for (const auto& [number, text] : info.valueTexts) candidates.push_back(static_cast<double>(number));
      if (candidates.empty()) candidates = {0, 1};
      for (const double candidate : candidates) {
        if (!operatorHolds(condition, candidate)) {
          blocks.emplace_back(info.key, candidate);
          return true;
        }
      }
      return false;
    }
    case fsm::NodeKind::All:
      for (std::uint32_t i = 0; i < condition.count; ++i) {
        if (operatorBlocks(m_machine.children[condition.first + i], sets, blocks)) return true;
      }
      return false;
    case fsm::NodeKind::Any: {
      bool any = false;
      for (std::uint32_t i = 0; i < condition.count; ++i) {
        any = operatorBlocks(m_machine.children[condition.first + i], sets, blocks) || any;
      }
      return any;
    }
    default:
      return false;
  }
}

void StatePlanner::blockEarlier(std::uint32_t state, const fsm::Transition* wanted, const Sets& sets,
                                Sets& blocks) const {
  for (const fsm::Transition& transition : m_machine.states[state].transitions) {
    if (&transition == wanted) return;
    if (transition.broken || transition.target == wanted->target || transition.target == state) continue;
    Sets found;
    if (!operatorBlocks(transition.condition, sets, found)) continue;
    for (const auto& block : found) {
      // never undo what the wanted step needs
      const bool needed =
          std::any_of(sets.begin(), sets.end(), [&](const auto& set) { return set.first == block.first; });
      if (!needed) blocks.push_back(block);
    }
  }
}

bool StatePlanner::raisesFault(std::uint32_t state) const {
  const auto& entry = m_machine.states[state].entry;
  return std::any_of(entry.begin(), entry.end(),
                     [](const fsm::Action& action) { return action.kind == fsm::ActionKind::RaiseFault; });
}

/// Breadth first over fsm.json's transitions; from each state the transitions an operator
/// input fires come before those it can only wait for.
std::vector<const fsm::Transition*> StatePlanner::pathTo(std::uint32_t from, const std::vector<std::uint32_t>& targets,
                                                         const std::vector<const fsm::Transition*>& avoid,
                                                         bool throughFaultStates) const {
  const std::size_t count = m_machine.states.size();
  std::vector<const fsm::Transition*> edgeInto(count, nullptr);
  std::vector<std::uint32_t> previous(count, fsm::NONE);
  std::vector<bool> seen(count, false);
  std::deque<std::uint32_t> queue{from};
  seen[from] = true;
  while (!queue.empty()) {
    const std::uint32_t state = queue.front();
    queue.pop_front();
    for (const bool byOperator : {true, false}) {
      for (const fsm::Transition& transition : m_machine.states[state].transitions) {
        if (transition.broken || seen[transition.target]) continue;
        if (std::find(avoid.begin(), avoid.end(), &transition) != avoid.end()) continue;
        Sets sets;
        if (operatorSets(transition.condition, sets) != byOperator) continue;
        const bool isTarget = std::find(targets.begin(), targets.end(), transition.target) != targets.end();
        if (!isTarget && !throughFaultStates && raisesFault(transition.target)) continue;
        seen[transition.target] = true;
        edgeInto[transition.target] = &transition;
        previous[transition.target] = state;
        if (isTarget) {
          std::vector<const fsm::Transition*> path;
          for (std::uint32_t at = transition.target; at != from; at = previous[at]) path.push_back(edgeInto[at]);
          std::reverse(path.begin(), path.end());
          return path;
        }
        queue.push_back(transition.target);
      }
    }
  }
  return {};
}

std::optional<double> StatePlanner::valueOf(signals::SignalIndex index) const {
  if (const auto reading = read(index)) return reading->value;
  for (const fsm::SignalRef& ref : m_machine.signals) {
    if (ref.index == index && ref.initial) return *ref.initial;
  }
  return std::nullopt;
}

bool StatePlanner::waitUntil(const std::function<bool()>& done, std::chrono::steady_clock::time_point deadline) {
  std::uint32_t epoch = m_table.changeEpoch();
  for (;;) {
    if (done()) return true;
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= 0ns) return false;
    epoch = m_table.waitForChange(epoch, std::min<std::chrono::nanoseconds>(left, 100ms));
  }
}

/// Waits (table change futex) until the FSM state is not `state`, at most until `deadline`.
std::optional<std::uint32_t> StatePlanner::waitForStateChange(std::uint32_t state,
                                                              std::chrono::steady_clock::time_point deadline) {
  std::uint32_t epoch = m_table.changeEpoch();
  for (;;) {
    const auto now = currentState();
    if (now && *now != state) return now;
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= 0ns) return now;
    epoch = m_table.waitForChange(epoch, std::min<std::chrono::nanoseconds>(left, 100ms));
  }
}

/// Brings the vehicle to one of `targets`; empty when it is there, else why not.
std::string StatePlanner::reach(const std::vector<std::uint32_t>& targets) {
  const auto stepTimeout =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(m_stepTimeoutSeconds));
  std::vector<const fsm::Transition*> avoid;  // transitions that did not fire in time
  std::string stuck;
  for (int step = 0; step < MAX_STEPS; ++step) {
    const auto state = currentState();
    if (!state) return "the FSM state is unknown (is vcu-fsm running?)";
    if (std::find(targets.begin(), targets.end(), *state) != targets.end()) return {};
    // a way round a fault state only when there is no other
    auto path = pathTo(*state, targets, avoid, false);
    if (path.empty()) path = pathTo(*state, targets, avoid, true);
    if (path.empty()) {
      return stuck.empty() ? "no transition path from " + stateName(state) + " in " + m_machine.file : stuck;
    }
    const fsm::Transition* transition = path.front();
    Sets sets;
    (void)operatorSets(transition->condition, sets);
    // switches left on that would take an earlier transition, here or in the next state
    Sets blocks;
    blockEarlier(*state, transition, sets, blocks);
    if (path.size() > 1) blockEarlier(transition->target, path[1], sets, blocks);
    for (const auto& [key, value] : blocks) {
      if (!setSignal(key, value)) return "cannot set " + key;
    }
    for (const auto& [key, value] : sets) {
      if (!setSignal(key, value)) return "cannot set " + key;
    }
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::nanoseconds(transition->afterNs) + stepTimeout;
    const auto next = waitForStateChange(*state, deadline);
    if (!next || *next == *state) {
      // e.g. a reset whose other conditions do not come true: another path (Stop, Start) next
      stuck = "stuck in " + stateName(state) + " on the way to " + m_machine.states[transition->target].name;
      avoid.push_back(transition);
    }
  }
  return "no target state after " + std::to_string(MAX_STEPS) + " steps";
}

}  // namespace openvcu::cli
