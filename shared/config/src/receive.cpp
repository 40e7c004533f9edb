#include "openvcu/config/receive.hpp"

#include <cmath>
#include <optional>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/j1939/id.hpp"

namespace openvcu::config {
namespace {

constexpr std::int64_t NS_PER_MS = 1'000'000;

std::optional<double> cycleMs(const config::VehicleConfig& vehicle, const dbc::Message& message) {
  const auto value = vehicle.database.attribute(message.attributes, "GenMsgCycleTime", dbc::ObjectType::Message);
  if (!value || value->kind != dbc::AttributeValue::Kind::Number || value->number <= 0) return std::nullopt;
  return value->number;
}

/// "0x18FF5071", "419385457" or a number.
std::optional<std::uint32_t> parseId(const config::Json& value) {
  if (value.is_number_unsigned()) {
    const auto number = value.get<std::uint64_t>();  // not get<uint32_t>: 0x100000123 would become 0x123
    return number <= 0x1FFFFFFFu ? std::optional<std::uint32_t>(static_cast<std::uint32_t>(number)) : std::nullopt;
  }
  if (!value.is_string()) return std::nullopt;
  const std::string text = value.get<std::string>();
  if (text.empty()) return std::nullopt;
  std::size_t used = 0;
  try {
    const unsigned long parsed = std::stoul(text, &used, 0);
    if (used != text.size() || parsed > 0x1FFFFFFFul) return std::nullopt;
    return static_cast<std::uint32_t>(parsed);
  } catch (...) {
    return std::nullopt;
  }
}

std::vector<std::int64_t> timeoutsFor(const config::VehicleConfig& vehicle, double factor) {
  std::vector<std::int64_t> timeouts(vehicle.database.messages.size(), 0);
  for (std::size_t m = 0; m < timeouts.size(); ++m) {
    const dbc::Message& message = vehicle.database.messages[m];
    if (config::sentBy(message, vehicle.node)) continue;  // the VCU's own: never stale
    if (const auto cycle = cycleMs(vehicle, message)) {
      timeouts[m] = static_cast<std::int64_t>(std::llround(*cycle * factor * static_cast<double>(NS_PER_MS)));
    }
  }
  return timeouts;
}

class Loader {
 public:
  Loader(const config::VehicleConfig& vehicle, config::JsonChecker& check)
      : m_vehicle(vehicle), m_check(check), m_config(defaultReceiveConfig(vehicle)) {}

  void run(const config::Json& root) {
    if (!m_check.isObject(root, "")) return;
    m_check.onlyKeys(
        root, "",
        {"timeoutFactor", "senders", "messages", "safety", "forward", "transport", "dm1", "batchWindowUs", "comment"});
    if (auto factor = m_check.number(root, "", "timeoutFactor", false)) {
      if (!(*factor >= 1.0 && *factor <= 100.0)) {
        m_check.error("/timeoutFactor", "must be between 1 and 100 (times the DBC cycle)");
      } else {
        m_config.timeoutFactor = *factor;
        m_config.timeoutNs = timeoutsFor(m_vehicle, *factor);
      }
    }
    senders(root);  // before "messages": a message's own expectedWhen wins over its sender's
    messages(root);
    safety(root);
    forward(root);
    if (const config::Json* transport = m_check.member(root, "", "transport", false)) {
      if (m_check.isObject(*transport, "/transport")) {
        m_check.onlyKeys(*transport, "/transport", {"maxPacketsPerCts", "comment"});
        if (auto packets = m_check.number(*transport, "/transport", "maxPacketsPerCts", false)) {
          if (*packets < 1 || *packets > 255 || *packets != std::floor(*packets)) {
            m_check.error("/transport/maxPacketsPerCts", "must be a whole number from 1 to 255");
          } else {
            m_config.maxPacketsPerCts = static_cast<std::uint8_t>(*packets);
          }
        }
      }
    }
    if (auto dm1 = m_check.boolean(root, "", "dm1", false)) m_config.dm1 = *dm1;
    if (auto window = m_check.number(root, "", "batchWindowUs", false)) {
      if (!(*window >= 0 && *window <= 20'000) || *window != std::floor(*window)) {
        m_check.error("/batchWindowUs", "must be a whole number of microseconds from 0 (off) to 20000");
      } else {
        m_config.batchWindowUs = static_cast<std::uint32_t>(*window);
      }
    }
  }

  ReceiveConfig& config() { return m_config; }

 private:
  /// A DBC message on one of the configured buses, or an error with a suggestion.
  std::optional<std::size_t> message(const std::string& name, const std::string& path) {
    const auto& messages = m_vehicle.database.messages;
    for (std::size_t m = 0; m < messages.size(); ++m) {
      if (messages[m].name == name && !messages[m].pseudo) {
        if (m_vehicle.busOf(m) == nullptr) {
          m_check.error(path, "message '" + name + "' is on no configured bus");
          return std::nullopt;
        }
        return m;
      }
    }
    std::vector<std::string> names;
    for (const auto& candidate : messages) names.push_back(candidate.name);
    std::string text = "unknown message '" + name + "'";
    if (auto suggestion = text::didYouMean(name, names)) text += "; did you mean '" + *suggestion + "'?";
    m_check.error(path, std::move(text));
    return std::nullopt;
  }

  std::optional<std::size_t> bus(const config::Json& item, const std::string& path, std::string_view key) {
    const auto name = m_check.string(item, path, key);
    if (!name) return std::nullopt;
    std::vector<std::string> names;
    for (std::size_t b = 0; b < m_vehicle.buses.size(); ++b) {
      if (m_vehicle.buses[b].name == *name) return b;
      names.push_back(m_vehicle.buses[b].name);
    }
    std::string text = "unknown bus '" + *name + "'";
    if (auto suggestion = text::didYouMean(*name, names)) text += "; did you mean '" + *suggestion + "'?";
    m_check.error(config::JsonChecker::join(path, key), std::move(text));
    return std::nullopt;
  }

  void messages(const config::Json& root) {
    const config::Json* map = m_check.member(root, "", "messages", false);
    if (!map || !m_check.isObject(*map, "/messages")) return;
    for (const auto& [name, settings] : map->items()) {
      const std::string path = config::JsonChecker::join("/messages", name);
      const auto index = message(name, path);
      if (!m_check.isObject(settings, path)) continue;
      m_check.onlyKeys(settings, path, {"timeoutMs", "expectedWhen", "comment"});
      if (!settings.contains("timeoutMs") && !settings.contains("expectedWhen")) {
        m_check.error(path, "give \"timeoutMs\", \"expectedWhen\" or both");
        continue;
      }
      if (const config::Json* when = m_check.member(settings, path, "expectedWhen", false)) {
        const auto expectation = expectedWhen(*when, path + "/expectedWhen");
        if (index && expectation) {
          if (config::sentBy(m_vehicle.database.messages[*index], m_vehicle.node)) {
            m_check.error(path + "/expectedWhen", "message '" + name + "' is sent by this node (" + m_vehicle.node +
                                                      "); only received messages are supervised");
          } else {
            m_config.expectationOf[*index] = *expectation;
          }
        }
      }
      if (!settings.contains("timeoutMs")) continue;
      const auto timeout = m_check.number(settings, path, "timeoutMs");
      if (!index || !timeout) continue;
      if (!(*timeout >= 0 && *timeout <= 3'600'000)) {
        m_check.error(path + "/timeoutMs", "must be between 0 (never stale) and 3600000");
        continue;
      }
      if (config::sentBy(m_vehicle.database.messages[*index], m_vehicle.node) && *timeout > 0) {
        m_check.error(path, "message '" + name + "' is sent by this node (" + m_vehicle.node +
                                "); receive timeouts are for messages other nodes send");
        continue;
      }
      m_config.timeoutNs[*index] = static_cast<std::int64_t>(std::llround(*timeout * static_cast<double>(NS_PER_MS)));
    }
  }

  /// "senders": {"VIC": {"expectedWhen": ...}}: the condition of every message the node sends.
  void senders(const config::Json& root) {
    const config::Json* map = m_check.member(root, "", "senders", false);
    if (!map || !m_check.isObject(*map, "/senders")) return;
    for (const auto& [name, settings] : map->items()) {
      const std::string path = config::JsonChecker::join("/senders", name);
      const dbc::Database& database = m_vehicle.database;
      const dbc::Node* node = database.findNode(name);
      if (node == nullptr) {
        std::vector<std::string> names;
        for (const dbc::Node& candidate : database.nodes) names.push_back(candidate.name);
        std::string text = "unknown node '" + name + "'";
        if (auto suggestion = text::didYouMean(name, names)) text += "; did you mean '" + *suggestion + "'?";
        m_check.error(path, std::move(text));
        continue;
      }
      if (name == m_vehicle.node) {
        m_check.error(path, "'" + name + "' is this node; \"senders\" names the nodes it receives from");
        continue;
      }
      if (!m_check.isObject(settings, path)) continue;
      m_check.onlyKeys(settings, path, {"expectedWhen", "comment"});
      const config::Json* when = m_check.member(settings, path, "expectedWhen", true);
      if (!when) continue;
      const auto expectation = expectedWhen(*when, path + "/expectedWhen");
      if (!expectation) continue;
      std::size_t received = 0;
      for (std::size_t m = 0; m < database.messages.size(); ++m) {
        const dbc::Message& message = database.messages[m];
        if (message.pseudo || !config::sentBy(message, name) || config::sentBy(message, m_vehicle.node)) continue;
        if (m_vehicle.busOf(m) == nullptr) continue;
        m_config.expectationOf[m] = *expectation;
        ++received;
      }
      if (received == 0) m_check.error(path, "node '" + name + "' sends no message on the configured buses");
    }
  }

  /// "always", or {"signal": KEY, "eq": VALUE, "startMs": MS}: an index into expectations.
  std::optional<std::int32_t> expectedWhen(const config::Json& value, const std::string& path) {
    if (value.is_string() && value.get<std::string>() == "always") return ALWAYS_EXPECTED;
    if (!value.is_object()) {
      m_check.error(path, "must be \"always\" or an object {\"signal\": KEY, \"eq\": VALUE, \"startMs\": MS}");
      return std::nullopt;
    }
    m_check.onlyKeys(value, path, {"signal", "eq", "startMs", "comment"});
    const auto signal = m_check.string(value, path, "signal");
    const auto equals = m_check.number(value, path, "eq");
    std::optional<double> start = 0.0;
    if (value.contains("startMs")) start = m_check.number(value, path, "startMs");
    if (!signal || !equals || !start) return std::nullopt;
    if (!(*start >= 0 && *start <= 600'000) || *start != std::floor(*start)) {
      m_check.error(path + "/startMs", "must be a whole number of milliseconds from 0 to 600000");
      return std::nullopt;
    }
    const signals::Catalog* catalog = this->catalog(path + "/signal");
    if (!catalog) return std::nullopt;
    if (!catalog->indexOf(*signal)) {
      std::string text = "unknown signal '" + *signal + "'";
      if (auto suggestion = catalog->suggest(*signal)) text += "; did you mean '" + *suggestion + "'?";
      m_check.error(path + "/signal", std::move(text));
      return std::nullopt;
    }
    const std::int64_t startNs = static_cast<std::int64_t>(*start) * NS_PER_MS;
    auto& expectations = m_config.expectations;
    for (std::size_t e = 0; e < expectations.size(); ++e) {
      if (expectations[e].signal == *signal && expectations[e].equals == *equals &&
          expectations[e].startNs == startNs) {
        return static_cast<std::int32_t>(e);
      }
    }
    expectations.push_back(ReceiveExpectation{*signal, *equals, startNs, path});
    return static_cast<std::int32_t>(expectations.size() - 1);
  }

  /// The configuration's catalog, built on first use (expectedWhen names a table key).
  const signals::Catalog* catalog(const std::string& path) {
    if (!m_catalog) {
      auto built = config::buildCatalog(m_vehicle);
      if (!built) {
        m_check.error(path, "cannot check the signal: " + built.error().message);
        return nullptr;
      }
      m_catalog.emplace(std::move(*built));
    }
    return &*m_catalog;
  }

  void safety(const config::Json& root) {
    const config::Json* list = m_check.array(root, "", "safety", false);
    if (!list) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = config::JsonChecker::join("/safety", i);
      const config::Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"message", "maxDelayMs", "headerCycleMs", "comment"});
      const auto name = m_check.string(item, path, "message");
      const auto delay = m_check.number(item, path, "maxDelayMs");
      const auto cycle = m_check.number(item, path, "headerCycleMs");
      if (!name || !delay || !cycle) continue;
      const auto index = message(*name, path + "/message");
      if (!index) continue;
      const dbc::Message& sdm = m_vehicle.database.messages[*index];
      if (!sdm.extended || sdm.length != 8) {
        m_check.error(path + "/message",
                      "a J1939-76 safety data message is an 8-byte 29-bit frame; '" + *name + "' is not");
        continue;
      }
      if (config::sentBy(sdm, m_vehicle.node)) {
        m_check.error(path + "/message", "'" + *name + "' is sent by this node; can-rx checks groups other nodes send");
        continue;
      }
      if (!(*delay > 0 && *delay <= 10'000)) {
        m_check.error(path + "/maxDelayMs", "must be above 0 and at most 10000");
        continue;
      }
      if (!(*cycle > 0 && *cycle <= 60'000)) {
        m_check.error(path + "/headerCycleMs", "must be above 0 and at most 60000");
        continue;
      }
      for (const SafetyGroup& existing : m_config.safety) {
        if (existing.dataMessage == *index) m_check.error(path + "/message", "'" + *name + "' is listed twice");
      }
      m_config.safety.push_back(
          SafetyGroup{*index, static_cast<std::int64_t>(*delay * 1e6), static_cast<std::int64_t>(*cycle * 1e6)});
    }
  }

  void forward(const config::Json& root) {
    const config::Json* list = m_check.array(root, "", "forward", false);
    if (!list) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = config::JsonChecker::join("/forward", i);
      const config::Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"from", "to", "id", "pgn", "source", "extended", "rewriteId", "comment"});
      ForwardRule rule;
      const auto from = bus(item, path, "from");
      const auto to = bus(item, path, "to");
      if (!from || !to) continue;
      if (*from == *to) {
        m_check.error(path + "/to", "forwarding a bus to itself would loop");
        continue;
      }
      rule.fromBus = *from;
      rule.toBus = *to;
      const bool hasId = item.contains("id");
      const bool hasPgn = item.contains("pgn");
      if (hasId == hasPgn) {
        m_check.error(path, "give exactly one of \"id\" (one CAN ID) or \"pgn\" (a J1939 PGN)");
        continue;
      }
      const auto value = parseId(item.at(hasId ? "id" : "pgn"));
      if (!value) {
        m_check.error(path + (hasId ? "/id" : "/pgn"), "must be a number or a \"0x...\" text up to 0x1FFFFFFF");
        continue;
      }
      rule.byPgn = hasPgn;
      rule.id = *value;
      if (hasPgn && *value > j1939::PGN_MASK) {
        m_check.error(path + "/pgn", "a PGN has 18 bits (at most 0x3FFFF)");
        continue;
      }
      rule.extended = hasPgn || *value > 0x7FF;
      if (auto extended = m_check.boolean(item, path, "extended", false)) {
        if (hasPgn && !*extended) {
          m_check.error(path + "/extended", "PGN rules match 29-bit frames only");
          continue;
        }
        if (!*extended && *value > 0x7FF) {
          m_check.error(path + "/extended", "an 11-bit ID is at most 0x7FF");
          continue;
        }
        rule.extended = *extended;
      }
      if (item.contains("source")) {
        const auto source = parseId(item.at("source"));
        if (!hasPgn) {
          m_check.error(path + "/source", "\"source\" narrows a \"pgn\" rule; an \"id\" rule already fixes it");
          continue;
        }
        if (!source || *source > 0xFD) {
          m_check.error(path + "/source", "must be a source address from 0 to 0xFD");
          continue;
        }
        rule.source = static_cast<std::uint8_t>(*source);
      }
      if (item.contains("rewriteId")) {
        const auto rewrite = parseId(item.at("rewriteId"));
        if (!rewrite || (!rule.extended && *rewrite > 0x7FF)) {
          m_check.error(path + "/rewriteId", rule.extended ? "must be a 29-bit CAN ID" : "must be an 11-bit CAN ID");
          continue;
        }
        rule.rewriteId = *rewrite;
      }
      m_config.forward.push_back(rule);
    }
  }

  const config::VehicleConfig& m_vehicle;
  config::JsonChecker& m_check;
  ReceiveConfig m_config;
  std::optional<signals::Catalog> m_catalog;
};

}  // namespace

ReceiveConfig defaultReceiveConfig(const config::VehicleConfig& vehicle) {
  ReceiveConfig config;
  config.timeoutNs = timeoutsFor(vehicle, config.timeoutFactor);
  config.expectationOf.assign(vehicle.database.messages.size(), ALWAYS_EXPECTED);
  return config;
}

Result<ReceiveConfig> loadReceiveConfig(const config::VehicleConfig& vehicle) {
  if (vehicle.receiveFile.empty()) return defaultReceiveConfig(vehicle);
  auto jsonResult = config::readJsonFile(vehicle.receiveFile);
  if (!jsonResult) return jsonResult.error();
  config::JsonChecker check(vehicle.receiveFile);
  Loader loader(vehicle, check);
  loader.run(*jsonResult);
  if (!check.ok()) return check.firstError();
  return std::move(loader.config());
}

}  // namespace openvcu::config
