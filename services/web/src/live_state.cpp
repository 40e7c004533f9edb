#include "live_state.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string_view>

#include "openvcu/commands/command_check.hpp"
#include "openvcu/core/clock.hpp"

namespace openvcu::web {
namespace {

using Json = nlohmann::json;

constexpr std::string_view DM1_PREFIX = "internal.dm1.";
constexpr std::string_view DM1_SUFFIX = ".activeDtcs";
/// Pages asking within this long share one build of the common part (each page's own signals
/// are read fresh on every update): ten pages at 20 updates/s build it at most 50 times a second.
constexpr std::int64_t COMMON_REUSE_NS = 20'000'000;

/// The value and its plane's write time (CLOCK_MONOTONIC ns) as the HMI shows it.
std::optional<std::pair<double, std::int64_t>> shown(const signals::SignalInfo& info,
                                                     const signals::SlotSnapshot& slot) noexcept {
  const auto sample = display::shownSample(info, slot);
  if (!sample) return std::nullopt;
  return std::pair{sample->value, sample->timestampNs};
}

/// A page's stream: its signals' values with the common part, when something changed.
class LiveStream final : public EventSource {
 public:
  LiveStream(LiveState& live, std::vector<signals::SignalIndex> indices)
      : m_live(live), m_indices(std::move(indices)) {}

  std::string next() override {
    const std::int64_t now = clock::monotonicNs();
    std::uint64_t version = 0;
    const std::string& common = m_live.common(now, version);
    m_signals.clear();
    m_signature.clear();
    for (std::size_t i = 0; i < m_indices.size(); ++i) {
      if (i > 0) m_signals += ',';
      m_live.appendSignal(m_signals, m_signature, m_indices[i], now);
    }
    const bool changed = version != m_sentVersion || m_signature != m_sentSignature;
    if (!changed && now - m_sentAtNs < std::chrono::nanoseconds(LIVE_IDLE_UPDATE).count()) return {};
    m_sentVersion = version;
    m_sentSignature = m_signature;
    m_sentAtNs = now;
    ++m_sequence;
    std::string event;
    event.reserve(common.size() + m_signals.size() + 96);
    event += "event: update\ndata: {\"t\":";
    event += std::to_string(clock::realtimeNs() / 1'000'000);
    event += ",\"seq\":";
    event += std::to_string(m_sequence);
    event += ',';
    event += common;  // "header":...,"faults":...,"operator":...
    event += ",\"signals\":[";
    event += m_signals;
    event += "]}\n\n";
    return event;
  }

 private:
  LiveState& m_live;
  std::vector<signals::SignalIndex> m_indices;
  std::string m_signals;
  std::string m_signature;
  std::string m_sentSignature;
  std::uint64_t m_sentVersion{0};
  std::int64_t m_sentAtNs{0};
  std::uint64_t m_sequence{0};
};

}  // namespace

LiveState::LiveState(const signals::Catalog& catalog, const signals::SignalTable& table, LiveSetup setup)
    : m_catalog(catalog),
      m_table(table),
      m_setup(std::move(setup)),
      m_health(display::expectedServices(), display::HEARTBEAT_STALE_NS),
      m_slots(catalog) {
  if (!m_setup.fsmFile.empty()) {
    if (auto rules = display::FsmRules::load(m_setup.fsmFile)) {
      m_rules = std::move(*rules);
    } else {
      m_rulesError = rules.error().toString();
    }
  }
  m_stateIndex = m_catalog.indexOf("internal.fsm.state");
  if (!m_setup.socKey.empty()) m_socIndex = m_catalog.indexOf(m_setup.socKey);
  for (signals::SignalIndex i = 0; i < m_catalog.size(); ++i) {
    const signals::SignalInfo& info = m_catalog[i];
    if (info.key.starts_with(DM1_PREFIX) && info.key.ends_with(DM1_SUFFIX)) {
      m_dm1.emplace_back(info.key.substr(DM1_PREFIX.size(), info.key.size() - DM1_PREFIX.size() - DM1_SUFFIX.size()),
                         i);
    }
    if (!info.key.starts_with(commands::OPERATOR_PREFIX) || info.key == commands::FAULT_RESET_KEY) continue;
    OperatorRow row{.key = info.key, .label = info.key.substr(commands::OPERATOR_PREFIX.size()), .index = i};
    if (info.valueTexts.size() >= 2) {
      row.label = info.valueTexts.back().second;
      row.onValue = static_cast<double>(info.valueTexts.back().first);
      if (row.label == "Start") row.label = "Start / Stop";
    }
    m_operator.push_back(std::move(row));
  }
  m_catalogJson = buildCatalogJson();
}

void LiveState::onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs) {
  m_health.onHeartbeat(beat, receivedMonoNs);
}

void LiveState::onFault(const ipc::FaultEvent& fault) {
  const FaultKey key{fault.name, fault.source};
  if (fault.active) {
    m_faults[key] = fault;
  } else {
    m_faults.erase(key);
  }
  m_builtAtNs = -1;
}

void LiveState::onTransition(const ipc::FsmTransition& transition) {
  m_stateSinceUnixMs = transition.timestampNs / 1'000'000;
  m_builtAtNs = -1;
}

bool LiveState::isOperatorKey(const std::string& key) const {
  return std::any_of(m_operator.begin(), m_operator.end(), [&](const OperatorRow& row) { return row.key == key; });
}

const std::string& LiveState::common(std::int64_t nowMonoNs, std::uint64_t& version) {
  if (m_builtAtNs < 0 || nowMonoNs - m_builtAtNs >= COMMON_REUSE_NS) rebuild(nowMonoNs);
  version = m_version;
  return m_common;
}

void LiveState::rebuild(std::int64_t nowMonoNs) {
  m_builtAtNs = nowMonoNs;
  m_slots.feed(m_health, m_table);
  const std::int64_t nowRealNs = clock::realtimeNs();
  // a silent service's "since" on the real-time clock, in ms, stable from build to build
  const auto sinceUnixMs = [&](std::int64_t silentNs) { return (nowRealNs - silentNs) / 1'000'000; };
  Json header = Json::object();
  double state = -1;
  if (m_stateIndex) {
    if (const auto slot = m_table.read(*m_stateIndex)) {
      if (const auto value = shown(m_catalog[*m_stateIndex], *slot)) {
        state = value->first;
        if (state != m_lastState) {
          // first sight, or a change the transition event has not told yet: since the write
          const std::int64_t age = std::max<std::int64_t>(0, nowMonoNs - value->second);
          if (m_lastState >= 0 || m_stateSinceUnixMs == 0) m_stateSinceUnixMs = (clock::realtimeNs() - age) / 1'000'000;
          m_lastState = state;
        }
      }
    }
  }
  if (state >= 0) {
    header["state"] = m_rules ? m_rules->stateName(state) : "state " + std::to_string(static_cast<long long>(state));
    header["stateIndex"] = state;
    header["stateSinceUnixMs"] = m_stateSinceUnixMs;
  } else {
    header["state"] = nullptr;
  }
  // the state is vcu-fsm's: while it does not beat, what the table holds is its last state
  const display::ServiceHealth* fsm = m_health.find("vcu-fsm");
  const display::Liveness fsmLiveness = fsm ? m_health.livenessOf(*fsm, nowMonoNs) : display::Liveness::NotHeard;
  header["stateStale"] = state >= 0 && fsmLiveness != display::Liveness::Beating;
  header["stateNote"] = fsmLiveness == display::Liveness::Beating
                            ? ""
                            : "vcu-fsm " + std::string(display::livenessName(fsmLiveness)) +
                                  ": the last state written, not the current one";
  if (const auto silentNs = fsm ? m_health.silentFor(*fsm, nowMonoNs) : std::nullopt) {
    header["stateWriterSilentSinceUnixMs"] = sinceUnixMs(*silentNs);
  }
  if (m_socIndex) {
    const signals::SignalInfo& info = m_catalog[*m_socIndex];
    Json soc = {{"key", info.key}};
    const auto slot = m_table.read(*m_socIndex);
    const display::ValueStatus status =
        slot ? display::classify(*slot, nowMonoNs, display::staleAfterFor(info, m_setup.busStaleAfterNs))
             : display::ValueStatus::NotConnected;
    const auto value = slot ? shown(info, *slot) : std::nullopt;
    soc["text"] = value ? display::formatValue(info, value->first, "%.1f") : "";
    soc["status"] = std::string(display::statusName(status));
    header["soc"] = std::move(soc);
  }
  Json services = Json::array();
  bool allReady = true;
  bool anyHeard = false;
  for (const display::ServiceHealth& service : m_health.services()) {
    const display::ValueStatus status = m_health.statusOf(service, nowMonoNs);
    allReady = allReady && status == display::ValueStatus::Ready;
    anyHeard = anyHeard || status != display::ValueStatus::NotConnected;
    const display::Liveness liveness = m_health.livenessOf(service, nowMonoNs);
    Json entry = {{"name", service.name},
                  {"status", std::string(display::statusName(status))},
                  {"liveness", std::string(display::livenessName(liveness))},
                  {"text", service.status},
                  {"restarts", service.restarts}};
    if (const auto silentNs = m_health.silentFor(service, nowMonoNs)) {
      entry["text"] = std::string(display::livenessName(liveness)) +
                      (service.status.empty() ? std::string() : " (last: " + service.status + ")");
      entry["silentSinceUnixMs"] = sinceUnixMs(*silentNs);
    }
    services.push_back(std::move(entry));
  }
  header["health"] = allReady ? "Ready" : (anyHeard ? "Stale" : "NotConnected");
  header["services"] = std::move(services);

  Json faults = Json::array();
  std::vector<ipc::FaultEvent> listed;
  for (const auto& [key, fault] : m_faults) listed.push_back(fault);
  // a silent service is a fault on its own, also without vcu-watchdog (which raises the same name)
  for (ipc::FaultEvent& silent : m_health.silentFaults(nowMonoNs, nowRealNs)) {
    if (!display::namesFault(listed, silent.name)) listed.push_back(std::move(silent));
  }
  for (const ipc::FaultEvent& fault : listed) {
    faults.push_back({{"name", fault.name},
                      {"source", fault.source},
                      {"severity", std::string(display::faultSeverityName(fault.severity))},
                      {"text", fault.text},
                      {"sinceUnixMs", fault.timestampNs / 1'000'000}});
  }
  for (const auto& [node, index] : m_dm1) {
    const auto slot = m_table.read(index);
    if (!slot || slot->bus.updates == 0 || slot->bus.value <= 0) continue;
    faults.push_back(
        {{"name", "dm1." + node},
         {"source", "DM1"},
         {"severity", "warning"},
         {"text", std::to_string(static_cast<long long>(slot->bus.value)) + " active DTC(s) (J1939-73 DM1)"},
         {"sinceUnixMs", nullptr}});
  }

  Json operatorRows = Json::array();
  for (const OperatorRow& row : m_operator) {
    const signals::SignalInfo& info = m_catalog[row.index];
    const auto slot = m_table.read(row.index);
    const auto value = slot ? shown(info, *slot) : std::nullopt;
    const double current = value ? value->first : 0.0;
    const bool on = value.has_value() && current == row.onValue;
    const bool reads = m_rules && state >= 0 && m_rules->stateReads(state, row.key);
    operatorRows.push_back({{"key", row.key},
                            {"label", row.label},
                            {"on", on},
                            {"onValue", row.onValue},
                            {"enabled", reads || on},
                            {"stateText", value ? display::formatValue(info, current, "") : std::string()}});
  }

  std::string text =
      "\"header\":" + header.dump() + ",\"faults\":" + faults.dump() + ",\"operator\":" + operatorRows.dump();
  if (text != m_common) {
    m_common = std::move(text);
    ++m_version;
  }
}

void LiveState::appendSignal(std::string& out, std::string& signature, signals::SignalIndex index,
                             std::int64_t nowMonoNs) const {
  const signals::SignalInfo& info = m_catalog[index];
  const auto slot = m_table.read(index);
  const display::ValueStatus status =
      slot ? display::classify(*slot, nowMonoNs, display::staleAfterFor(info, m_setup.busStaleAfterNs))
           : display::ValueStatus::NotConnected;
  const auto value = slot ? shown(info, *slot) : std::nullopt;
  Json entry = {{"key", info.key}, {"status", std::string(display::statusName(status))}};
  if (value) {
    entry["value"] = value->first;
    entry["text"] = display::formatValue(info, value->first, "");
    entry["ageMs"] = std::max<std::int64_t>(0, nowMonoNs - value->second) / 1'000'000;
  } else {
    entry["value"] = nullptr;
    entry["text"] = "";
    entry["ageMs"] = nullptr;
  }
  out += entry.dump();
  signature += std::to_string(index);
  signature += ':';
  signature += value ? std::to_string(value->first) : "-";
  signature += display::statusName(status);
  signature += ';';
}

Result<std::unique_ptr<EventSource>> LiveState::openStream(const std::string& keys) {
  std::vector<signals::SignalIndex> indices;
  std::vector<std::string> unknown;
  std::size_t start = 0;
  while (start <= keys.size() && !keys.empty()) {
    const std::size_t comma = std::min(keys.find(',', start), keys.size());
    const std::string key = keys.substr(start, comma - start);
    start = comma + 1;
    if (key.empty()) continue;
    if (const auto index = m_catalog.indexOf(key)) {
      if (std::find(indices.begin(), indices.end(), *index) == indices.end()) indices.push_back(*index);
    } else {
      unknown.push_back(key);
    }
    if (comma == keys.size()) break;
  }
  if (!unknown.empty()) {
    std::string message = "unknown signal";
    message += unknown.size() == 1 ? " " : "s ";
    for (std::size_t i = 0; i < unknown.size() && i < 5; ++i) message += (i > 0 ? ", '" : "'") + unknown[i] + "'";
    return Error{message + " (GET /api/catalog lists them)"};
  }
  if (indices.size() > MAX_LIVE_SIGNALS) {
    return Error{std::to_string(indices.size()) + " signals: a page follows at most " +
                 std::to_string(MAX_LIVE_SIGNALS)};
  }
  return std::unique_ptr<EventSource>(std::make_unique<LiveStream>(*this, std::move(indices)));
}

std::string LiveState::buildCatalogJson() const {
  Json list = Json::array();
  for (signals::SignalIndex i = 0; i < m_catalog.size(); ++i) {
    const signals::SignalInfo& info = m_catalog[i];
    Json entry = {{"key", info.key},
                  {"unit", info.unit},
                  {"min", info.minimum},
                  {"max", info.maximum},
                  {"comment", info.comment}};
    const bool internal = info.key.starts_with("internal.");
    if (internal) {
      const auto dot = info.key.find('.', 9);
      entry["group"] = info.key.substr(9, dot == std::string::npos ? std::string::npos : dot - 9);
      entry["bus"] = entry["node"] = entry["message"] = "";
      entry["signal"] = dot == std::string::npos ? info.key.substr(9) : info.key.substr(dot + 1);
      entry["direction"] = "internal";
    } else {
      const auto first = info.key.find('.');
      entry["bus"] = info.bus;
      entry["node"] = first == std::string::npos ? "" : info.key.substr(0, first);
      entry["message"] = info.message;
      entry["signal"] = info.key.substr(info.key.rfind('.') + 1);
      entry["direction"] = info.direction == signals::SignalDirection::Received ? "rx" : "tx";
    }
    Json values = Json::object();
    for (const auto& [raw, text] : info.valueTexts) values[std::to_string(raw)] = text;
    entry["values"] = std::move(values);
    list.push_back(std::move(entry));
  }
  return Json{{"signals", std::move(list)}}.dump();
}

}  // namespace openvcu::web
