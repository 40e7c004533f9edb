// The spin check (machine_cycles.hpp): elementary cycles of transitions, and for each a
// search for signal values under which the cycle keeps firing, in three-valued logic
// (true, false, not decided) so that nothing undecidable is ever claimed.

#include "machine_cycles.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "openvcu/core/text.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::fsm {
namespace {

using config::JsonChecker;

/// Cycles examined and condition evaluations made before the search gives up (a warning
/// says so); far above what a vehicle's machine needs (HHEA: a few hundred evaluations).
constexpr std::size_t MAX_CYCLES = 20'000;
constexpr std::size_t MAX_EVALUATIONS = 2'000'000;
/// Steps of the cycle enumeration (edges followed) and the longest cycle followed: a file
/// of tens of thousands of states neither stalls the check nor exhausts the stack.
constexpr std::size_t MAX_STEPS = 2'000'000;
constexpr std::size_t MAX_CYCLE_LENGTH = 64;
/// Errors reported one by one; further spinning cycles are counted in one more error.
constexpr std::size_t MAX_REPORTED = 5;
constexpr std::size_t MAX_WITNESS_SIGNALS = 4;

enum class Truth : std::uint8_t { False, True, Unknown };

Truth both(Truth a, Truth b) {
  if (a == Truth::False || b == Truth::False) return Truth::False;
  if (a == Truth::True && b == Truth::True) return Truth::True;
  return Truth::Unknown;
}

Truth either(Truth a, Truth b) {
  if (a == Truth::True || b == Truth::True) return Truth::True;
  if (a == Truth::False && b == Truth::False) return Truth::False;
  return Truth::Unknown;
}

Truth negate(Truth a) {
  if (a == Truth::Unknown) return a;
  return a == Truth::True ? Truth::False : Truth::True;
}

using text::number;

/// One signal as a condition sees it (engine.cpp's Sample, with the age instead of a time).
struct Value {
  bool present{};
  double value{};
  signals::Quality quality{signals::Quality::NeverReceived};
  std::int64_t ageNs{};  ///< how long since the value was written; -1: no time (an initial value)
};

/// One transition between two different states: an edge of the cycle graph.
struct Edge {
  std::uint32_t from{};
  std::uint32_t transition{};  ///< index in the state's transitions
  std::uint32_t to{};
};

/// A condition that must hold (or must not) when the cycle is in state `point`.
struct Constraint {
  std::uint32_t node{NONE};
  bool mustHold{};
  std::size_t point{};                 ///< index of the cycle's state where it is evaluated
  std::vector<std::uint32_t> signals;  ///< the signal slots it reads that the cycle does not write
};

class CycleSearch {
 public:
  CycleSearch(const Machine& machine, const signals::Catalog& catalog) : m_machine(machine), m_catalog(catalog) {}

  /// The values that keep `cycle` firing, or empty when that is not proved.
  std::optional<std::vector<std::pair<std::uint32_t, Value>>> prove(const std::vector<Edge>& cycle) {
    m_cycle = &cycle;
    if (!buildConstraints()) return std::nullopt;
    computeWrites();
    collectVariables();
    m_assigned.assign(m_machine.signals.size(), std::nullopt);
    if (!search()) return std::nullopt;
    std::vector<std::pair<std::uint32_t, Value>> witness;
    for (const std::uint32_t slot : m_variables) {
      if (m_assigned[slot]) witness.emplace_back(slot, *m_assigned[slot]);
    }
    return witness;
  }

  [[nodiscard]] bool exhausted() const noexcept { return m_evaluations >= MAX_EVALUATIONS; }

  /// The truth of `node` knowing nothing about any signal (used to drop edges that can never
  /// fire at the moment of entry, e.g. a `for` at the top).
  Truth staticTruth(std::uint32_t node) {
    m_known.clear();
    m_assigned.assign(m_machine.signals.size(), std::nullopt);
    m_unknownOnCycle.clear();
    m_known.resize(1);
    return eval(node, 0);
  }

 private:
  /// For each state of the cycle: its edge's condition must hold, the conditions of the
  /// other-state transitions before it must not (file order is priority; self-transitions
  /// never take precedence for long: they fire once and are then held).
  bool buildConstraints() {
    m_constraints.clear();
    std::vector<Constraint> earlier;
    const std::vector<Edge>& cycle = *m_cycle;
    for (std::size_t point = 0; point < cycle.size(); ++point) {
      const State& state = m_machine.states[cycle[point].from];
      for (std::uint32_t t = 0; t <= cycle[point].transition; ++t) {
        const Transition& transition = state.transitions[t];
        const bool chosen = t == cycle[point].transition;
        if (!chosen && transition.target == cycle[point].from) continue;
        if (!chosen && transition.afterNs > 0) continue;  // not due at the moment of entry
        // A broken condition (the file has errors anyway): nothing is proved about this state.
        if (transition.broken || transition.condition == NONE) return false;
        (chosen ? m_constraints : earlier).push_back(Constraint{transition.condition, chosen, point, {}});
      }
    }
    // The cycle's own conditions first: they decide most cycles with the fewest values tried.
    m_constraints.insert(m_constraints.end(), earlier.begin(), earlier.end());
    return true;
  }

  /// Which command each signal the cycle writes holds at each of its states (after one
  /// round, every written signal has one); signals whose value the cycle cannot know
  /// (a `from` action, a self-transition's action) are marked undecided.
  void computeWrites() {
    const std::vector<Edge>& cycle = *m_cycle;
    m_known.assign(cycle.size(), {});
    m_unknownOnCycle.clear();
    std::map<signals::SignalIndex, double> current;
    const auto apply = [&](const std::vector<Action>& actions) {
      for (const Action& action : actions) {
        if (action.kind != ActionKind::SetSignal) continue;
        if (action.copy) {
          m_unknownOnCycle.insert(action.signal);
        } else {
          current[action.signal] = action.value;
        }
      }
    };
    for (const Edge& edge : cycle) {
      for (const Transition& transition : m_machine.states[edge.from].transitions) {
        if (transition.target != edge.from) continue;
        for (const Action& action : transition.actions) {
          if (action.kind == ActionKind::SetSignal) m_unknownOnCycle.insert(action.signal);
        }
      }
    }
    for (int round = 0; round < 2; ++round) {
      for (std::size_t e = 0; e < cycle.size(); ++e) {
        const Edge& edge = cycle[e];
        apply(m_machine.states[edge.from].exit);
        apply(m_machine.states[edge.from].transitions[edge.transition].actions);
        apply(m_machine.states[edge.to].entry);
        if (round == 1) m_known[(e + 1) % cycle.size()] = current;
      }
    }
  }

  void collectVariables() {
    m_variables.clear();
    std::set<std::uint32_t> seen;
    for (Constraint& constraint : m_constraints) {
      constraint.signals.clear();
      collectSignals(constraint.node, constraint.signals);
      std::sort(constraint.signals.begin(), constraint.signals.end());
      constraint.signals.erase(std::unique(constraint.signals.begin(), constraint.signals.end()),
                               constraint.signals.end());
      for (const std::uint32_t slot : constraint.signals) {
        if (seen.insert(slot).second) m_variables.push_back(slot);
      }
    }
  }

  void collectSignals(std::uint32_t node, std::vector<std::uint32_t>& out) const {
    const ConditionNode& current = m_machine.nodes[node];
    if (current.signal != NONE) {
      const signals::SignalIndex index = m_machine.signals[current.signal].index;
      bool written = m_unknownOnCycle.contains(index);
      for (const auto& known : m_known) written = written || known.contains(index);
      if (!written) out.push_back(current.signal);
    }
    if (current.kind == NodeKind::All || current.kind == NodeKind::Any || current.kind == NodeKind::Not) {
      for (std::uint32_t c = 0; c < current.count; ++c) collectSignals(m_machine.children[current.first + c], out);
    }
  }

  /// The values worth trying for one signal: at and between the constants it is compared
  /// with, without a value, and every quality and age its leaves tell apart.
  const std::vector<Value>& candidates(std::uint32_t slot) {
    if (m_candidates.size() != m_machine.signals.size()) m_candidates.resize(m_machine.signals.size());
    if (!m_candidates[slot]) m_candidates[slot] = makeCandidates(slot);
    return *m_candidates[slot];
  }

  std::vector<Value> makeCandidates(std::uint32_t slot) const {
    std::vector<double> constants;
    std::vector<std::int64_t> ages;
    bool quality = false;
    for (const ConditionNode& node : m_machine.nodes) {
      if (node.signal != slot) continue;
      if (node.kind == NodeKind::Compare) {
        if (node.op == CompareOp::In) {
          constants.insert(constants.end(), m_machine.constants.begin() + node.first,
                           m_machine.constants.begin() + node.first + node.count);
        } else {
          constants.push_back(node.value);
        }
      } else if (node.kind == NodeKind::Quality) {
        quality = true;
      } else if (node.kind == NodeKind::Age) {
        ages.push_back(node.durationNs);
      }
    }
    std::sort(constants.begin(), constants.end());
    constants.erase(std::unique(constants.begin(), constants.end()), constants.end());
    const SignalRef& ref = m_machine.signals[slot];
    const signals::SignalInfo& info = m_catalog[ref.index];
    const bool integral = !info.valueTexts.empty();
    std::vector<double> values;
    if (constants.empty()) {
      values.push_back(0);
    } else {
      values.push_back(integral ? std::ceil(constants.front()) - 1 : constants.front() - 1);
      for (std::size_t c = 0; c < constants.size(); ++c) {
        values.push_back(constants[c]);
        if (c + 1 < constants.size()) {
          // Between two constants; a signal with a value table takes whole numbers only.
          double between = (constants[c] + constants[c + 1]) / 2;
          if (integral) between = std::floor(constants[c]) + 1;
          if (between > constants[c] && between < constants[c + 1]) values.push_back(between);
        }
      }
      values.push_back(integral ? std::floor(constants.back()) + 1 : constants.back() + 1);
    }
    if (info.minimum < info.maximum) {  // only values the DBC range allows, its ends included
      values.push_back(info.minimum);
      values.push_back(info.maximum);
      std::erase_if(values, [&](double value) { return value < info.minimum || value > info.maximum; });
      std::sort(values.begin(), values.end());
      values.erase(std::unique(values.begin(), values.end()), values.end());
    }
    std::vector<signals::Quality> qualities{signals::Quality::Valid};
    if (quality) {
      qualities.push_back(signals::Quality::Stale);
      qualities.push_back(signals::Quality::OutOfRange);
    }
    std::vector<std::int64_t> agesTried{0};
    for (const std::int64_t age : ages) agesTried.push_back(age + 1);
    std::vector<Value> result;
    if (!ref.initial) result.push_back(Value{});  // never received: no value
    for (const double value : values) {
      for (const signals::Quality q : qualities) {
        for (const std::int64_t age : agesTried) result.push_back(Value{true, value, q, age});
      }
    }
    return result;
  }

  /// Depth-first over the values of the signals of the first undecided constraint: true
  /// once every constraint holds (the assignment is the witness).
  bool search() {
    if (++m_evaluations >= MAX_EVALUATIONS) return false;
    std::optional<std::uint32_t> branch;
    for (const Constraint& constraint : m_constraints) {
      const Truth value = eval(constraint.node, constraint.point);
      const Truth truth = constraint.mustHold ? value : negate(value);
      if (truth == Truth::False) return false;
      if (truth == Truth::True) continue;
      const auto open = std::find_if(constraint.signals.begin(), constraint.signals.end(),
                                     [&](std::uint32_t slot) { return !m_assigned[slot]; });
      // Undecided with every input chosen: it depends on what the cycle cannot know.
      if (open == constraint.signals.end()) return false;
      if (!branch) branch = *open;
    }
    if (!branch) return true;
    for (const Value& value : candidates(*branch)) {
      m_assigned[*branch] = value;
      if (search()) return true;
      if (exhausted()) break;
    }
    m_assigned[*branch].reset();
    return false;
  }

  /// What a leaf reads at the cycle's state `point`.
  std::optional<Value> read(std::uint32_t slot, std::size_t point) const {
    const signals::SignalIndex index = m_machine.signals[slot].index;
    if (m_unknownOnCycle.contains(index)) return std::nullopt;
    if (const auto it = m_known[point].find(index); it != m_known[point].end()) {
      return Value{true, it->second, signals::Quality::Valid, 0};  // commanded by the cycle just now
    }
    return m_assigned[slot];
  }

  Truth eval(std::uint32_t index, std::size_t point) {
    const ConditionNode& node = m_machine.nodes[index];
    if (node.forNs > 0) return Truth::False;  // its timer restarts at entry: false at that moment
    switch (node.kind) {
      case NodeKind::True: return Truth::True;
      case NodeKind::All: {
        Truth result = Truth::True;
        for (std::uint32_t c = 0; c < node.count; ++c) result = both(result, eval(m_machine.children[node.first + c], point));
        return result;
      }
      case NodeKind::Any: {
        Truth result = Truth::False;
        for (std::uint32_t c = 0; c < node.count; ++c) result = either(result, eval(m_machine.children[node.first + c], point));
        return result;
      }
      case NodeKind::Not: return negate(eval(m_machine.children[node.first], point));
      case NodeKind::Compare:
      case NodeKind::Quality:
      case NodeKind::Age: {
        const auto value = read(node.signal, point);
        if (!value) return Truth::Unknown;
        return leaf(node, *value) ? Truth::True : Truth::False;
      }
    }
    return Truth::Unknown;
  }

  /// engine.cpp's evalRaw for one value.
  bool leaf(const ConditionNode& node, const Value& value) const {
    switch (node.kind) {
      case NodeKind::Compare: {
        if (!value.present) return false;
        switch (node.op) {
          case CompareOp::Eq: return value.value == node.value;
          case CompareOp::Ne: return value.value != node.value;
          case CompareOp::Lt: return value.value < node.value;
          case CompareOp::Gt: return value.value > node.value;
          case CompareOp::Le: return value.value <= node.value;
          case CompareOp::Ge: return value.value >= node.value;
          case CompareOp::In:
            return std::find(m_machine.constants.begin() + node.first,
                             m_machine.constants.begin() + node.first + node.count,
                             value.value) != m_machine.constants.begin() + node.first + node.count;
        }
        return false;
      }
      case NodeKind::Quality: {
        const signals::Quality quality = value.present ? value.quality : signals::Quality::NeverReceived;
        return (node.qualityMask & (1U << static_cast<unsigned>(quality))) != 0;
      }
      case NodeKind::Age: return !value.present || value.ageNs > node.durationNs;
      default: return false;
    }
  }

  const Machine& m_machine;
  const signals::Catalog& m_catalog;
  const std::vector<Edge>* m_cycle{};
  std::vector<Constraint> m_constraints;
  std::vector<std::map<signals::SignalIndex, double>> m_known;  ///< per state of the cycle
  std::set<signals::SignalIndex> m_unknownOnCycle;
  std::vector<std::uint32_t> m_variables;  ///< signal slots the cycle does not write
  std::vector<std::optional<Value>> m_assigned;
  std::vector<std::optional<std::vector<Value>>> m_candidates;  ///< per signal slot, made once
  std::size_t m_evaluations{};
};

std::string describeValue(const signals::SignalInfo& info, const Value& value) {
  if (!value.present) return info.key + " never received";
  std::string text = info.key;
  text += " = ";
  text += number(value.value);
  if (const auto name = signals::valueText(info, value.value)) {
    text += " (";
    text += *name;
    text += ')';
  }
  if (value.quality != signals::Quality::Valid) {
    text += ' ';
    text += signals::qualityName(value.quality);
  }
  if (value.ageNs > 0) {
    text += ", not updated for over ";
    text += formatDuration(value.ageNs - 1);
  }
  return text;
}

}  // namespace

void checkSpinningCycles(JsonChecker& check, const Machine& machine, const signals::Catalog& catalog) {
  const std::size_t count = machine.states.size();
  CycleSearch search(machine, catalog);
  // Edges: transitions to another state that can be true at the moment of entry.
  std::vector<std::vector<Edge>> edges(count);
  for (std::uint32_t s = 0; s < count; ++s) {
    const State& state = machine.states[s];
    for (std::uint32_t t = 0; t < state.transitions.size(); ++t) {
      const Transition& transition = state.transitions[t];
      if (transition.target == NONE || transition.target == s || transition.broken || transition.afterNs > 0 ||
          transition.condition == NONE) {
        continue;
      }
      if (search.staticTruth(transition.condition) == Truth::False) continue;
      edges[s].push_back(Edge{s, t, transition.target});
    }
  }
  // Elementary cycles, each once: from its lowest state, through higher states only.
  std::size_t cycles = 0;
  std::size_t proved = 0;
  std::vector<Edge> path;
  std::vector<bool> onPath(count, false);
  const auto report = [&](const std::vector<Edge>& cycle, const std::vector<std::pair<std::uint32_t, Value>>& witness) {
    ++proved;
    if (proved > MAX_REPORTED) return;
    std::string states;
    std::string paths;
    for (const Edge& edge : cycle) {
      states += "'" + machine.states[edge.from].name + "' -> ";
      if (!paths.empty()) paths += ", ";
      paths += machine.states[edge.from].transitions[edge.transition].path;
    }
    states += "'" + machine.states[cycle.front().from].name + "'";
    std::string when;
    for (std::size_t w = 0; w < witness.size() && w < MAX_WITNESS_SIGNALS; ++w) {
      if (!when.empty()) when += ", ";
      when += describeValue(catalog[machine.signals[witness[w].first].index], witness[w].second);
    }
    if (witness.size() > MAX_WITNESS_SIGNALS) when += ", ...";
    check.error(machine.states[cycle.front().from].transitions[cycle.front().transition].path,
                "transitions can fire in a cycle without any input change: " + states + " (" + paths + ")" +
                    (when.empty() ? std::string(": their conditions are always true") : ", e.g. with " + when) +
                    "; vcu-fsm would never settle. Make one of them false once the cycle ran (a condition on a "
                    "signal the cycle sets), or add an \"after\" or a \"for\"");
  };
  // Only states that can still lead back to `start` through states above it are followed.
  std::vector<std::vector<std::uint32_t>> incoming(count);
  for (std::uint32_t s = 0; s < count; ++s) {
    for (const Edge& edge : edges[s]) incoming[edge.to].push_back(s);
  }
  std::vector<bool> leadsBack(count, false);
  std::size_t steps = 0;
  bool truncated = false;  ///< a work limit: the enumeration stopped
  bool tooLong = false;    ///< a cycle longer than MAX_CYCLE_LENGTH was not followed
  const auto visit = [&](auto&& self, std::uint32_t start, std::uint32_t state) -> void {
    for (const Edge& edge : edges[state]) {
      if (cycles >= MAX_CYCLES || search.exhausted() || ++steps > MAX_STEPS) {
        truncated = true;
        return;
      }
      if (edge.to == start) {
        path.push_back(edge);
        ++cycles;
        if (const auto witness = search.prove(path)) report(path, *witness);
        path.pop_back();
      } else if (edge.to > start && !onPath[edge.to] && leadsBack[edge.to]) {
        if (path.size() + 1 >= MAX_CYCLE_LENGTH) {
          tooLong = true;  // not followed; the other cycles still are
          continue;
        }
        onPath[edge.to] = true;
        path.push_back(edge);
        self(self, start, edge.to);
        path.pop_back();
        onPath[edge.to] = false;
      }
    }
  };
  for (std::uint32_t start = 0; start < count && !truncated; ++start) {
    std::fill(leadsBack.begin(), leadsBack.end(), false);
    std::vector<std::uint32_t> pending{start};
    while (!pending.empty()) {
      const std::uint32_t s = pending.back();
      pending.pop_back();
      for (const std::uint32_t from : incoming[s]) {
        if (++steps > MAX_STEPS) {
          truncated = true;
          break;
        }
        if (from > start && !leadsBack[from]) {
          leadsBack[from] = true;
          pending.push_back(from);
        }
      }
    }
    if (truncated) break;
    onPath[start] = true;
    visit(visit, start, start);
    onPath[start] = false;
  }
  if (proved > MAX_REPORTED) {
    check.error("/", std::to_string(proved - MAX_REPORTED) + " more cycles of transitions can fire without any input change");
  }
  truncated = truncated || search.exhausted();
  if (truncated) {
    check.warning("/", "the cycle check stopped at its work limit after " + std::to_string(cycles) +
                           " cycles; cycles not examined are bounded at run time by the loop guard");
  } else if (tooLong) {
    check.warning("/", "cycles of more than " + std::to_string(MAX_CYCLE_LENGTH) +
                           " states were not examined; at run time the loop guard bounds them");
  }
}

}  // namespace openvcu::fsm
