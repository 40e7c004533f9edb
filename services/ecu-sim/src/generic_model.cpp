#include "generic_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace openvcu::ecusim {
namespace {

constexpr double NAN_VALUE = std::numeric_limits<double>::quiet_NaN();

bool compare(config::SimCompareOp op, double value, double constant) noexcept {
  switch (op) {
    case config::SimCompareOp::Eq: return value == constant;
    case config::SimCompareOp::Ne: return value != constant;
    case config::SimCompareOp::Lt: return value < constant;
    case config::SimCompareOp::Gt: return value > constant;
    case config::SimCompareOp::Le: return value <= constant;
    case config::SimCompareOp::Ge: return value >= constant;
    case config::SimCompareOp::In: return false;  // compared against the constants list by the caller
  }
  return false;
}

}  // namespace

Result<GenericModel> GenericModel::create(VirtualBus& bus, const config::SimConfig& config) {
  GenericModel model(bus, config);
  const config::SimRules& rules = config.rules;
  for (const config::SimSignal& signal : rules.signals) {
    const bridge::SignalRef ref{signal.message, signal.signal};
    const bool carried = signal.kind == config::SimSignal::Kind::Node  ? bus.isOutput(ref)
                         : signal.kind == config::SimSignal::Kind::Vcu ? bus.isInput(ref)
                                                                       : true;
    if (!carried) {
      return Error{config.file + ": " + signal.path + ": the simulator does not carry " + signal.key +
                   " (its message is not on a configured bus it can send or receive)"};
    }
    model.m_refs.push_back(ref);
  }
  const std::size_t slots = rules.signals.size();
  model.m_sampled.assign(slots, NAN_VALUE);
  model.m_written.assign(slots, 0.0);
  model.m_isWritten.assign(slots, 0);
  model.m_byRule.assign(slots, 0);
  model.m_timers.assign(rules.timerCount, NOT_HOLDING);
  model.m_ruleSince.assign(rules.rules.size(), NOT_HOLDING);
  model.m_active.assign(rules.faults.size(), 0);
  model.m_lastNormal.assign(slots, 0.0);
  model.m_faultTouched.assign(slots, 0);
  for (std::uint32_t i = 0; i < slots; ++i) {
    if (rules.signals[i].kind == config::SimSignal::Kind::Node) model.m_lastNormal[i] = model.startValue(i);
  }
  for (const config::SimFault& fault : rules.faults) {
    for (const config::SimAssignment& assignment : fault.set) model.m_faultTouched[assignment.signal] = 1;
  }
  for (const config::SimFollow& follow : rules.follow) model.m_followState.push_back(model.startValue(follow.signal));
  for (const config::SimIntegrate& integrate : rules.integrate) {
    const double start = model.startValue(integrate.signal);
    model.m_integrateState.push_back(std::clamp(start, integrate.minimum, integrate.maximum));
  }
  return model;
}

double GenericModel::startValue(std::uint32_t slot) const noexcept {
  const double value = m_bus->current(m_refs[slot]);
  return std::isnan(value) ? 0.0 : value;
}

void GenericModel::receive(const can::Frame& frame, std::int64_t atNs) noexcept {
  switch (m_pairs.receive(frame, atNs, false)) {
    case SafetyPairs::Outcome::Header:
    case SafetyPairs::Outcome::NotUsed:
      return;  // an SHM, or an SDM the receiver did not accept: its values are not taken
    case SafetyPairs::Outcome::Used:
    case SafetyPairs::Outcome::NotPaired:
      m_bus->receive(frame, atNs);
      return;
  }
}

std::optional<std::size_t> GenericModel::faultIndex(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < m_rules->faults.size(); ++i) {
    if (m_rules->faults[i].name == name) return i;
  }
  return std::nullopt;
}

double GenericModel::sampled(std::string_view key) const noexcept {
  for (std::size_t i = 0; i < m_rules->signals.size(); ++i) {
    if (m_rules->signals[i].key == key) return m_sampled[i];
  }
  return NAN_VALUE;
}

bool GenericModel::holds(std::uint32_t node, std::int64_t nowNs) noexcept {
  return node == config::SIM_NONE || evaluate(node, nowNs);
}

bool GenericModel::evaluate(std::uint32_t index, std::int64_t nowNs) noexcept {
  const config::SimConditionNode& node = m_rules->nodes[index];
  bool raw = false;
  switch (node.kind) {
    case config::SimNodeKind::True:
      raw = true;
      break;
    case config::SimNodeKind::All:
      // every child is evaluated (no short cut), so that each `for` timer sees every step
      raw = true;
      for (std::uint32_t c = 0; c < node.count; ++c) raw = evaluate(m_rules->children[node.first + c], nowNs) && raw;
      break;
    case config::SimNodeKind::Any:
      for (std::uint32_t c = 0; c < node.count; ++c) raw = evaluate(m_rules->children[node.first + c], nowNs) || raw;
      break;
    case config::SimNodeKind::Not:
      raw = !evaluate(m_rules->children[node.first], nowNs);
      break;
    case config::SimNodeKind::Compare: {
      const double value = m_sampled[node.signal];
      if (std::isnan(value)) break;  // no value yet: every comparison is false, ne included (as fsm.json)
      if (node.op != config::SimCompareOp::In) {
        raw = compare(node.op, value, node.value);
        break;
      }
      for (std::uint32_t v = 0; v < node.count && !raw; ++v) raw = value == m_rules->constants[node.first + v];
      break;
    }
  }
  if (node.forNs <= 0) return raw;
  std::int64_t& since = m_timers[node.timer];
  if (!raw) {
    since = NOT_HOLDING;
    return false;
  }
  if (since == NOT_HOLDING) since = nowNs;
  return nowNs - since >= node.forNs;
}

void GenericModel::write(std::uint32_t slot, double value) noexcept {
  m_written[slot] = value;
  m_isWritten[slot] = 1;
}

void GenericModel::writeAll(const std::vector<config::SimAssignment>& values) noexcept {
  for (const config::SimAssignment& assignment : values) write(assignment.signal, assignment.value);
}

void GenericModel::step(std::int64_t nowNs) noexcept {
  const double dt = m_lastStepNs == NOT_HOLDING ? 0.0 : static_cast<double>(nowNs - m_lastStepNs) / 1e9;
  m_lastStepNs = nowNs;
  // 1. sample
  const auto& verdict = m_pairs.verdict();
  const double safetyOk = !verdict ? NAN_VALUE : *verdict == j1939::SafetyResult::Ok ? 1.0 : 0.0;
  for (std::size_t i = 0; i < m_refs.size(); ++i) {
    switch (m_rules->signals[i].kind) {
      case config::SimSignal::Kind::Node: m_sampled[i] = m_bus->current(m_refs[i]); break;
      case config::SimSignal::Kind::Vcu: m_sampled[i] = m_bus->get(m_refs[i]); break;
      case config::SimSignal::Kind::SafetyOk: m_sampled[i] = safetyOk; break;
    }
  }
  std::fill(m_isWritten.begin(), m_isWritten.end(), std::uint8_t{0});
  // 2. rules in file order
  for (std::size_t r = 0; r < m_rules->rules.size(); ++r) {
    const config::SimRule& rule = m_rules->rules[r];
    std::int64_t& since = m_ruleSince[r];
    if (holds(rule.when, nowNs)) {
      if (since == NOT_HOLDING) since = nowNs;
    } else {
      since = NOT_HOLDING;
    }
    const bool active = since != NOT_HOLDING && nowNs - since >= rule.afterNs;
    writeAll(active ? rule.set : rule.otherwise);
  }
  std::copy(m_isWritten.begin(), m_isWritten.end(), m_byRule.begin());
  // 3. follow
  for (std::size_t f = 0; f < m_rules->follow.size(); ++f) {
    const config::SimFollow& follow = m_rules->follow[f];
    double& state = m_followState[f];
    if (m_byRule[follow.signal]) state = m_written[follow.signal];
    double target = 0;
    if (holds(follow.when, nowNs)) {
      target = follow.target == config::SIM_NONE ? follow.targetValue : m_sampled[follow.target];
      if (std::isnan(target)) target = 0;  // a target with no value yet: toward 0
    }
    state += (target - state) * std::min(1.0, dt * 1e9 / static_cast<double>(follow.timeConstantNs));
    write(follow.signal, state);
  }
  // 4. integrate
  for (std::size_t i = 0; i < m_rules->integrate.size(); ++i) {
    const config::SimIntegrate& integrate = m_rules->integrate[i];
    double& state = m_integrateState[i];
    if (m_byRule[integrate.signal]) state = m_written[integrate.signal];
    double rate = integrate.factor;
    if (integrate.rateSignal != config::SIM_NONE) {
      const double source = m_sampled[integrate.rateSignal];
      rate = std::isnan(source) ? 0.0 : rate * source;
    }
    state = std::clamp(state + rate * dt, integrate.minimum, integrate.maximum);
    write(integrate.signal, state);
  }
  // 5. faults override everything; a signal a fault sets returns, once no fault sets it,
  // to what the rules, follow and integrate last gave it (else its start value)
  for (std::size_t i = 0; i < m_refs.size(); ++i) {
    if (m_isWritten[i]) {
      m_lastNormal[i] = m_written[i];
    } else if (m_faultTouched[i]) {
      write(static_cast<std::uint32_t>(i), m_lastNormal[i]);
    }
  }
  for (std::size_t f = 0; f < m_active.size(); ++f) {
    if (m_active[f]) writeAll(m_rules->faults[f].set);
  }
  for (std::size_t i = 0; i < m_refs.size(); ++i) {
    if (m_isWritten[i]) m_bus->set(m_refs[i], m_written[i]);
  }
}

}  // namespace openvcu::ecusim
