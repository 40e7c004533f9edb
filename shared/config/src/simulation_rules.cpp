// The generic model's keys of simulation.json -> SimRules (simulation_rules.hpp): signal
// keys resolved against the configured buses' DBC messages, value names against the
// signals' value tables, durations to nanoseconds; every problem named by its JSON path.

#include "simulation_rules_loader.hpp"

#include <cmath>
#include <unordered_map>

#include "openvcu/can/frame.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/core/text.hpp"

namespace openvcu::config {
namespace {

constexpr int MAX_DEPTH = 32;
constexpr std::string_view SILENT_PREFIX = "silent.";

std::optional<SimCompareOp> parseOp(std::string_view name) {
  if (name == "eq") return SimCompareOp::Eq;
  if (name == "ne" || name == "neq") return SimCompareOp::Ne;
  if (name == "lt") return SimCompareOp::Lt;
  if (name == "gt") return SimCompareOp::Gt;
  if (name == "le") return SimCompareOp::Le;
  if (name == "ge") return SimCompareOp::Ge;
  if (name == "in") return SimCompareOp::In;
  return std::nullopt;
}

bool isOperatorKey(std::string_view key) { return parseOp(key).has_value() || key == "quality" || key == "ageGt"; }

std::string inQuotes(std::string_view text) { return "'" + std::string(text) + "'"; }

class RulesLoader {
 public:
  RulesLoader(JsonChecker& check, const VehicleConfig& vehicle, bool hasSafety, SimRules& out)
      : m_check(check), m_vehicle(vehicle), m_hasSafety(hasSafety), m_out(out) {
    // Every decodable signal of every message on a configured bus, by its catalog key.
    for (const BusConfig& bus : vehicle.buses) {
      for (const std::size_t index : bus.messages) {
        const dbc::Message& message = vehicle.database.messages[index];
        if (message.pseudo || message.length > can::MAX_DATA_LENGTH) continue;
        for (std::uint32_t s = 0; s < message.signals.size(); ++s) {
          if (!message.signals[s].decodable()) continue;
          std::string key = signalKey(message, message.signals[s]);
          if (m_keys.contains(key)) continue;
          m_keys.emplace(key, Known{index, s});
          m_keyNames.push_back(std::move(key));
        }
      }
    }
  }

  void run(const Json& root) {
    if (const Json* rules = m_check.array(root, "", "rules", false)) {
      for (std::size_t i = 0; i < rules->size(); ++i) rule((*rules)[i], JsonChecker::join("/rules", i));
    }
    if (const Json* follows = m_check.array(root, "", "follow", false)) {
      for (std::size_t i = 0; i < follows->size(); ++i) follow((*follows)[i], JsonChecker::join("/follow", i));
    }
    if (const Json* integrates = m_check.array(root, "", "integrate", false)) {
      for (std::size_t i = 0; i < integrates->size(); ++i) {
        integrate((*integrates)[i], JsonChecker::join("/integrate", i));
      }
    }
    if (const Json* faults = m_check.member(root, "", "faults", false); faults && m_check.isObject(*faults, "/faults")) {
      for (const auto& item : faults->items()) fault(item.key(), item.value(), JsonChecker::join("/faults", item.key()));
    }
  }

 private:
  struct Known {
    std::size_t message;
    std::uint32_t signal;
  };

  // ---- signals and values ----------------------------------------------------------------

  /// The slot of `key` in m_out.signals (added once); `settable`: it must be a simulated node's.
  std::optional<std::uint32_t> signal(const std::string& key, const std::string& path, bool settable) {
    const auto existing = m_slots.find(key);
    std::uint32_t slot = 0;
    if (existing != m_slots.end()) {
      slot = existing->second;
    } else {
      SimSignal resolved;
      resolved.key = key;
      resolved.path = path;
      if (key == SIM_SAFETY_OK_KEY) {
        if (!m_hasSafety) {
          m_check.error(path, std::string(SIM_SAFETY_OK_KEY) + " needs a \"safety\" list (no pairs are checked)");
          return std::nullopt;
        }
        resolved.kind = SimSignal::Kind::SafetyOk;
      } else {
        const auto found = m_keys.find(key);
        if (found == m_keys.end()) {
          std::string message = "no bus signal " + inQuotes(key) + " (keys are Transmitter.Message.Signal)";
          if (const auto suggestion = text::didYouMean(key, m_keyNames)) {
            message += "; did you mean " + inQuotes(*suggestion) + "?";
          }
          m_check.error(path, std::move(message));
          return std::nullopt;
        }
        resolved.message = found->second.message;
        resolved.signal = found->second.signal;
        const bool vcu = sentBy(m_vehicle.database.messages[resolved.message], m_vehicle.node);
        resolved.kind = vcu ? SimSignal::Kind::Vcu : SimSignal::Kind::Node;
      }
      slot = static_cast<std::uint32_t>(m_out.signals.size());
      m_out.signals.push_back(std::move(resolved));
      m_slots.emplace(key, slot);
    }
    if (settable && m_out.signals[slot].kind != SimSignal::Kind::Node) {
      m_check.error(path, inQuotes(key) + (m_out.signals[slot].kind == SimSignal::Kind::Vcu
                                             ? " is sent by the VCU (" + m_vehicle.node + "): the simulator sets only the other nodes' signals"
                                             : " is read-only"));
      return std::nullopt;
    }
    return slot;
  }

  const dbc::Signal* dbcSignal(std::uint32_t slot) const {
    const SimSignal& resolved = m_out.signals[slot];
    if (resolved.kind == SimSignal::Kind::SafetyOk) return nullptr;
    return &m_vehicle.database.messages[resolved.message].signals[resolved.signal];
  }

  /// A number, true/false, or a name from the signal's value table.
  std::optional<double> value(std::uint32_t slot, const Json& json, const std::string& path) {
    if (json.is_boolean()) return json.get<bool>() ? 1.0 : 0.0;
    if (json.is_number()) {
      const double number = json.get<double>();
      if (std::isfinite(number)) return number;
    }
    const dbc::Signal* info = dbcSignal(slot);
    const std::string& key = m_out.signals[slot].key;
    if (json.is_string()) {
      const std::string name = json.get<std::string>();
      std::vector<std::string> names;
      if (info != nullptr) {
        for (const dbc::ValueDescription& described : info->valueDescriptions) {
          if (described.text == name) return static_cast<double>(described.value);
          names.push_back(described.text);
        }
      }
      std::string message = inQuotes(name) + " is not a value of " + key;
      if (names.empty()) {
        message += " (it has no value table: use a number)";
      } else if (const auto suggestion = text::didYouMean(name, names)) {
        message += " (did you mean " + inQuotes(*suggestion) + "?)";
      }
      m_check.error(path, std::move(message));
      return std::nullopt;
    }
    m_check.error(path, "must be a number, true/false or a value name of " + key);
    return std::nullopt;
  }

  /// `value` must lie in the signal's DBC range when it has one (`what` says why).
  bool inRange(std::uint32_t slot, double number, const std::string& path, const char* what) {
    const dbc::Signal* info = dbcSignal(slot);
    if (info == nullptr || !(info->minimum < info->maximum)) return true;
    if (number >= info->minimum && number <= info->maximum) return true;
    m_check.error(path, formatNumber(number) + " is outside " + m_out.signals[slot].key + "'s range [" +
                            formatNumber(info->minimum) + ", " + formatNumber(info->maximum) + "]" + what);
    return false;
  }

  std::optional<std::int64_t> duration(const Json& object, const std::string& path, std::string_view key) {
    const Json* json = m_check.member(object, path, key, false);
    if (json == nullptr) return std::nullopt;
    const auto ns = json->is_string() ? parseDurationNs(json->get<std::string>()) : std::nullopt;
    if (!ns) m_check.error(JsonChecker::join(path, key), "expected " + std::string(DURATION_FORM));
    return ns;
  }

  /// {"K": V, ...}: values for simulated nodes' signals ("comment" skipped).
  std::vector<SimAssignment> assignments(const Json& json, const std::string& path) {
    std::vector<SimAssignment> result;
    if (!m_check.isObject(json, path)) return result;
    for (const auto& item : json.items()) {
      if (item.key() == "comment") continue;
      const std::string itemPath = JsonChecker::join(path, item.key());
      const auto slot = signal(item.key(), itemPath, true);
      if (!slot) continue;
      const auto number = value(*slot, item.value(), itemPath);
      if (!number || !inRange(*slot, *number, itemPath, "")) continue;
      result.push_back(SimAssignment{*slot, *number});
    }
    return result;
  }

  // ---- conditions (the shape of fsm.json's) ----------------------------------------------

  std::uint32_t addNode(const SimConditionNode& node) {
    m_out.nodes.push_back(node);
    return static_cast<std::uint32_t>(m_out.nodes.size() - 1);
  }

  std::uint32_t group(SimNodeKind kind, const std::vector<std::uint32_t>& children) {
    SimConditionNode node;
    node.kind = kind;
    node.first = static_cast<std::uint32_t>(m_out.children.size());
    node.count = static_cast<std::uint32_t>(children.size());
    m_out.children.insert(m_out.children.end(), children.begin(), children.end());
    return addNode(node);
  }

  std::uint32_t condition(const Json& json, const std::string& path, int depth) {
    if (!json.is_object()) {
      m_check.error(path, "a condition must be an object ({\"key\": K, \"eq\": V}, {\"all\": [...]}, ...)");
      return SIM_NONE;
    }
    if (depth > MAX_DEPTH) {
      m_check.error(path, "conditions nested deeper than " + std::to_string(MAX_DEPTH));
      return SIM_NONE;
    }
    const std::int64_t forNs = duration(json, path, "for").value_or(0);
    const int groups = static_cast<int>(json.contains("all")) + static_cast<int>(json.contains("any")) +
                       static_cast<int>(json.contains("not"));
    std::uint32_t node = SIM_NONE;
    if (groups > 1) {
      m_check.error(path, "one of all, any and not per object (nest them instead)");
      return SIM_NONE;
    }
    if (groups == 1) {
      node = groupCondition(json, path, depth);
    } else if (json.contains("key")) {
      node = leaf(json, path);
    } else {
      for (const auto& item : json.items()) {
        if (isOperatorKey(item.key())) {
          m_check.error(path, "a comparison needs \"key\" (the signal to compare)");
          return SIM_NONE;
        }
      }
      node = flat(json, path);
    }
    if (node != SIM_NONE && forNs > 0) {
      m_out.nodes[node].forNs = forNs;
      m_out.nodes[node].timer = m_out.timerCount++;
    }
    return node;
  }

  std::uint32_t groupCondition(const Json& json, const std::string& path, int depth) {
    if (json.contains("not")) {
      m_check.onlyKeys(json, path, {"not", "for", "comment"});
      const std::uint32_t child = condition(json["not"], JsonChecker::join(path, "not"), depth + 1);
      return child == SIM_NONE ? SIM_NONE : group(SimNodeKind::Not, {child});
    }
    const bool all = json.contains("all");
    const std::string_view key = all ? "all" : "any";
    m_check.onlyKeys(json, path, {key, "for", "comment"});
    const Json& list = json[std::string(key)];
    const std::string listPath = JsonChecker::join(path, key);
    if (!list.is_array()) {
      m_check.error(listPath, "must be a list of conditions");
      return SIM_NONE;
    }
    std::vector<std::uint32_t> children;
    bool failed = false;
    for (std::size_t c = 0; c < list.size(); ++c) {
      const std::uint32_t child = condition(list[c], JsonChecker::join(listPath, c), depth + 1);
      failed = failed || child == SIM_NONE;
      children.push_back(child);
    }
    return failed ? SIM_NONE : group(all ? SimNodeKind::All : SimNodeKind::Any, children);
  }

  std::uint32_t leaf(const Json& json, const std::string& path) {
    if (json.contains("quality") || json.contains("ageGt")) {
      m_check.error(path, "quality and ageGt are fsm.json's only: the simulator compares values (eq, ne, lt, gt, le, ge, in)");
      return SIM_NONE;
    }
    m_check.onlyKeys(json, path, {"key", "eq", "ne", "neq", "lt", "gt", "le", "ge", "in", "for", "comment"});
    const auto key = m_check.string(json, path, "key");
    if (!key) return SIM_NONE;
    const auto slot = signal(*key, JsonChecker::join(path, "key"), false);
    if (!slot) return SIM_NONE;
    std::vector<std::uint32_t> leaves;
    bool failed = false;
    for (const auto& item : json.items()) {
      const auto op = parseOp(item.key());
      if (!op) continue;
      const std::uint32_t compared = compare(*slot, *op, item.value(), JsonChecker::join(path, item.key()));
      failed = failed || compared == SIM_NONE;
      leaves.push_back(compared);
    }
    if (failed) return SIM_NONE;
    if (leaves.empty()) {
      m_check.error(path, "no operator: use one of eq, ne, lt, gt, le, ge, in");
      return SIM_NONE;
    }
    return leaves.size() == 1 ? leaves.front() : group(SimNodeKind::All, leaves);
  }

  /// The thesis' flat form {"K1": v1, "K2": v2}: every key equal to its value; {} is always true.
  std::uint32_t flat(const Json& json, const std::string& path) {
    std::vector<std::uint32_t> leaves;
    bool failed = false;
    for (const auto& item : json.items()) {
      if (item.key() == "for" || item.key() == "comment") continue;
      const std::string itemPath = JsonChecker::join(path, item.key());
      const auto slot = signal(item.key(), itemPath, false);
      const std::uint32_t compared = slot ? compare(*slot, SimCompareOp::Eq, item.value(), itemPath) : SIM_NONE;
      failed = failed || compared == SIM_NONE;
      leaves.push_back(compared);
    }
    if (failed) return SIM_NONE;
    if (leaves.empty()) return addNode(SimConditionNode{});
    return leaves.size() == 1 ? leaves.front() : group(SimNodeKind::All, leaves);
  }

  std::uint32_t compare(std::uint32_t slot, SimCompareOp op, const Json& json, const std::string& path) {
    SimConditionNode node;
    node.kind = SimNodeKind::Compare;
    node.op = op;
    node.signal = slot;
    if (op != SimCompareOp::In) {
      const auto constant = value(slot, json, path);
      if (!constant) return SIM_NONE;
      if (op == SimCompareOp::Eq && !inRange(slot, *constant, path, ": never equal")) return SIM_NONE;
      node.value = *constant;
      return addNode(node);
    }
    if (!json.is_array() || json.empty()) {
      m_check.error(path, "in: must be a non-empty list of values");
      return SIM_NONE;
    }
    node.first = static_cast<std::uint32_t>(m_out.constants.size());
    node.count = static_cast<std::uint32_t>(json.size());
    for (std::size_t v = 0; v < json.size(); ++v) {
      const std::string itemPath = JsonChecker::join(path, v);
      const auto constant = value(slot, json[v], itemPath);
      if (!constant || !inRange(slot, *constant, itemPath, ": never equal")) return SIM_NONE;
      m_out.constants.push_back(*constant);
    }
    return addNode(node);
  }

  /// An optional "when" member: its root node, SIM_NONE when absent (always); false on an error.
  bool optionalCondition(const Json& object, const std::string& path, std::uint32_t& root) {
    root = SIM_NONE;
    const Json* when = m_check.member(object, path, "when", false);
    if (when == nullptr) return true;
    root = condition(*when, JsonChecker::join(path, "when"), 0);
    return root != SIM_NONE;
  }

  // ---- the sections ----------------------------------------------------------------------

  void rule(const Json& json, const std::string& path) {
    if (!m_check.isObject(json, path)) return;
    m_check.onlyKeys(json, path, {"when", "after", "set", "otherwise", "comment"});
    SimRule entry;
    entry.path = path;
    if (!optionalCondition(json, path, entry.when)) return;
    entry.afterNs = duration(json, path, "after").value_or(0);
    const Json* set = m_check.member(json, path, "set", true);
    if (set != nullptr) entry.set = assignments(*set, JsonChecker::join(path, "set"));
    if (const Json* otherwise = m_check.member(json, path, "otherwise", false)) {
      entry.otherwise = assignments(*otherwise, JsonChecker::join(path, "otherwise"));
    }
    m_out.rules.push_back(std::move(entry));
  }

  void follow(const Json& json, const std::string& path) {
    if (!m_check.isObject(json, path)) return;
    m_check.onlyKeys(json, path, {"signal", "target", "timeConstant", "when", "comment"});
    SimFollow entry;
    entry.path = path;
    const auto key = m_check.string(json, path, "signal");
    const auto slot = key ? signal(*key, JsonChecker::join(path, "signal"), true) : std::nullopt;
    if (!slot) return;
    entry.signal = *slot;
    if (const Json* target = m_check.member(json, path, "target", true)) {
      const std::string targetPath = JsonChecker::join(path, "target");
      if (target->is_string()) {
        const auto targetSlot = signal(target->get<std::string>(), targetPath, false);
        if (!targetSlot) return;
        entry.target = *targetSlot;
      } else if (target->is_number() && std::isfinite(target->get<double>())) {
        entry.targetValue = target->get<double>();
      } else {
        m_check.error(targetPath, "must be a signal key or a number");
        return;
      }
    }
    const auto timeConstant = duration(json, path, "timeConstant");
    if (!timeConstant) {
      if (!json.contains("timeConstant")) m_check.error(JsonChecker::join(path, "timeConstant"), "missing");
      return;
    }
    if (*timeConstant <= 0) {
      m_check.error(JsonChecker::join(path, "timeConstant"), "must be longer than 0s");
      return;
    }
    entry.timeConstantNs = *timeConstant;
    if (!optionalCondition(json, path, entry.when)) return;
    m_out.follow.push_back(std::move(entry));
  }

  void integrate(const Json& json, const std::string& path) {
    if (!m_check.isObject(json, path)) return;
    m_check.onlyKeys(json, path, {"signal", "rate", "min", "max", "comment"});
    SimIntegrate entry;
    entry.path = path;
    const auto key = m_check.string(json, path, "signal");
    const auto slot = key ? signal(*key, JsonChecker::join(path, "signal"), true) : std::nullopt;
    if (!slot) return;
    entry.signal = *slot;
    const Json* rate = m_check.member(json, path, "rate", true);
    if (rate == nullptr) return;
    const std::string ratePath = JsonChecker::join(path, "rate");
    if (rate->is_object()) {
      m_check.onlyKeys(*rate, ratePath, {"signal", "factor", "comment"});
      const auto rateKey = m_check.string(*rate, ratePath, "signal");
      const auto rateSlot = rateKey ? signal(*rateKey, JsonChecker::join(ratePath, "signal"), false) : std::nullopt;
      if (!rateSlot) return;
      entry.rateSignal = *rateSlot;
      entry.factor = m_check.number(*rate, ratePath, "factor", false).value_or(1.0);
    } else if (rate->is_number() && std::isfinite(rate->get<double>())) {
      entry.factor = rate->get<double>();
    } else {
      m_check.error(ratePath, "must be a number (per second) or {\"signal\": K, \"factor\": F}");
      return;
    }
    // the signal's DBC range by default: the integral never winds up beyond what is sent
    const dbc::Signal* info = dbcSignal(entry.signal);
    if (info != nullptr && info->minimum < info->maximum) {
      entry.minimum = info->minimum;
      entry.maximum = info->maximum;
    }
    if (const auto minimum = m_check.number(json, path, "min", false)) entry.minimum = *minimum;
    if (const auto maximum = m_check.number(json, path, "max", false)) entry.maximum = *maximum;
    if (!(entry.minimum <= entry.maximum)) {
      m_check.error(JsonChecker::join(path, "min"), "must not be above max");
      return;
    }
    m_out.integrate.push_back(std::move(entry));
  }

  void fault(const std::string& name, const Json& json, const std::string& path) {
    if (name == "comment") return;
    if (name.empty() || name.starts_with(SILENT_PREFIX) ||
        name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != std::string::npos) {
      m_check.error(path, "a fault name is letters, digits, _ and - (silent.<NODE> is built in)");
      return;
    }
    if (!m_check.isObject(json, path)) return;
    m_check.onlyKeys(json, path, {"set", "comment"});
    SimFault entry;
    entry.name = name;
    entry.path = path;
    if (const Json* set = m_check.member(json, path, "set", true)) entry.set = assignments(*set, JsonChecker::join(path, "set"));
    m_out.faults.push_back(std::move(entry));
  }

  JsonChecker& m_check;
  const VehicleConfig& m_vehicle;
  bool m_hasSafety;
  SimRules& m_out;
  std::unordered_map<std::string, Known> m_keys;
  std::vector<std::string> m_keyNames;
  std::unordered_map<std::string, std::uint32_t> m_slots;
};

}  // namespace

void loadSimRules(const Json& root, JsonChecker& check, const VehicleConfig& vehicle, bool hasSafety, SimRules& out) {
  RulesLoader loader(check, vehicle, hasSafety, out);
  loader.run(root);
}

}  // namespace openvcu::config
