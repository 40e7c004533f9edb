#include "openvcu/fleet/payloads.hpp"

#include <array>
#include <nlohmann/json.hpp>

#include "openvcu/fleet/topics.hpp"

namespace openvcu::fleet {
namespace {

using Json = nlohmann::json;

constexpr std::array<std::string_view, 4> LEVEL_NAMES{"info", "warning", "error", "critical"};

/// The JSON object of a payload with "v": 1, or why not.
Result<Json> parseObject(std::string_view payload) {
  Json json = Json::parse(payload, nullptr, false);
  if (json.is_discarded()) return Error{"not JSON"};
  if (!json.is_object()) return Error{"not a JSON object"};
  const auto version = json.find("v");
  if (version == json.end() || !version->is_number_integer()) return Error{"/v: missing (the format version)"};
  if (version->get<int>() != PAYLOAD_VERSION) {
    return Error{"/v: version " + std::to_string(version->get<int>()) + " (this reads " +
                 std::to_string(PAYLOAD_VERSION) + ")"};
  }
  return json;
}

/// Reads members by JSON pointer; the first problem is kept and returned by error().
class Reader {
 public:
  std::string text(const Json& object, const char* key, const std::string& path, bool required = true) {
    const auto it = object.find(key);
    if (it == object.end() || it->is_null()) {
      if (required) fail(path + "/" + key + ": missing");
      return {};
    }
    if (!it->is_string()) {
      fail(path + "/" + key + ": not a string");
      return {};
    }
    return it->get<std::string>();
  }
  template <typename Number>
  Number number(const Json& object, const char* key, const std::string& path, bool required = true) {
    const auto it = object.find(key);
    if (it == object.end()) {
      if (required) fail(path + "/" + key + ": missing");
      return Number{};
    }
    if (!it->is_number()) {
      fail(path + "/" + key + ": not a number");
      return Number{};
    }
    return it->get<Number>();
  }
  const Json& array(const Json& object, const char* key, const std::string& path) {
    static const Json EMPTY = Json::array();
    const auto it = object.find(key);
    if (it == object.end()) return EMPTY;
    if (!it->is_array()) {
      fail(path + "/" + key + ": not an array");
      return EMPTY;
    }
    return *it;
  }
  bool objectAt(const Json& item, const std::string& path) {
    if (item.is_object()) return true;
    fail(path + ": not an object");
    return false;
  }
  void fail(std::string message) {
    if (m_error.empty()) m_error = std::move(message);
  }
  [[nodiscard]] bool ok() const { return m_error.empty(); }
  [[nodiscard]] Error error() const { return Error{m_error}; }

 private:
  std::string m_error;
};

}  // namespace

std::optional<FaultLevel> faultLevelFromName(std::string_view name) noexcept {
  for (std::size_t i = 0; i < LEVEL_NAMES.size(); ++i) {
    if (LEVEL_NAMES[i] == name) return static_cast<FaultLevel>(i);
  }
  return std::nullopt;
}

std::string_view faultLevelName(FaultLevel level) noexcept {
  return LEVEL_NAMES.at(static_cast<std::size_t>(level));
}

Result<bool> parseStatus(std::string_view payload) {
  if (payload == STATUS_ONLINE) return true;
  if (payload == STATUS_OFFLINE) return false;
  return Error{"status: '" + std::string(payload.substr(0, 32)) + "' is neither online nor offline"};
}

Result<BirthMessage> parseBirth(std::string_view payload) {
  auto json = parseObject(payload);
  if (!json) return json.error();
  Reader read;
  BirthMessage out;
  out.vehicleId = read.text(*json, "vehicleId", "");
  out.instance = read.text(*json, "instance", "", false);
  out.software = read.text(*json, "software", "", false);
  out.configHash = read.text(*json, "configHash", "", false);
  out.nextSeq = read.number<std::uint64_t>(*json, "nextSeq", "", false);
  out.unixMs = read.number<std::int64_t>(*json, "t", "", false);
  const Json& signalList = read.array(*json, "signals", "");
  for (std::size_t i = 0; i < signalList.size(); ++i) {
    const std::string path = "/signals/" + std::to_string(i);
    if (!read.objectAt(signalList[i], path)) break;
    out.signals.push_back({read.text(signalList[i], "name", path), read.text(signalList[i], "unit", path, false)});
  }
  if (const auto commands = json->find("commands"); commands != json->end() && commands->is_object()) {
    const auto enabled = commands->find("enabled");
    out.commandsEnabled = enabled != commands->end() && enabled->is_boolean() && enabled->get<bool>();
  }
  if (!read.ok()) return read.error();
  return out;
}

Result<StateMessage> parseState(std::string_view payload) {
  auto json = parseObject(payload);
  if (!json) return json.error();
  Reader read;
  StateMessage out;
  out.seq = read.number<std::uint64_t>(*json, "seq", "");
  out.unixMs = read.number<std::int64_t>(*json, "t", "");
  out.state = read.text(*json, "state", "");
  out.previous = read.text(*json, "previous", "", false);
  out.event = read.text(*json, "event", "", false);
  out.atUnixMs = read.number<std::int64_t>(*json, "atUnixMs", "", false);
  if (!read.ok()) return read.error();
  return out;
}

Result<FaultsMessage> parseFaults(std::string_view payload) {
  auto json = parseObject(payload);
  if (!json) return json.error();
  Reader read;
  FaultsMessage out;
  out.seq = read.number<std::uint64_t>(*json, "seq", "");
  out.unixMs = read.number<std::int64_t>(*json, "t", "");
  const Json& active = read.array(*json, "active", "");
  for (std::size_t i = 0; i < active.size() && read.ok(); ++i) {
    const std::string path = "/active/" + std::to_string(i);
    if (!read.objectAt(active[i], path)) break;
    ActiveFault fault;
    fault.source = read.text(active[i], "source", path, false);
    fault.name = read.text(active[i], "name", path);
    fault.text = read.text(active[i], "text", path, false);
    const std::string severity = read.text(active[i], "severity", path, false);
    if (!severity.empty()) {
      const auto level = faultLevelFromName(severity);
      if (!level) read.fail(path + "/severity: unknown '" + severity + "'");
      fault.level = level.value_or(FaultLevel::Error);
    }
    out.active.push_back(std::move(fault));
  }
  const Json& dm1 = read.array(*json, "dm1", "");
  for (std::size_t i = 0; i < dm1.size() && read.ok(); ++i) {
    const std::string path = "/dm1/" + std::to_string(i);
    if (!read.objectAt(dm1[i], path)) break;
    out.dm1.push_back({read.text(dm1[i], "node", path), read.number<std::int64_t>(dm1[i], "activeDtcs", path)});
  }
  if (!read.ok()) return read.error();
  return out;
}

Result<HealthMessage> parseHealth(std::string_view payload) {
  auto json = parseObject(payload);
  if (!json) return json.error();
  Reader read;
  HealthMessage out;
  out.seq = read.number<std::uint64_t>(*json, "seq", "");
  out.unixMs = read.number<std::int64_t>(*json, "t", "");
  const Json& services = read.array(*json, "services", "");
  for (std::size_t i = 0; i < services.size() && read.ok(); ++i) {
    const std::string path = "/services/" + std::to_string(i);
    if (!read.objectAt(services[i], path)) break;
    out.services.push_back({read.text(services[i], "name", path), read.text(services[i], "status", path),
                            read.text(services[i], "text", path, false),
                            read.number<std::int64_t>(services[i], "restarts", path, false)});
  }
  if (const auto queue = json->find("queue"); queue != json->end() && queue->is_object()) {
    out.queuePending = read.number<std::uint64_t>(*queue, "pending", "/queue", false);
    out.queueDropped = read.number<std::uint64_t>(*queue, "dropped", "/queue", false);
  }
  if (const auto link = json->find("link"); link != json->end() && link->is_object()) {
    out.linkConnects = read.number<std::uint64_t>(*link, "connects", "/link", false);
    out.linkRefused = read.number<std::uint64_t>(*link, "refused", "/link", false);
  }
  if (!read.ok()) return read.error();
  return out;
}

Result<SignalsMessage> parseSignals(std::string_view payload) {
  auto json = parseObject(payload);
  if (!json) return json.error();
  Reader read;
  SignalsMessage out;
  out.seq = read.number<std::uint64_t>(*json, "seq", "");
  out.unixMs = read.number<std::int64_t>(*json, "t", "");
  const Json& names = read.array(*json, "names", "");
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!names[i].is_string()) read.fail("/names/" + std::to_string(i) + ": not a string");
  }
  const Json& samples = read.array(*json, "samples", "");
  for (std::size_t i = 0; i < samples.size() && read.ok(); ++i) {
    const Json& sample = samples[i];
    const std::string path = "/samples/" + std::to_string(i);
    if (!sample.is_array() || sample.size() != 3 || !sample[0].is_number_unsigned() || !sample[1].is_number() ||
        !sample[2].is_number()) {
      read.fail(path + ": not [name index, Unix ms, value]");
      break;
    }
    const auto index = sample[0].get<std::size_t>();
    if (index >= names.size()) {
      read.fail(path + ": name index " + std::to_string(index) + " beyond /names");
      break;
    }
    out.samples.push_back({names[index].get<std::string>(), sample[1].get<std::int64_t>(), sample[2].get<double>()});
  }
  if (!read.ok()) return read.error();
  return out;
}

}  // namespace openvcu::fleet
