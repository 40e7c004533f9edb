#include "common/display_logic.hpp"

#include <time.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "openvcu/config/dashboard.hpp"
#include "openvcu/config/json.hpp"

namespace openvcu::hmi {
namespace {

bool contains(std::string_view text, std::string_view part) {
  return text.find(part) != std::string_view::npos;
}

/// Collects every signal key a condition reads: {"key": K, ...} and {"internal.x": value}.
void collectKeys(const config::Json& node, std::set<std::string, std::less<>>& keys) {
  if (node.is_array()) {
    for (const auto& element : node) collectKeys(element, keys);
    return;
  }
  if (!node.is_object()) return;
  for (auto it = node.begin(); it != node.end(); ++it) {
    if (it.key() == "key" && it->is_string()) keys.insert(it->get<std::string>());
    if (it.key().find('.') != std::string::npos) keys.insert(it.key());
    collectKeys(*it, keys);
  }
}

}  // namespace

std::string_view statusName(ValueStatus status) noexcept {
  switch (status) {
    case ValueStatus::Ready:
      return "Ready";
    case ValueStatus::Stale:
      return "Stale";
    case ValueStatus::NotConnected:
      return "NotConnected";
    case ValueStatus::Error:
      return "Error";
  }
  return "Error";
}

ValueStatus classify(const signals::SlotSnapshot& slot, std::int64_t nowNs, std::int64_t staleAfterNs) noexcept {
  if (slot.bus.updates > 0) {
    if (slot.bus.quality != signals::Quality::Valid) return ValueStatus::Stale;
    if (staleAfterNs > 0 && nowNs - slot.bus.timestampNs > staleAfterNs) return ValueStatus::Stale;
    return ValueStatus::Ready;
  }
  if (slot.command.updates > 0 || slot.override.active) return ValueStatus::Ready;
  return ValueStatus::NotConnected;
}

std::optional<double> shownValue(const signals::SignalInfo& signal, const signals::SlotSnapshot& slot) noexcept {
  if (slot.bus.updates > 0) return slot.bus.value;
  if (signal.direction == signals::SignalDirection::Received) return std::nullopt;
  if (const auto command = signals::effectiveCommand(slot)) return command->value;
  return std::nullopt;
}

std::string formatValue(const signals::SignalInfo& signal, double value, std::string_view format) {
  if (auto maybeText = valueText(signal, value)) return *maybeText;
  std::array<char, 64> text{};
  if (format.empty()) {
    const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size() - 1, value);
    if (ec != std::errc{}) return "?";
    *end = '\0';
  } else {
    const std::string spec = config::isSafeNumberFormat(format) ? std::string(format) : std::string("%g");
    std::snprintf(text.data(), text.size(), spec.c_str(), value);
  }
  std::string out = text.data();
  if (!signal.unit.empty()) out += " " + signal.unit;
  return out;
}

std::string shortLabel(std::string_view key) {
  // "HVLP_SA71.HS2_Status_Feedback.InverterStatus" -> "HVLP_SA71 InverterStatus";
  // "internal.relay.Cl15" -> "relay Cl15"
  const auto first = key.find('.');
  const auto last = key.rfind('.');
  if (first == std::string_view::npos) return std::string(key);
  if (key.starts_with("internal.")) {
    const auto previous = key.rfind('.', last - 1);
    return std::string(key.substr(previous + 1, last - previous - 1)) + " " + std::string(key.substr(last + 1));
  }
  return std::string(key.substr(0, first)) + " " + std::string(key.substr(last + 1));
}

TextTone toneOf(std::string_view text) noexcept {
  // the good words first: "No fault (Normal)" is good although it contains "fault"
  for (const std::string_view good :
       {"Normal", "normal", "No fault", "No error", "OK", "Ok", "Closed", "Connected", "Ready"}) {
    if (contains(text, good)) return TextTone::Good;
  }
  for (const std::string_view bad : {"Fault", "fault", "Error", "error", "Fail", "fail", "Alarm", "alarm"}) {
    if (contains(text, bad)) return TextTone::Bad;
  }
  return TextTone::Neutral;
}

std::int64_t staleAfterFor(const signals::SignalInfo& signal, std::int64_t busTimeoutNs) noexcept {
  return signal.kind == signals::SignalKind::Bus ? busTimeoutNs : 0;
}

// ---- state machine rules -------------------------------------------------------------

Result<FsmRules> FsmRules::parse(std::string_view text, const std::string& source) {
  auto jsonResult = config::parseJson(text, source);
  if (!jsonResult) return jsonResult.error();
  const config::Json& root = *jsonResult;
  if (!root.is_object() || !root.contains("states") || !root["states"].is_array()) {
    return Error{"must be an object with a \"states\" array", Location::json(source, "/states")};
  }
  FsmRules rules;
  for (std::size_t i = 0; i < root["states"].size(); ++i) {
    const config::Json& state = root["states"][i];
    if (!state.is_object() || !state.contains("name") || !state["name"].is_string()) {
      return Error{"a state needs a \"name\"", Location::json(source, "/states/" + std::to_string(i))};
    }
    State entry;
    entry.name = state["name"].get<std::string>();
    if (state.contains("transitions") && state["transitions"].is_array()) {
      for (const auto& transition : state["transitions"]) {
        if (transition.is_object() && transition.contains("condition"))
          collectKeys(transition["condition"], entry.reads);
      }
    }
    rules.m_states.push_back(std::move(entry));
  }
  return rules;
}

Result<FsmRules> FsmRules::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error{"cannot read the FSM file", Location{path, 0, 0, {}}};
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

std::string FsmRules::stateName(double index) const {
  if (index >= 0 && index < static_cast<double>(m_states.size()) && std::trunc(index) == index) {
    return m_states[static_cast<std::size_t>(index)].name;
  }
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "state %g", index);
  return text.data();
}

bool FsmRules::stateReads(double index, std::string_view key) const {
  if (!(index >= 0 && index < static_cast<double>(m_states.size()))) return false;
  const auto& reads = m_states[static_cast<std::size_t>(index)].reads;
  return reads.find(key) != reads.end();
}

// ---- service health ------------------------------------------------------------------

HealthTracker::HealthTracker(std::vector<std::string> expected, std::int64_t staleAfterNs)
    : m_staleAfterNs(staleAfterNs) {
  for (std::string& name : expected) {
    ServiceHealth service;
    service.name = std::move(name);
    m_services.push_back(std::move(service));
  }
}

bool HealthTracker::onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs) {
  auto it = std::find_if(m_services.begin(), m_services.end(),
                         [&](const ServiceHealth& service) { return service.name == beat.service; });
  const bool added = it == m_services.end();
  if (added) {
    ServiceHealth service;
    service.name = beat.service;
    m_services.push_back(std::move(service));
    it = m_services.end() - 1;
  }
  if (it->pid != 0 && it->pid != beat.pid) ++it->restarts;
  it->pid = beat.pid;
  it->uptimeMs = beat.uptimeMs;
  it->lastBeatMonoNs = receivedMonoNs;
  it->status = beat.status;
  ++it->heartbeats;
  return added;
}

ValueStatus HealthTracker::statusOf(const ServiceHealth& service, std::int64_t nowNs) const noexcept {
  if (service.lastBeatMonoNs < 0) return ValueStatus::NotConnected;
  const std::int64_t age = nowNs - service.lastBeatMonoNs;
  if (age > 3 * m_staleAfterNs) return ValueStatus::NotConnected;
  if (age > m_staleAfterNs) return ValueStatus::Stale;
  if (service.status.starts_with("stopping")) return ValueStatus::NotConnected;
  return ValueStatus::Ready;
}

const ServiceHealth* HealthTracker::find(std::string_view name) const noexcept {
  for (const ServiceHealth& service : m_services) {
    if (service.name == name) return &service;
  }
  return nullptr;
}

// ---- commands --------------------------------------------------------------------------

CommandTracker::CommandTracker(std::string issuer, std::int64_t firstId, std::int64_t timeoutNs)
    : m_issuer(std::move(issuer)), m_nextId(firstId > 0 ? firstId : 1), m_timeoutNs(timeoutNs) {}

void CommandTracker::prepare(ipc::CommandRequest& request, std::int64_t nowNs) {
  request.requestId = m_nextId++;
  request.issuer = m_issuer;
  m_pending[request.requestId] = nowNs + m_timeoutNs;
}

std::optional<std::pair<std::int64_t, CommandOutcome>> CommandTracker::onAck(const ipc::CommandAck& ack) {
  if (ack.issuer != m_issuer) return std::nullopt;
  const auto it = m_pending.find(ack.requestId);
  if (it == m_pending.end()) return std::nullopt;
  m_pending.erase(it);
  CommandOutcome outcome;
  if (ack.accepted) {
    outcome.state = CommandOutcome::State::Accepted;
    outcome.text = "accepted by " + ack.responder;
  } else {
    outcome.state = CommandOutcome::State::Refused;
    outcome.text = "refused by " + ack.responder + ": " + ack.reason;
  }
  return std::make_pair(ack.requestId, std::move(outcome));
}

std::vector<std::pair<std::int64_t, CommandOutcome>> CommandTracker::expire(std::int64_t nowNs) {
  std::vector<std::pair<std::int64_t, CommandOutcome>> expired;
  for (auto it = m_pending.begin(); it != m_pending.end();) {
    if (nowNs >= it->second) {
      std::array<char, 64> text{};
      std::snprintf(text.data(), text.size(), "no answer within %.1f s", static_cast<double>(m_timeoutNs) / 1e9);
      expired.emplace_back(it->first, CommandOutcome{CommandOutcome::State::TimedOut, text.data()});
      it = m_pending.erase(it);
    } else {
      ++it;
    }
  }
  return expired;
}

// ---- log ring --------------------------------------------------------------------------

LogBuffer::LogBuffer(std::size_t capacity) : m_capacity(capacity > 0 ? capacity : 1) {}

bool LogBuffer::add(ipc::LogRecord record) {
  m_records.push_back(std::move(record));
  if (m_records.size() <= m_capacity) return false;
  m_records.pop_front();
  return true;
}

std::vector<std::size_t> LogBuffer::select(std::string_view service, ipc::LogLevel minimum) const {
  std::vector<std::size_t> indices;
  for (std::size_t i = 0; i < m_records.size(); ++i) {
    const ipc::LogRecord& record = m_records[i];
    if (record.level < minimum) continue;
    if (!service.empty() && record.service != service) continue;
    indices.push_back(i);
  }
  return indices;
}

std::string LogBuffer::exportText(const std::vector<std::size_t>& indices) const {
  std::string out;
  for (const std::size_t index : indices) {
    if (index >= m_records.size()) continue;
    const ipc::LogRecord& record = m_records[index];
    out += formatUtc(record.timestampNs) + " " + std::string(levelName(record.level)) + " " + record.service + ": " +
           record.text + "\n";
  }
  return out;
}

std::set<std::string> LogBuffer::services() const {
  std::set<std::string> names;
  for (const ipc::LogRecord& record : m_records) names.insert(record.service);
  return names;
}

std::string_view levelName(ipc::LogLevel level) noexcept {
  switch (level) {
    case ipc::LogLevel::Trace:
      return "trace";
    case ipc::LogLevel::Debug:
      return "debug";
    case ipc::LogLevel::Info:
      return "info";
    case ipc::LogLevel::Warning:
      return "warning";
    case ipc::LogLevel::Error:
      return "error";
    case ipc::LogLevel::Critical:
      return "critical";
  }
  return "?";
}

}  // namespace openvcu::hmi
