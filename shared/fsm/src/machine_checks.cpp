#include "machine_checks.hpp"
#include "openvcu/core/text.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace openvcu::fsm {
namespace {

using config::JsonChecker;

using text::number;

bool isLeaf(const ConditionNode& node) {
  return node.kind == NodeKind::Compare || node.kind == NodeKind::Quality || node.kind == NodeKind::Age;
}

/// What the comparisons of one signal in one `all` allow.
struct Feasible {
  double low{-std::numeric_limits<double>::infinity()};
  double high{std::numeric_limits<double>::infinity()};
  bool lowInclusive{};
  bool highInclusive{};
  std::optional<std::vector<double>> allowed;  ///< eq / in narrow to a set
  std::vector<double> excluded;                ///< ne

  void add(const Machine& machine, const ConditionNode& node) {
    const auto narrow = [&](std::vector<double> values) {
      if (!allowed) {
        allowed = std::move(values);
        return;
      }
      std::erase_if(*allowed, [&](double value) { return std::find(values.begin(), values.end(), value) == values.end(); });
    };
    switch (node.op) {
      case CompareOp::Eq: narrow({node.value}); break;
      case CompareOp::In:
        narrow(std::vector<double>(machine.constants.begin() + node.first,
                                   machine.constants.begin() + node.first + node.count));
        break;
      case CompareOp::Ne: excluded.push_back(node.value); break;
      case CompareOp::Lt: setHigh(node.value, false); break;
      case CompareOp::Le: setHigh(node.value, true); break;
      case CompareOp::Gt: setLow(node.value, false); break;
      case CompareOp::Ge: setLow(node.value, true); break;
    }
  }
  void setHigh(double value, bool inclusive) {
    if (value < high || (value == high && !inclusive)) {
      high = value;
      highInclusive = inclusive;
    }
  }
  void setLow(double value, bool inclusive) {
    if (value > low || (value == low && !inclusive)) {
      low = value;
      lowInclusive = inclusive;
    }
  }
  [[nodiscard]] bool inside(double value) const {
    const bool aboveLow = value > low || (lowInclusive && value == low);
    const bool belowHigh = value < high || (highInclusive && value == high);
    return aboveLow && belowHigh && std::find(excluded.begin(), excluded.end(), value) == excluded.end();
  }
  [[nodiscard]] bool possible() const {
    if (allowed) return std::any_of(allowed->begin(), allowed->end(), [&](double value) { return inside(value); });
    if (low < high) return true;
    return low == high && lowInclusive && highInclusive && inside(low);
  }
};

bool alwaysTrue(const Machine& machine, const Transition& transition) {
  if (transition.afterNs > 0 || transition.condition == NONE) return false;
  const ConditionNode& node = machine.nodes[transition.condition];
  if (node.forNs > 0) return false;
  return node.kind == NodeKind::True || (node.kind == NodeKind::All && node.count == 0);
}

bool changesSomething(const std::vector<Action>& actions) {
  return std::any_of(actions.begin(), actions.end(), [](const Action& action) { return action.kind != ActionKind::Nothing; });
}

void collect(const Machine& machine, std::uint32_t node, std::vector<std::uint32_t>& out) {
  if (node == NONE) return;
  const ConditionNode& current = machine.nodes[node];
  if (current.signal != NONE) out.push_back(current.signal);
  if (current.kind == NodeKind::All || current.kind == NodeKind::Any || current.kind == NodeKind::Not) {
    for (std::uint32_t c = 0; c < current.count; ++c) collect(machine, machine.children[current.first + c], out);
  }
}

}  // namespace

std::string formatDuration(std::int64_t ns) {
  if (ns % 60'000'000'000 == 0) return std::to_string(ns / 60'000'000'000) + "min";
  if (ns % 1'000'000'000 == 0) return std::to_string(ns / 1'000'000'000) + "s";
  if (ns % 1'000'000 == 0) return std::to_string(ns / 1'000'000) + "ms";
  return number(static_cast<double>(ns) / 1e6) + "ms";
}

std::string describeCondition(const Machine& machine, const signals::Catalog& catalog, std::uint32_t node) {
  if (node == NONE) return "always";
  const ConditionNode& current = machine.nodes[node];
  std::string text;
  const auto key = [&] { return catalog[machine.signals[current.signal].index].key; };
  switch (current.kind) {
    case NodeKind::True: text = "always"; break;
    case NodeKind::All:
    case NodeKind::Any:
    case NodeKind::Not: {
      text = current.kind == NodeKind::All ? "all(" : current.kind == NodeKind::Any ? "any(" : "not(";
      for (std::uint32_t c = 0; c < current.count; ++c) {
        if (c > 0) text += ", ";
        text += describeCondition(machine, catalog, machine.children[current.first + c]);
      }
      text += ')';
      break;
    }
    case NodeKind::Compare:
      text = key();
      text += ' ';
      text += compareOpName(current.op);
      text += ' ';
      if (current.op == CompareOp::In) {
        text += '[';
        for (std::uint32_t v = 0; v < current.count; ++v) {
          if (v > 0) text += ", ";
          text += number(machine.constants[current.first + v]);
        }
        text += ']';
      } else {
        text += number(current.value);
      }
      break;
    case NodeKind::Quality: {
      text = key() + " quality ";
      constexpr std::string_view NAMES[] = {"neverReceived", "valid", "stale", "outOfRange"};
      bool first = true;
      for (unsigned q = 0; q < 4; ++q) {
        if ((current.qualityMask & (1U << q)) == 0) continue;
        if (!first) text += '|';
        text += NAMES[q];
        first = false;
      }
      break;
    }
    case NodeKind::Age: text = key() + " ageGt " + formatDuration(current.durationNs); break;
  }
  if (current.forNs > 0) text += " for " + formatDuration(current.forNs);
  return text;
}

void checkSiblings(JsonChecker& check, const Machine& machine, const signals::Catalog& catalog, std::uint32_t node,
                   const std::string& listPath) {
  const ConditionNode& parent = machine.nodes[node];
  std::map<std::string, std::vector<std::uint32_t>> same;  // text -> children
  std::map<std::uint32_t, std::vector<std::uint32_t>> bySignal;
  std::vector<std::string> order;
  for (std::uint32_t c = 0; c < parent.count; ++c) {
    const std::uint32_t child = machine.children[parent.first + c];
    const ConditionNode& current = machine.nodes[child];
    if (!isLeaf(current)) continue;
    const std::string text = describeCondition(machine, catalog, child);
    if (same[text].empty()) order.push_back(text);
    same[text].push_back(c);
    if (current.kind == NodeKind::Compare && current.forNs == 0) bySignal[current.signal].push_back(child);
  }
  for (const std::string& text : order) {
    const auto& entries = same[text];
    if (entries.size() < 2) continue;
    std::string message = "the same condition " + std::to_string(entries.size()) + " times: '" + text + "'";
    if (entries.size() > 2) message += " (different signals meant?)";
    check.warning(listPath == parent.path ? listPath : JsonChecker::join(listPath, entries[1]), std::move(message));
  }
  if (parent.kind != NodeKind::All) return;
  for (const auto& [signal, children] : bySignal) {
    if (children.size() < 2) continue;
    Feasible feasible;
    for (const std::uint32_t child : children) feasible.add(machine, machine.nodes[child]);
    if (feasible.possible()) continue;
    std::string terms;
    for (const std::uint32_t child : children) {
      if (!terms.empty()) terms += ", ";
      terms += describeCondition(machine, catalog, child);
    }
    check.error(listPath,
                "can never be true: " + catalog[machine.signals[signal].index].key + " cannot satisfy all of " + terms +
                    " at once");
  }
}

void checkMachineGraph(JsonChecker& check, const Machine& machine, const signals::Catalog& catalog,
                       bool initialDefined) {
  const std::size_t count = machine.states.size();
  std::vector<bool> incoming(count, false);
  for (std::size_t s = 0; s < count; ++s) {
    const State& state = machine.states[s];
    std::map<std::string, std::size_t> seen;
    bool shadowed = false;
    for (std::size_t t = 0; t < state.transitions.size(); ++t) {
      const Transition& transition = state.transitions[t];
      if (transition.target != NONE && transition.target != s) incoming[transition.target] = true;
      if (transition.broken) continue;
      if (shadowed) {
        check.warning(transition.path, "never taken: an earlier transition of state '" + state.name +
                                           "' is always true (transitions are tried in file order)");
        continue;
      }
      const std::string key = describeCondition(machine, catalog, transition.condition) + " after " +
                              std::to_string(transition.afterNs);
      if (const auto it = seen.find(key); it != seen.end()) {
        check.warning(transition.path, "never taken: same condition as " + state.transitions[it->second].path +
                                           ", which is tried first");
      } else {
        seen.emplace(key, t);
      }
      if (transition.target == s && !changesSomething(transition.actions)) {
        check.warning(transition.path, "returns to its own state '" + state.name + "' and does nothing");
      }
      shadowed = alwaysTrue(machine, transition);
    }
  }
  if (initialDefined && count > 0) {
    std::vector<bool> reached(count, false);
    std::vector<std::uint32_t> pending{machine.initial};
    reached[machine.initial] = true;
    while (!pending.empty()) {
      const std::uint32_t s = pending.back();
      pending.pop_back();
      for (const Transition& transition : machine.states[s].transitions) {
        if (transition.target == NONE || reached[transition.target]) continue;
        reached[transition.target] = true;
        pending.push_back(transition.target);
      }
    }
    for (std::size_t s = 0; s < count; ++s) {
      if (!reached[s]) {
        check.warning(JsonChecker::join("/states", s), "state '" + machine.states[s].name +
                                                           "' is unreachable from the initial state '" +
                                                           machine.states[machine.initial].name + "'");
      }
    }
  } else {
    for (std::size_t s = 0; s < count; ++s) {
      if (!incoming[s] && !machine.states[s].name.empty()) {
        check.warning(JsonChecker::join("/states", s),
                      "no transition leads to state '" + machine.states[s].name + "' (and it is not the initial state)");
      }
    }
  }
  if (machine.timerCount > PERSISTED_TIMERS) {
    check.warning("/", std::to_string(machine.timerCount) + " `for` conditions: the running timers of those after the " +
                           std::to_string(PERSISTED_TIMERS) + "th restart from zero when vcu-fsm restarts");
  }
}

void collectStateSignals(const Machine& machine, State& state) {
  state.signals.clear();
  for (const Transition& transition : state.transitions) collect(machine, transition.condition, state.signals);
  std::sort(state.signals.begin(), state.signals.end());
  state.signals.erase(std::unique(state.signals.begin(), state.signals.end()), state.signals.end());
}

}  // namespace openvcu::fsm
