#include "openvcu/core/text.hpp"
#include "openvcu/fsm/engine.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace openvcu::fsm {
namespace {

constexpr double NS_PER_S = 1e9;

using text::number;

bool compare(CompareOp op, double value, double constant) noexcept {
  switch (op) {
    case CompareOp::Eq: return value == constant;
    case CompareOp::Ne: return value != constant;
    case CompareOp::Lt: return value < constant;
    case CompareOp::Gt: return value > constant;
    case CompareOp::Le: return value <= constant;
    case CompareOp::Ge: return value >= constant;
    case CompareOp::In: return false;  // handled by the caller
  }
  return false;
}

}  // namespace

// ---- MemoryAccess -----------------------------------------------------------------------

std::optional<signals::SlotSnapshot> MemoryAccess::read(signals::SignalIndex index) noexcept {
  if (index >= m_slots.size()) return std::nullopt;
  return m_slots[index];
}

void MemoryAccess::writeCommand(signals::SignalIndex index, double value, std::int64_t nowNs) noexcept {
  setCommand(index, value, nowNs, FSM_WRITER);
}

void MemoryAccess::writeStatus(signals::SignalIndex index, double value, std::int64_t nowNs) noexcept {
  setBus(index, value, nowNs);
}

void MemoryAccess::setBus(signals::SignalIndex index, double value, std::int64_t nowNs,
                          signals::Quality quality) noexcept {
  if (index >= m_slots.size()) return;
  signals::BusValue& bus = m_slots[index].bus;
  bus = signals::BusValue{value, nowNs, FSM_WRITER, quality, bus.updates + 1};
}

void MemoryAccess::setQuality(signals::SignalIndex index, signals::Quality quality) noexcept {
  if (index < m_slots.size() && m_slots[index].bus.updates > 0) m_slots[index].bus.quality = quality;
}

void MemoryAccess::setCommand(signals::SignalIndex index, double value, std::int64_t nowNs,
                              signals::WriterId writer) noexcept {
  if (index >= m_slots.size()) return;
  signals::CommandValue& command = m_slots[index].command;
  command = signals::CommandValue{value, nowNs, writer, command.updates + 1};
}

// ---- StatusSlots ------------------------------------------------------------------------

Result<StatusSlots> StatusSlots::find(const signals::Catalog& catalog) {
  StatusSlots slots;
  for (auto [key, slot] : {std::pair{"internal.fsm.state", &slots.state},
                           std::pair{"internal.fsm.stateSince", &slots.stateSince},
                           std::pair{"internal.fsm.stateEntered", &slots.stateEntered},
                           std::pair{"internal.fsm.machine", &slots.machine}}) {
    auto found = catalog.find(key);
    if (!found) return found.error();
    *slot = *found;
  }
  for (std::uint32_t timer = 0; timer < PERSISTED_TIMERS; ++timer) {
    auto found = catalog.find("internal.fsm.timer." + std::to_string(timer));
    if (!found) return found.error();
    slots.timers.push_back(*found);
  }
  return slots;
}

// ---- Engine -----------------------------------------------------------------------------

Engine::Engine(Machine machine, const signals::Catalog& catalog, SignalAccess& access, StatusSlots slots)
    : m_machine(std::move(machine)), m_catalog(catalog), m_access(access), m_slots(std::move(slots)) {
  resize();
}

void Engine::resize() {
  m_samples.assign(m_machine.signals.size(), Sample{});
  m_changed.assign(m_machine.signals.size(), 1);
  m_timers.assign(m_machine.timerCount, 0);
  std::size_t most = 0;
  for (const State& state : m_machine.states) most = std::max(most, state.transitions.size());
  m_held.assign(most, 0);
  m_conditions.assign(most, 0);
  m_outputs.transitions.reserve(MAX_FIRINGS + 2);

  // The signals whose commands restoreTable() may write back: every action target and
  // every input read on the command plane. What was known of them survives a reload.
  std::vector<OwnedCommand> owned;
  std::vector<std::uint32_t> ownedOf(m_catalog.size(), NONE);
  const auto own = [&](signals::SignalIndex index) {
    if (index >= ownedOf.size() || ownedOf[index] != NONE) return;
    ownedOf[index] = static_cast<std::uint32_t>(owned.size());
    OwnedCommand entry{index, 0.0, false};
    if (index < m_ownedOf.size() && m_ownedOf[index] != NONE) entry = m_owned[m_ownedOf[index]];
    owned.push_back(entry);
  };
  const auto ownTargets = [&](const std::vector<Action>& actions) {
    for (const Action& action : actions) {
      if (action.kind == ActionKind::SetSignal) own(action.signal);
    }
  };
  for (const State& state : m_machine.states) {
    ownTargets(state.entry);
    ownTargets(state.exit);
    for (const Transition& transition : state.transitions) ownTargets(transition.actions);
  }
  for (const SignalRef& ref : m_machine.signals) {
    if (ref.plane == ReadPlane::Command) own(ref.index);
  }
  m_owned = std::move(owned);
  m_ownedOf = std::move(ownedOf);
}

void Engine::clearOutputs() noexcept {
  m_outputs.transitions.clear();
  m_outputs.faults.clear();
  m_outputs.events.clear();
}

void Engine::start(std::int64_t monoNs, std::int64_t realNs, StartMode mode) {
  const auto hash = m_access.read(m_slots.machine);
  const auto state = m_access.read(m_slots.state);
  const auto entered = m_access.read(m_slots.stateEntered);
  const bool sameMachine = hash && hash->bus.updates > 0 &&
                           static_cast<std::uint64_t>(hash->bus.value) == m_machine.hash;
  const bool validState = state && state->bus.updates > 0 && state->bus.value >= 0 &&
                          state->bus.value < static_cast<double>(m_machine.states.size());
  if (mode == StartMode::Resume && sameMachine && validState && entered && entered->bus.updates > 0) {
    m_state = static_cast<std::uint32_t>(state->bus.value);
    m_enteredNs = static_cast<std::int64_t>(std::llround(entered->bus.value * NS_PER_S));
    for (std::uint32_t timer = 0; timer < m_timers.size() && timer < m_slots.timers.size(); ++timer) {
      const auto since = m_access.read(m_slots.timers[timer]);
      if (since && since->bus.value > 0) m_timers[timer] = static_cast<std::int64_t>(std::llround(since->bus.value * NS_PER_S));
    }
    m_outputs.transitions.push_back(ipc::FsmTransition{
        0, "", stateName(),
        "resumed after a restart (state entered " + number(static_cast<double>(monoNs - m_enteredNs) / NS_PER_S) +
            " s ago; entry actions not re-run)"});
  } else {
    for (std::uint32_t timer = 0; timer < m_slots.timers.size(); ++timer) {
      m_access.writeStatus(m_slots.timers[timer], 0, monoNs);
    }
    m_access.writeStatus(m_slots.machine, static_cast<double>(m_machine.hash), monoNs);
    enter(m_machine.initial, monoNs, realNs);
    std::string why = "initial state";
    if (mode == StartMode::Resume && validState && !sameMachine) why += " (the table's state belongs to another FSM file)";
    m_outputs.transitions.push_back(ipc::FsmTransition{0, "", stateName(), std::move(why)});
  }
  m_access.writeStatus(m_slots.machine, static_cast<double>(m_machine.hash), monoNs);
  step(monoNs, realNs, true);
}

Status Engine::replace(Machine machine, std::int64_t monoNs, std::int64_t realNs) {
  const auto state = machine.findState(stateName());
  if (!state) {
    return Error{"the current state '" + stateName() + "' does not exist in " + machine.file +
                 ": the running machine is kept"};
  }
  const std::string from = stateName();
  m_machine = std::move(machine);
  m_state = *state;
  resize();
  for (std::uint32_t timer = 0; timer < m_slots.timers.size(); ++timer) m_access.writeStatus(m_slots.timers[timer], 0, monoNs);
  m_access.writeStatus(m_slots.machine, static_cast<double>(m_machine.hash), monoNs);
  writeState(monoNs, realNs);
  m_outputs.transitions.push_back(ipc::FsmTransition{0, from, stateName(), "reloaded " + m_machine.file});
  step(monoNs, realNs, true);
  return {};
}

std::size_t Engine::restoreTable(std::int64_t monoNs, std::int64_t realNs) noexcept {
  m_graceUntilNs = monoNs + DAMAGE_GRACE_NS;
  for (Sample& sample : m_samples) sample.written = 0;  // the table's counters start again from 0
  m_access.writeStatus(m_slots.machine, static_cast<double>(m_machine.hash), monoNs);
  for (std::uint32_t timer = 0; timer < m_slots.timers.size(); ++timer) {
    const std::int64_t since = timer < m_timers.size() ? m_timers[timer] : 0;
    m_access.writeStatus(m_slots.timers[timer], static_cast<double>(since) / NS_PER_S, monoNs);
  }
  std::size_t written = 0;
  for (const OwnedCommand& owned : m_owned) {
    if (!owned.ours) continue;
    m_access.writeCommand(owned.index, owned.value, monoNs);
    ++written;
  }
  writeState(monoNs, realNs);  // last, as after a transition
  return written;
}

void Engine::remember(signals::SignalIndex index, double value, bool ours) noexcept {
  if (index >= m_ownedOf.size() || m_ownedOf[index] == NONE) return;
  OwnedCommand& owned = m_owned[m_ownedOf[index]];
  owned.value = value;
  owned.ours = ours;
}

void Engine::trackCommands() noexcept {
  for (OwnedCommand& owned : m_owned) {
    const auto snapshot = m_access.read(owned.index);
    // Never commanded (or the table lost it): keep what was known, restoreTable() needs it.
    if (!snapshot || snapshot->command.updates == 0) continue;
    owned.value = snapshot->command.value;
    owned.ours = snapshot->command.writer == FSM_WRITER;
  }
}

bool Engine::refresh(std::int64_t monoNs) noexcept {
  bool any = false;
  for (std::size_t s = 0; s < m_machine.signals.size(); ++s) {
    const SignalRef& ref = m_machine.signals[s];
    const auto snapshot = m_access.read(ref.index);
    if (!snapshot) continue;  // a write in progress: keep the previous value, read again next step
    Sample sample;
    const auto command = ref.plane == ReadPlane::Command ? signals::effectiveCommand(*snapshot) : std::nullopt;
    if (command) {
      sample = Sample{command->value, command->timestampNs, signals::Quality::Valid, true, 0};
    } else if (snapshot->bus.updates > 0) {
      sample = Sample{snapshot->bus.value, snapshot->bus.timestampNs, snapshot->bus.quality, true, 0};
    } else if (ref.initial) {
      sample = Sample{*ref.initial, 0, signals::Quality::Valid, true, 0};
    }
    sample.written = snapshot->bus.updates;
    if (ref.plane == ReadPlane::Command) sample.written += snapshot->command.updates + snapshot->override.updates;
    Sample& current = m_samples[s];
    // Update counters go back only when the table lost its values (issue 18); whoever
    // notices first starts the grace window, restoreTable() or this.
    if (sample.written < current.written) m_graceUntilNs = std::max(m_graceUntilNs, monoNs + DAMAGE_GRACE_NS);
    if (sample.written == 0 && current.present && monoNs < m_graceUntilNs) {
      current.written = 0;  // wiped and not written again yet: keep the previous sample
      continue;
    }
    current.written = sample.written;
    const bool changed = sample.present != current.present || sample.quality != current.quality ||
                         (sample.present && sample.value != current.value) ||
                         sample.timestampNs != current.timestampNs;
    // A new timestamp alone matters only to `ageGt`; it is stored but is not a change.
    const bool relevant = sample.present != current.present || sample.quality != current.quality ||
                          (sample.present && sample.value != current.value);
    if (changed) current = sample;
    if (relevant) {
      m_changed[s] = 1;
      any = true;
    }
  }
  return any;
}

bool Engine::step(std::int64_t monoNs, std::int64_t realNs, bool force) {
  ++m_counters.steps;
  if (m_graceUntilNs > 0 && monoNs >= m_graceUntilNs) m_graceUntilNs = 0;  // over: inputs read as they are
  trackCommands();
  refresh(monoNs);
  bool relevant = force || monoNs >= m_deadline;
  if (!relevant) {
    for (const std::uint32_t signal : m_machine.states[m_state].signals) {
      if (m_changed[signal] != 0) {
        relevant = true;
        break;
      }
    }
  }
  if (!relevant) return false;
  evaluate(monoNs, realNs);
  std::fill(m_changed.begin(), m_changed.end(), 0);
  return true;
}

void Engine::evaluate(std::int64_t monoNs, std::int64_t realNs) {
  for (std::uint32_t firing = 0;; ++firing) {
    ++m_counters.evaluations;
    m_pendingDeadline = NO_DEADLINE;
    const State& state = m_machine.states[m_state];
    const std::size_t count = state.transitions.size();
    // Every condition is evaluated (no short cut), so that every `for` timer sees the change.
    for (std::size_t t = 0; t < count; ++t) {
      const Transition& transition = state.transitions[t];
      bool holds = transition.condition == NONE || evalNode(transition.condition, monoNs);
      if (transition.afterNs > 0) {
        const std::int64_t due = m_enteredNs + transition.afterNs;
        if (monoNs < due) {
          m_pendingDeadline = std::min(m_pendingDeadline, due);
          holds = false;
        }
      }
      m_conditions[t] = holds ? 1 : 0;
    }
    std::size_t chosen = count;
    for (std::size_t t = 0; t < count; ++t) {
      if (m_conditions[t] == 0) continue;
      // A self-transition fires when its condition becomes true, not while it stays true.
      if (state.transitions[t].target == m_state && m_held[t] != 0) continue;
      chosen = t;
      break;
    }
    std::copy(m_conditions.begin(), m_conditions.begin() + static_cast<std::ptrdiff_t>(count), m_held.begin());
    // Only the machine's own timers: its own writes were read back by refresh() and are no
    // change, so after a loop guard the next evaluation waits for an input or a deadline.
    m_deadline = m_pendingDeadline;
    if (chosen == count) {
      if (m_looping) {
        m_looping = false;
        m_outputs.faults.push_back(ipc::FaultEvent{0, "fsm_loop", "vcu-fsm", ipc::FaultSeverity::Error, false,
                                                   "settled in '" + stateName() + "'"});
      }
      return;
    }
    if (firing == MAX_FIRINGS) {
      ++m_counters.loopGuards;
      if (!m_looping) {
        m_looping = true;
        m_outputs.faults.push_back(ipc::FaultEvent{
            0, "fsm_loop", "vcu-fsm", ipc::FaultSeverity::Error, true,
            std::to_string(MAX_FIRINGS) + " transitions in one step, stopped in '" + stateName() +
                "': the machine does not settle; it waits for an input change or a deadline"});
      }
      return;
    }
    const Transition& transition = state.transitions[chosen];
    const std::uint32_t from = m_state;
    if (transition.target == m_state) {
      ++m_counters.selfTransitions;
      runActions(transition.actions, monoNs);
    } else {
      ++m_counters.transitions;
      runActions(state.exit, monoNs);
      runActions(transition.actions, monoNs);
      enter(transition.target, monoNs, realNs);
    }
    m_outputs.transitions.push_back(
        ipc::FsmTransition{0, m_machine.states[from].name, stateName(), cause(transition)});
    refresh(monoNs);  // our own writes may feed the next round
  }
}

void Engine::enter(std::uint32_t state, std::int64_t monoNs, std::int64_t realNs) {
  m_state = state;
  m_enteredNs = monoNs;
  std::fill(m_held.begin(), m_held.end(), 0);
  for (std::uint32_t timer = 0; timer < m_timers.size(); ++timer) setTimer(timer, 0, monoNs);
  runActions(m_machine.states[state].entry, monoNs);
  writeState(monoNs, realNs);  // last: a vcu-fsm killed before this resumes the old state and fires again
}

void Engine::writeState(std::int64_t monoNs, std::int64_t realNs) noexcept {
  m_access.writeStatus(m_slots.stateEntered, static_cast<double>(m_enteredNs) / NS_PER_S, monoNs);
  m_access.writeStatus(m_slots.stateSince,
                       static_cast<double>(realNs - (monoNs - m_enteredNs)) / NS_PER_S, monoNs);
  m_access.writeStatus(m_slots.state, static_cast<double>(m_state), monoNs);
}

void Engine::setTimer(std::uint32_t timer, std::int64_t sinceNs, std::int64_t monoNs) noexcept {
  if (m_timers[timer] == sinceNs) return;
  m_timers[timer] = sinceNs;
  if (timer < m_slots.timers.size()) {
    m_access.writeStatus(m_slots.timers[timer], static_cast<double>(sinceNs) / NS_PER_S, monoNs);
  }
}

bool Engine::copiedValue(const Action& action, double& value) noexcept {
  const auto source = m_access.read(action.source);
  if (!source) return false;
  if (const auto command = signals::effectiveCommand(*source)) {
    value = command->value;
  } else if (source->bus.updates > 0) {
    value = source->bus.value;
  } else {
    return false;
  }
  const signals::SignalInfo& target = m_catalog[action.signal];
  if (target.minimum < target.maximum) value = std::clamp(value, target.minimum, target.maximum);
  return true;
}

bool Engine::runActions(const std::vector<Action>& actions, std::int64_t monoNs) {
  bool wrote = false;
  for (const Action& action : actions) {
    switch (action.kind) {
      case ActionKind::Nothing: break;
      case ActionKind::SetSignal: {
        double value = action.value;
        if (action.copy && !copiedValue(action, value)) break;  // the source has no value yet
        const auto snapshot = m_access.read(action.signal);
        remember(action.signal, value, true);
        if (snapshot && snapshot->command.updates > 0 && snapshot->command.value == value &&
            snapshot->command.writer == FSM_WRITER) {
          break;  // already commanded: no write, no change to wake anyone
        }
        m_access.writeCommand(action.signal, value, monoNs);
        ++m_counters.commandsWritten;
        wrote = true;
        break;
      }
      case ActionKind::RaiseFault:
      case ActionKind::ClearFault:
        m_outputs.faults.push_back(ipc::FaultEvent{0, action.name, "vcu-fsm", action.severity,
                                                   action.kind == ActionKind::RaiseFault, action.text});
        break;
      case ActionKind::Event:
        m_outputs.events.push_back(ipc::LogRecord{0, "vcu-fsm", ipc::LogLevel::Info, action.text});
        break;
    }
  }
  return wrote;
}

bool Engine::evalNode(std::uint32_t node, std::int64_t monoNs) noexcept {
  const ConditionNode& current = m_machine.nodes[node];
  const bool raw = evalRaw(current, monoNs);
  if (current.forNs <= 0) return raw;
  if (!raw) {
    setTimer(current.timer, 0, monoNs);
    return false;
  }
  if (m_timers[current.timer] == 0) setTimer(current.timer, monoNs, monoNs);
  const std::int64_t due = m_timers[current.timer] + current.forNs;
  if (monoNs >= due) return true;
  m_pendingDeadline = std::min(m_pendingDeadline, due);
  return false;
}

bool Engine::evalRaw(const ConditionNode& node, std::int64_t monoNs) noexcept {
  switch (node.kind) {
    case NodeKind::True: return true;
    case NodeKind::All: {
      bool result = true;
      for (std::uint32_t c = 0; c < node.count; ++c) result = evalNode(m_machine.children[node.first + c], monoNs) && result;
      return result;
    }
    case NodeKind::Any: {
      bool result = false;
      for (std::uint32_t c = 0; c < node.count; ++c) result = evalNode(m_machine.children[node.first + c], monoNs) || result;
      return result;
    }
    case NodeKind::Not: return !evalNode(m_machine.children[node.first], monoNs);
    case NodeKind::Compare: {
      const Sample& sample = m_samples[node.signal];
      if (!sample.present) return false;  // a value never seen compares false, whatever the operator
      if (node.op != CompareOp::In) return compare(node.op, sample.value, node.value);
      for (std::uint32_t v = 0; v < node.count; ++v) {
        if (sample.value == m_machine.constants[node.first + v]) return true;
      }
      return false;
    }
    case NodeKind::Quality: {
      const Sample& sample = m_samples[node.signal];
      return (node.qualityMask & (1U << static_cast<unsigned>(sample.quality))) != 0;
    }
    case NodeKind::Age: {
      const Sample& sample = m_samples[node.signal];
      if (!sample.present || sample.timestampNs == 0) return true;
      const std::int64_t due = sample.timestampNs + node.durationNs;
      if (monoNs > due) return true;
      m_pendingDeadline = std::min(m_pendingDeadline, due + 1);
      return false;
    }
  }
  return false;
}

std::string Engine::cause(const Transition& transition) const {
  std::string text = describeCondition(m_machine, m_catalog, transition.condition);
  if (transition.condition == NONE) text.clear();
  if (transition.afterNs > 0) {
    if (!text.empty()) text += " and ";
    text += "after " + formatDuration(transition.afterNs);
  }
  std::string values;
  describeValues(transition.condition, values);
  if (!values.empty()) text += " [" + values + "]";
  return text + " (" + transition.path + ")";
}

void Engine::describeValues(std::uint32_t node, std::string& out) const {
  if (node == NONE) return;
  const ConditionNode& current = m_machine.nodes[node];
  if (current.signal != NONE) {
    const std::string& key = m_catalog[m_machine.signals[current.signal].index].key;
    if (out.find(key + " =") != std::string::npos) return;
    if (!out.empty()) out += ", ";
    const Sample& sample = m_samples[current.signal];
    out += key;
    out += sample.present ? " = " + number(sample.value) : " never received";
    if (sample.present && sample.quality != signals::Quality::Valid) {
      out += " (";
      out += signals::qualityName(sample.quality);
      out += ')';
    }
    return;
  }
  for (std::uint32_t c = 0; c < current.count; ++c) {
    if (current.kind == NodeKind::Compare) break;
    describeValues(m_machine.children[current.first + c], out);
  }
}

}  // namespace openvcu::fsm
