#include "engine.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <string_view>

#include "openvcu/display/values.hpp"
#include "openvcu/fleet/payloads.hpp"
#include "openvcu/fleet/topics.hpp"
#include "openvcu/j1939/dm1.hpp"

namespace openvcu::telemetry {
namespace {

using Json = nlohmann::json;
/// Members in the order written (the faults message keeps the documented field order).
using OrderedJson = nlohmann::ordered_json;

/// A DBC signal not received for this long is Stale (dashboard.json's default).
constexpr std::int64_t BUS_STALE_NS = 2'000'000'000;

std::int64_t toUnixMs(std::int64_t monoNs, const ClockPair& clocks) {
  return clocks.unixMs + (monoNs - clocks.monoNs) / 1'000'000;
}

/// "<suffix>\n{"v":1,"seq":N,"t":T,<body>}"; body: members without braces.
std::string record(fleet::Topic topic, std::uint64_t sequence, std::int64_t unixMs, const std::string& body) {
  const std::string_view suffix = fleet::topicSuffix(topic);
  std::string out;
  out.reserve(suffix.size() + body.size() + 48);
  out += suffix;
  out += "\n{\"v\":";
  out += std::to_string(fleet::PAYLOAD_VERSION);
  out += ",\"seq\":";
  out += std::to_string(sequence);
  out += ",\"t\":";
  out += std::to_string(unixMs);
  if (!body.empty()) out += ',';
  out += body;
  out += '}';
  return out;
}

/// The members of a JSON object without its braces.
template <typename AnyJson>
std::string members(const AnyJson& object) {
  std::string text = object.dump();
  return text.substr(1, text.size() - 2);
}

}  // namespace

Engine::Engine(const signals::Catalog& catalog, const signals::SignalTable& table)
    : m_catalog(&catalog), m_table(&table), m_health(display::expectedServices(), display::HEARTBEAT_STALE_NS) {}

Result<Engine> Engine::create(const config::TelemetryConfig& settings, const signals::Catalog& catalog,
                              const signals::SignalTable& table) {
  Engine engine(catalog, table);
  std::string unknown;
  for (const config::TelemetrySignal& signal : settings.signals) {
    const auto index = catalog.indexOf(signal.name);
    if (!index) {
      unknown += (unknown.empty() ? "'" : ", '") + signal.name + "'";
      continue;
    }
    engine.m_watched.push_back(Watched{.name = signal.name,
                                       .index = *index,
                                       .minPeriodNs = static_cast<std::int64_t>(1e9 / signal.maxRateHz),
                                       .deadband = signal.deadband});
  }
  if (!unknown.empty()) return Error{"/signals: not in this vehicle's catalog: " + unknown};
  return engine;
}

void Engine::onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs) {
  m_health.onHeartbeat(beat, receivedMonoNs);
}

void Engine::onFault(const ipc::FaultEvent& fault) {
  const FaultKey key{fault.name, fault.source};
  if (fault.active) {
    m_faults[key] = fault;
  } else {
    m_faults.erase(key);
  }
}

void Engine::onTransition(const ipc::FsmTransition& transition) { m_transitions.push_back(transition); }

void Engine::onDm1(const ipc::NodeDm1& dm1) { m_dm1[dm1.node] = dm1; }

void Engine::sample(std::int64_t nowMonoNs) {
  for (std::size_t i = 0; i < m_watched.size(); ++i) {
    Watched& watched = m_watched[i];
    if (watched.sent && nowMonoNs - watched.lastSentNs < watched.minPeriodNs) continue;  // the rate limit
    const signals::SignalInfo& info = (*m_catalog)[watched.index];
    const auto slot = m_table->read(watched.index);
    if (!slot) continue;
    const auto shown = display::shownSample(info, *slot);
    if (!shown) continue;  // nothing written yet
    const int status = static_cast<int>(display::classify(*slot, nowMonoNs, display::staleAfterFor(info, BUS_STALE_NS)));
    const bool moved = !watched.sent || std::fabs(shown->value - watched.lastValue) > watched.deadband ||
                       (watched.deadband == 0 && shown->value != watched.lastValue);
    const bool due = moved || status != watched.lastStatus || nowMonoNs - watched.lastSentNs >= SIGNAL_KEEPALIVE_NS;
    if (!due) continue;
    m_samples.push_back(Sample{.signal = i, .timestampMonoNs = shown->timestampNs, .value = shown->value});
    watched.sent = true;
    watched.lastValue = shown->value;
    watched.lastStatus = status;
    watched.lastSentNs = nowMonoNs;
    ++m_samplesKept;
  }
}

std::string Engine::faultsBody(std::int64_t /*nowMonoNs*/) const {
  OrderedJson active = OrderedJson::array();
  for (const auto& [key, fault] : m_faults) {
    active.push_back({{"source", fault.source}, {"name", fault.name}, {"severity", std::string(display::faultSeverityName(fault.severity))},
                      {"text", fault.text}, {"sinceUnixMs", fault.timestampNs / 1'000'000}});
  }
  // a node whose last DM1 lists active DTCs: lamps (DM1 byte 0) and every DTC in DM1 order
  OrderedJson dm1 = OrderedJson::array();
  for (const auto& [node, last] : m_dm1) {
    if (last.dtcs.empty()) continue;
    const auto lamp = [&last](unsigned shift) {
      return std::string(j1939::lampStatusName(static_cast<j1939::LampStatus>((last.lamps >> shift) & 0x3U)));
    };
    OrderedJson dtcs = OrderedJson::array();
    for (const ipc::NodeDtc& dtc : last.dtcs) {
      dtcs.push_back(
          {{"spn", dtc.spn}, {"fmi", dtc.fmi}, {"oc", dtc.occurrences}, {"cm", dtc.conversionMethod ? 1 : 0}});
    }
    dm1.push_back(
        {{"node", node},
         {"activeDtcs", last.dtcs.size()},
         {"lamps", {{"malfunction", lamp(6)}, {"redStop", lamp(4)}, {"amberWarning", lamp(2)}, {"protect", lamp(0)}}},
         {"dtcs", std::move(dtcs)}});
  }
  return members(OrderedJson{{"active", std::move(active)}, {"dm1", std::move(dm1)}});
}

std::string Engine::healthSignature(std::int64_t nowMonoNs) const {
  std::string signature;
  for (const display::ServiceHealth& service : m_health.services()) {
    signature += service.name;
    signature += '=';
    signature += display::statusName(m_health.statusOf(service, nowMonoNs));
    signature += ';';
  }
  return signature;
}

std::vector<std::string> Engine::tick(std::uint64_t firstSequence, const TickInputs& inputs) {
  std::vector<std::string> records;
  std::uint64_t sequence = firstSequence;
  const ClockPair& clocks = inputs.clocks;
  const std::int64_t now = clocks.monoNs;

  for (const ipc::FsmTransition& transition : m_transitions) {
    const Json body = {{"state", transition.toState}, {"previous", transition.fromState}, {"event", transition.cause},
                       {"atUnixMs", transition.timestampNs / 1'000'000}};
    records.push_back(record(fleet::Topic::State, sequence++, clocks.unixMs, members(body)));
  }
  m_transitions.clear();

  if (std::string faults = faultsBody(now); faults != m_sentFaults) {
    records.push_back(record(fleet::Topic::Faults, sequence++, clocks.unixMs, faults));
    m_sentFaults = std::move(faults);
  }

  std::string signature = healthSignature(now);
  const bool linkChanged = inputs.link.connects != m_sentLink.connects || inputs.link.refused != m_sentLink.refused;
  if (signature != m_sentHealth || m_healthSentNs < 0 || now - m_healthSentNs >= HEALTH_PERIOD_NS ||
      !inputs.drops.empty() || linkChanged) {
    Json services = Json::array();
    for (const display::ServiceHealth& service : m_health.services()) {
      services.push_back({{"name", service.name},
                          {"status", std::string(display::statusName(m_health.statusOf(service, now)))},
                          {"text", service.status},
                          {"restarts", service.restarts}});
    }
    Json drops = Json::array();
    for (const QueueDrop& drop : inputs.drops) {
      drops.push_back({{"first", drop.firstSequence}, {"last", drop.lastSequence}, {"records", drop.records}});
    }
    const Json body = {{"services", std::move(services)},
                       {"queue", {{"pending", inputs.queue.pendingRecords}, {"diskBytes", inputs.queue.diskBytes},
                                  {"dropped", inputs.queue.droppedRecords}, {"drops", std::move(drops)}}},
                       {"link", {{"connects", inputs.link.connects}, {"refused", inputs.link.refused}}}};
    records.push_back(record(fleet::Topic::Health, sequence++, clocks.unixMs, members(body)));
    m_sentHealth = std::move(signature);
    m_sentLink = inputs.link;
    m_healthSentNs = now;
  }

  // the samples, cut into messages of at most MAX_SIGNALS_MESSAGE_BYTES
  std::size_t next = 0;
  while (next < m_samples.size()) {
    Json names = Json::array();
    std::vector<int> nameOf(m_watched.size(), -1);
    std::string samples;
    for (; next < m_samples.size() && samples.size() + 256 < MAX_SIGNALS_MESSAGE_BYTES; ++next) {
      const Sample& sample = m_samples[next];
      if (nameOf[sample.signal] < 0) {
        nameOf[sample.signal] = static_cast<int>(names.size());
        names.push_back(m_watched[sample.signal].name);
      }
      if (!samples.empty()) samples += ',';
      samples += '[';
      samples += std::to_string(nameOf[sample.signal]);
      samples += ',';
      samples += std::to_string(toUnixMs(sample.timestampMonoNs, clocks));
      samples += ',';
      samples += Json(sample.value).dump();
      samples += ']';
    }
    records.push_back(record(fleet::Topic::Signals, sequence++, clocks.unixMs,
                             "\"names\":" + names.dump() + ",\"samples\":[" + samples + "]"));
  }
  m_samples.clear();
  return records;
}

}  // namespace openvcu::telemetry
