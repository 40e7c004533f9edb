// Loading an FSM file: JSON -> Machine, every key resolved and every value checked. The
// whole-machine analyses (reachability, contradictions, shadowed transitions) are in
// machine_checks.cpp.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "machine_checks.hpp"
#include "machine_cycles.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::fsm {
namespace {

using config::Json;
using config::JsonChecker;

constexpr int MAX_DEPTH = 32;
constexpr std::string_view OPERATORS[] = {"eq", "ne", "neq", "lt", "gt", "le", "ge", "in"};
/// Internal signals the stack reports; a machine may read them but never command them.
std::string inQuotes(std::string_view text) {
  std::string result = "'";
  result += text;
  result += '\'';
  return result;
}

using text::number;

std::optional<CompareOp> parseOp(std::string_view name) {
  if (name == "eq") return CompareOp::Eq;
  if (name == "ne" || name == "neq") return CompareOp::Ne;
  if (name == "lt") return CompareOp::Lt;
  if (name == "gt") return CompareOp::Gt;
  if (name == "le") return CompareOp::Le;
  if (name == "ge") return CompareOp::Ge;
  if (name == "in") return CompareOp::In;
  return std::nullopt;
}

bool isOperatorKey(std::string_view key) {
  return std::find(std::begin(OPERATORS), std::end(OPERATORS), key) != std::end(OPERATORS) || key == "quality" ||
         key == "ageGt";
}

std::optional<signals::Quality> parseQuality(std::string_view name) {
  if (name == "valid") return signals::Quality::Valid;
  if (name == "stale") return signals::Quality::Stale;
  if (name == "neverReceived") return signals::Quality::NeverReceived;
  if (name == "outOfRange") return signals::Quality::OutOfRange;
  return std::nullopt;
}

class Loader {
 public:
  Loader(JsonChecker& check, const config::VehicleConfig& vehicle, const signals::Catalog& catalog)
      : m_check(check), m_vehicle(vehicle), m_catalog(catalog) {
  }

  void load(const Json& root) {
    if (!m_check.isObject(root, "")) return;
    m_check.onlyKeys(root, "", {"initialState", "states", "comment"});
    const auto initial = m_check.string(root, "", "initialState");
    const Json* states = m_check.array(root, "", "states");
    if (states != nullptr) {
      for (std::size_t s = 0; s < states->size(); ++s) declareState((*states)[s], JsonChecker::join("/states", s));
      for (std::size_t s = 0; s < states->size() && s < m_machine.states.size(); ++s) {
        loadState((*states)[s], JsonChecker::join("/states", s), m_machine.states[s]);
      }
      if (states->empty()) m_check.error("/states", "no states");
    }
    if (initial) {
      if (const auto index = resolveState(*initial, "/initialState", "initial state")) m_machine.initial = *index;
      m_initialDefined = m_stateIndex.contains(*initial);
    }
    m_machine.hash = std::hash<std::string>{}(root.dump()) & 0xFFFF'FFFF'FFFFULL;
  }

  Machine take() { return std::move(m_machine); }
  [[nodiscard]] bool initialDefined() const noexcept { return m_initialDefined; }
  [[nodiscard]] const std::vector<std::string>& targetPaths() const noexcept { return m_targetPaths; }

 private:
  void declareState(const Json& state, const std::string& path) {
    State& declared = m_machine.states.emplace_back();
    if (!m_check.isObject(state, path)) return;
    const auto name = m_check.string(state, path, "name");
    if (!name) return;
    if (name->empty()) m_check.error(JsonChecker::join(path, "name"), "empty state name");
    // A hashed index: linear searches here and in resolveState made 100,000 states take
    // 107 s to check.
    const auto index = static_cast<std::uint32_t>(m_machine.states.size() - 1);
    if (const auto [where, fresh] = m_stateIndex.emplace(*name, index); !fresh) {
      m_check.error(JsonChecker::join(path, "name"),
                    "state " + inQuotes(*name) + " is defined twice (also /states/" + std::to_string(where->second) + ")");
    }
    declared.name = *name;
  }

  void loadState(const Json& json, const std::string& path, State& state) {
    if (!json.is_object()) return;
    m_check.onlyKeys(json, path, {"name", "transitions", "entry", "exit", "comment"});
    state.entry = actions(json, path, "entry");
    state.exit = actions(json, path, "exit");
    if (const Json* transitions = m_check.array(json, path, "transitions", false)) {
      for (std::size_t t = 0; t < transitions->size(); ++t) {
        const std::string transitionPath = JsonChecker::join(JsonChecker::join(path, "transitions"), t);
        if (auto transition = loadTransition((*transitions)[t], transitionPath)) {
          state.transitions.push_back(std::move(*transition));
        }
      }
    }
  }

  std::optional<Transition> loadTransition(const Json& json, const std::string& path) {
    if (!m_check.isObject(json, path)) return std::nullopt;
    m_check.onlyKeys(json, path, {"condition", "actions", "nextState", "after", "comment"});
    Transition transition;
    transition.path = path;
    const Json* condition = m_check.member(json, path, "condition", false);
    const Json* after = m_check.member(json, path, "after", false);
    if (after != nullptr) {
      if (auto ns = duration(*after, JsonChecker::join(path, "after"))) transition.afterNs = *ns;
    }
    if (condition != nullptr) {
      transition.condition = parseCondition(*condition, JsonChecker::join(path, "condition"), 0);
      transition.broken = transition.condition == NONE;
    } else if (after == nullptr) {
      m_check.error(JsonChecker::join(path, "condition"), "missing: a transition needs a condition or an after");
    }
    transition.actions = actions(json, path, "actions");
    const auto next = m_check.string(json, path, "nextState");
    m_targetPaths.push_back(JsonChecker::join(path, "nextState"));
    if (next) {
      const auto index = resolveState(*next, JsonChecker::join(path, "nextState"), "next state");
      transition.target = index.value_or(NONE);
    } else {
      transition.target = NONE;
    }
    return transition;
  }

  std::optional<std::uint32_t> resolveState(const std::string& name, const std::string& path, std::string_view what) {
    if (const auto found = m_stateIndex.find(name); found != m_stateIndex.end()) return found->second;
    std::vector<std::string> names;
    std::optional<std::string> suggestion;
    for (const State& state : m_machine.states) {
      names.push_back(state.name);
      const bool sameLetters = std::equal(name.begin(), name.end(), state.name.begin(), state.name.end(),
                                          [](unsigned char a, unsigned char b) { return std::tolower(a) == std::tolower(b); });
      if (sameLetters && !suggestion) suggestion = state.name;
    }
    if (!suggestion) suggestion = text::didYouMean(name, names);
    std::string message = std::string(what) + " " + inQuotes(name) + " is not defined";
    if (suggestion) message += " (did you mean " + inQuotes(*suggestion) + "?)";
    m_check.error(path, std::move(message));
    return std::nullopt;
  }

  // ---- conditions ---------------------------------------------------------------------

  std::uint32_t addNode(ConditionNode node) {
    m_machine.nodes.push_back(std::move(node));
    return static_cast<std::uint32_t>(m_machine.nodes.size() - 1);
  }

  std::uint32_t group(NodeKind kind, const std::vector<std::uint32_t>& children, const std::string& path) {
    ConditionNode node;
    node.kind = kind;
    node.first = static_cast<std::uint32_t>(m_machine.children.size());
    node.count = static_cast<std::uint32_t>(children.size());
    node.path = path;
    m_machine.children.insert(m_machine.children.end(), children.begin(), children.end());
    return addNode(std::move(node));
  }

  std::uint32_t parseCondition(const Json& json, const std::string& path, int depth) {
    if (!json.is_object()) {
      m_check.error(path, "a condition must be an object ({\"key\": K, \"eq\": V}, {\"all\": [...]}, ...)");
      return NONE;
    }
    if (depth > MAX_DEPTH) {
      m_check.error(path, "conditions nested deeper than " + std::to_string(MAX_DEPTH));
      return NONE;
    }
    std::int64_t forNs = 0;
    if (const auto it = json.find("for"); it != json.end()) {
      forNs = duration(*it, JsonChecker::join(path, "for")).value_or(0);
    }
    std::uint32_t node = NONE;
    const int groups = static_cast<int>(json.contains("all")) + static_cast<int>(json.contains("any")) +
                       static_cast<int>(json.contains("not"));
    if (groups > 1) {
      m_check.error(path, "one of all, any and not per object (nest them instead)");
      return NONE;
    }
    if (groups == 1) {
      node = parseGroup(json, path, depth);
    } else if (json.contains("key")) {
      node = parseLeaf(json, path);
    } else {
      bool hasOperator = false;
      for (const auto& item : json.items()) hasOperator = hasOperator || isOperatorKey(item.key());
      if (hasOperator) {
        m_check.error(path, "a comparison needs \"key\" (the signal to compare)");
        return NONE;
      }
      node = parseFlat(json, path);
    }
    if (node != NONE && forNs > 0) {
      // every node returned here was made for this object (path == `path`), so `for` is its own
      m_machine.nodes[node].forNs = forNs;
      m_machine.nodes[node].timer = m_machine.timerCount++;
    }
    return node;
  }

  std::uint32_t parseGroup(const Json& json, const std::string& path, int depth) {
    if (json.contains("not")) {
      m_check.onlyKeys(json, path, {"not", "for", "comment"});
      const std::uint32_t child = parseCondition(json["not"], JsonChecker::join(path, "not"), depth + 1);
      if (child == NONE) return NONE;
      ConditionNode node;
      node.kind = NodeKind::Not;
      node.first = static_cast<std::uint32_t>(m_machine.children.size());
      node.count = 1;
      node.path = path;
      m_machine.children.push_back(child);
      return addNode(std::move(node));
    }
    const bool all = json.contains("all");
    const std::string_view key = all ? "all" : "any";
    m_check.onlyKeys(json, path, {key, "for", "comment"});
    const Json& list = json[std::string(key)];
    const std::string listPath = JsonChecker::join(path, key);
    if (!list.is_array()) {
      m_check.error(listPath, "must be a list of conditions");
      return NONE;
    }
    if (list.empty()) {
      m_check.warning(listPath, all ? "empty all: always true" : "empty any: never true");
    }
    std::vector<std::uint32_t> children;
    bool failed = false;
    for (std::size_t c = 0; c < list.size(); ++c) {
      const std::uint32_t child = parseCondition(list[c], JsonChecker::join(listPath, c), depth + 1);
      failed = failed || child == NONE;
      children.push_back(child);
    }
    if (failed) return NONE;
    ConditionNode node;
    node.kind = all ? NodeKind::All : NodeKind::Any;
    node.first = static_cast<std::uint32_t>(m_machine.children.size());
    node.count = static_cast<std::uint32_t>(children.size());
    node.path = path;
    m_machine.children.insert(m_machine.children.end(), children.begin(), children.end());
    const std::uint32_t index = addNode(std::move(node));
    checkSiblings(m_check, m_machine, m_catalog, index, listPath);
    return index;
  }

  std::uint32_t parseLeaf(const Json& json, const std::string& path) {
    m_check.onlyKeys(json, path, {"key", "eq", "ne", "neq", "lt", "gt", "le", "ge", "in", "quality", "ageGt", "for",
                                  "comment"});
    const auto key = m_check.string(json, path, "key");
    if (!key) return NONE;
    const auto signal = readSignal(*key, JsonChecker::join(path, "key"));
    std::vector<std::uint32_t> leaves;
    bool failed = !signal.has_value();
    for (const auto& item : json.items()) {
      const std::string itemPath = JsonChecker::join(path, item.key());
      if (const auto op = parseOp(item.key())) {
        if (!signal) continue;
        const std::uint32_t leaf = compareLeaf(*signal, *op, item.value(), itemPath, path);
        failed = failed || leaf == NONE;
        leaves.push_back(leaf);
      } else if (item.key() == "quality") {
        if (!signal) continue;
        const std::uint32_t leaf = qualityLeaf(*signal, item.value(), itemPath, path);
        failed = failed || leaf == NONE;
        leaves.push_back(leaf);
      } else if (item.key() == "ageGt") {
        const auto ns = duration(item.value(), itemPath);
        if (!signal || !ns) {
          failed = true;
          continue;
        }
        ConditionNode node;
        node.kind = NodeKind::Age;
        node.signal = *signal;
        node.durationNs = *ns;
        node.path = path;
        leaves.push_back(addNode(std::move(node)));
      }
    }
    if (failed) return NONE;
    if (leaves.empty()) {
      m_check.error(path, "no operator: use one of eq, ne, lt, gt, le, ge, in, quality, ageGt");
      return NONE;
    }
    if (leaves.size() == 1) return leaves.front();
    const std::uint32_t index = group(NodeKind::All, leaves, path);
    checkSiblings(m_check, m_machine, m_catalog, index, path);
    return index;
  }

  /// The thesis' flat form {"K1": v1, "K2": v2}: every key equal to its value.
  std::uint32_t parseFlat(const Json& json, const std::string& path) {
    std::vector<std::uint32_t> leaves;
    bool failed = false;
    for (const auto& item : json.items()) {
      if (item.key() == "for" || item.key() == "comment") continue;
      const std::string itemPath = JsonChecker::join(path, item.key());
      const auto signal = readSignal(item.key(), itemPath);
      if (!signal) {
        failed = true;
        continue;
      }
      const std::uint32_t leaf = compareLeaf(*signal, CompareOp::Eq, item.value(), itemPath, path);
      failed = failed || leaf == NONE;
      leaves.push_back(leaf);
    }
    if (failed) return NONE;
    if (leaves.empty()) {
      m_check.warning(path, "empty condition {}: always true");
      ConditionNode node;
      node.kind = NodeKind::True;
      node.path = path;
      return addNode(std::move(node));
    }
    if (leaves.size() == 1) return leaves.front();
    const std::uint32_t index = group(NodeKind::All, leaves, path);
    checkSiblings(m_check, m_machine, m_catalog, index, path);
    return index;
  }

  std::uint32_t compareLeaf(std::uint32_t signal, CompareOp op, const Json& value, const std::string& valuePath,
                            const std::string& nodePath) {
    const signals::SignalInfo& info = m_catalog[m_machine.signals[signal].index];
    ConditionNode node;
    node.kind = NodeKind::Compare;
    node.op = op;
    node.signal = signal;
    node.path = nodePath;
    if (op == CompareOp::In) {
      if (!value.is_array() || value.empty()) {
        m_check.error(valuePath, "in: must be a non-empty list of values");
        return NONE;
      }
      node.first = static_cast<std::uint32_t>(m_machine.constants.size());
      for (std::size_t v = 0; v < value.size(); ++v) {
        const auto constant = signalValue(info, value[v], JsonChecker::join(valuePath, v));
        if (!constant) return NONE;
        checkConditionRange(info, *constant, op, JsonChecker::join(valuePath, v));
        m_machine.constants.push_back(*constant);
      }
      node.count = static_cast<std::uint32_t>(value.size());
      return addNode(std::move(node));
    }
    const auto constant = signalValue(info, value, valuePath);
    if (!constant) return NONE;
    checkConditionRange(info, *constant, op, valuePath);
    node.value = *constant;
    return addNode(std::move(node));
  }

  std::uint32_t qualityLeaf(std::uint32_t signal, const Json& value, const std::string& valuePath,
                            const std::string& nodePath) {
    ConditionNode node;
    node.kind = NodeKind::Quality;
    node.signal = signal;
    node.path = nodePath;
    const auto addOne = [&](const Json& item, const std::string& itemPath) {
      const auto quality = item.is_string() ? parseQuality(item.get<std::string>()) : std::nullopt;
      if (!quality) {
        m_check.error(itemPath, "quality: expected valid, stale, neverReceived or outOfRange");
        return false;
      }
      node.qualityMask = static_cast<std::uint8_t>(node.qualityMask | (1U << static_cast<unsigned>(*quality)));
      return true;
    };
    if (value.is_array()) {
      for (std::size_t q = 0; q < value.size(); ++q) {
        if (!addOne(value[q], JsonChecker::join(valuePath, q))) return NONE;
      }
    } else if (!addOne(value, valuePath)) {
      return NONE;
    }
    return addNode(std::move(node));
  }

  void checkConditionRange(const signals::SignalInfo& info, double value, CompareOp op, const std::string& path) {
    if (!(info.minimum < info.maximum) || (value >= info.minimum && value <= info.maximum)) return;
    const std::string range = "[" + number(info.minimum) + ", " + number(info.maximum) + "]";
    if (op == CompareOp::Eq || op == CompareOp::In) {
      m_check.error(path, number(value) + " is outside " + info.key + "'s range " + range + ": never equal");
    } else {
      m_check.warning(path, number(value) + " is outside " + info.key + "'s range " + range);
    }
  }

  /// The machine's slot for a signal a condition reads (added once).
  std::optional<std::uint32_t> readSignal(const std::string& key, const std::string& path) {
    auto found = m_catalog.find(key);
    if (!found) {
      m_check.error(path, found.error().message);
      return std::nullopt;
    }
    const signals::SignalIndex index = *found;
    if (const auto it = m_slots.find(index); it != m_slots.end()) return it->second;
    const auto slot = static_cast<std::uint32_t>(m_machine.signals.size());
    // What the stack commands (transmitted and internal signals) is read as commanded; what
    // other nodes send, from the bus.
    const bool received = m_catalog[index].direction == signals::SignalDirection::Received;
    SignalRef ref{index, received ? ReadPlane::Bus : ReadPlane::Command, {}};
    for (const config::InternalSignal& declared : m_vehicle.internalSignals) {
      if (key.size() == config::INTERNAL_PREFIX.size() + declared.name.size() && key.ends_with(declared.name) &&
          key.starts_with(config::INTERNAL_PREFIX)) {
        ref.initial = declared.initial;
      }
    }
    m_machine.signals.push_back(ref);
    m_slots.emplace(index, slot);
    return slot;
  }

  std::optional<double> signalValue(const signals::SignalInfo& info, const Json& value, const std::string& path) {
    if (value.is_boolean()) return value.get<bool>() ? 1.0 : 0.0;
    if (value.is_number()) {
      const double number = value.get<double>();
      if (std::isfinite(number)) return number;
    }
    if (value.is_string()) {
      const std::string name = value.get<std::string>();
      std::vector<std::string> names;
      for (const auto& [raw, text] : info.valueTexts) {
        if (text == name) return static_cast<double>(raw);
        names.push_back(text);
      }
      std::string message = inQuotes(name) + " is not a value of " + info.key;
      if (names.empty()) {
        message += " (it has no value table: use a number)";
      } else if (const auto suggestion = text::didYouMean(name, names)) {
        message += " (did you mean " + inQuotes(*suggestion) + "?)";
      }
      m_check.error(path, std::move(message));
      return std::nullopt;
    }
    m_check.error(path, "must be a number, true/false or a value name of " + info.key);
    return std::nullopt;
  }

  std::optional<std::int64_t> duration(const Json& json, const std::string& path) {
    if (!json.is_string()) {
      m_check.error(path, "a duration is a string with a unit: \"500ms\", \"2s\", \"1min\"");
      return std::nullopt;
    }
    const std::string text = json.get<std::string>();
    const std::optional<std::int64_t> ns = config::parseDurationNs(text);
    if (!ns || *ns == 0) {
      m_check.error(path, inQuotes(text) + ": expected a positive duration with a unit: \"500ms\", \"2s\", \"1min\"");
      return std::nullopt;
    }
    return ns;
  }

  // ---- actions ------------------------------------------------------------------------

  std::vector<Action> actions(const Json& json, const std::string& path, std::string_view key) {
    std::vector<Action> result;
    const Json* list = m_check.array(json, path, key, false);
    if (list == nullptr) return result;
    const std::string listPath = JsonChecker::join(path, key);
    for (std::size_t a = 0; a < list->size(); ++a) {
      if (auto action = parseAction((*list)[a], JsonChecker::join(listPath, a))) result.push_back(std::move(*action));
    }
    for (std::size_t a = 0; a < result.size(); ++a) {
      for (std::size_t b = a + 1; b < result.size(); ++b) {
        if (result[a].kind == ActionKind::SetSignal && result[b].kind == ActionKind::SetSignal &&
            result[a].signal == result[b].signal) {
          m_check.warning(JsonChecker::join(listPath, b), m_catalog[result[a].signal].key + " is set twice (also " +
                                                             JsonChecker::join(listPath, a) + "); the last one wins");
        }
      }
    }
    return result;
  }

  std::optional<Action> parseAction(const Json& json, const std::string& path) {
    if (!m_check.isObject(json, path)) return std::nullopt;
    Action action;
    if (json.empty()) {
      m_check.warning(path, "empty action { }: does nothing");
      return action;
    }
    if (json.contains("signal")) {
      m_check.onlyKeys(json, path, {"signal", "value", "from", "comment"});
      const auto key = m_check.string(json, path, "signal");
      if (json.contains("from")) {
        const auto source = m_check.string(json, path, "from");
        if (json.contains("value")) m_check.error(JsonChecker::join(path, "value"), "give \"value\" or \"from\", not both");
        if (!key || !source) return std::nullopt;
        return copySignal(*key, *source, JsonChecker::join(path, "signal"), JsonChecker::join(path, "from"));
      }
      const Json* value = m_check.member(json, path, "value", true);
      if (!key || value == nullptr) return std::nullopt;
      return setSignal(*key, *value, JsonChecker::join(path, "signal"), JsonChecker::join(path, "value"));
    }
    if (json.contains("sendGroup")) {
      m_check.onlyKeys(json, path, {"sendGroup", "on", "comment"});
      const auto name = m_check.string(json, path, "sendGroup");
      const auto on = m_check.boolean(json, path, "on");
      if (!name || !on) return std::nullopt;
      const auto key = sendGroupSignal(*name, JsonChecker::join(path, "sendGroup"));
      if (!key) return std::nullopt;
      return setSignal(*key, Json(*on ? 1 : 0), JsonChecker::join(path, "sendGroup"), JsonChecker::join(path, "on"));
    }
    if (json.contains("raise")) {
      m_check.onlyKeys(json, path, {"raise", "severity", "text", "comment"});
      const auto name = m_check.string(json, path, "raise");
      const auto severity = m_check.string(json, path, "severity", false).value_or("error");
      action.kind = ActionKind::RaiseFault;
      action.text = m_check.string(json, path, "text", false).value_or("");
      if (severity == "info") action.severity = ipc::FaultSeverity::Info;
      else if (severity == "warning") action.severity = ipc::FaultSeverity::Warning;
      else if (severity == "error") action.severity = ipc::FaultSeverity::Error;
      else if (severity == "critical") action.severity = ipc::FaultSeverity::Critical;
      else m_check.error(JsonChecker::join(path, "severity"), "expected info, warning, error or critical");
      if (!name) return std::nullopt;
      if (name->empty()) m_check.error(JsonChecker::join(path, "raise"), "empty fault name");
      action.name = *name;
      return action;
    }
    if (json.contains("clear")) {
      m_check.onlyKeys(json, path, {"clear", "text", "comment"});
      const auto name = m_check.string(json, path, "clear");
      if (!name) return std::nullopt;
      action.kind = ActionKind::ClearFault;
      action.name = *name;
      action.text = m_check.string(json, path, "text", false).value_or("");
      return action;
    }
    if (json.contains("event")) {
      m_check.onlyKeys(json, path, {"event", "comment"});
      const auto text = m_check.string(json, path, "event");
      if (!text) return std::nullopt;
      action.kind = ActionKind::Event;
      action.text = *text;
      return action;
    }
    std::string message = "unknown action: expected {\"signal\": K, \"value\": V}, {\"sendGroup\": G, \"on\": B}, "
                          "{\"raise\": F}, {\"clear\": F} or {\"event\": TEXT}";
    const std::vector<std::string> forms = {"signal", "sendGroup", "raise", "clear", "event"};
    if (!json.items().begin().key().empty()) {
      if (const auto suggestion = text::didYouMean(json.items().begin().key(), forms)) {
        message += " (did you mean " + inQuotes(*suggestion) + "?)";
      }
    }
    m_check.error(path, std::move(message));
    return std::nullopt;
  }

  /// The catalog index of a signal an action may command, or empty (with the error).
  std::optional<signals::SignalIndex> commandable(const std::string& key, const std::string& keyPath) {
    auto found = m_catalog.find(key);
    if (!found) {
      m_check.error(keyPath, found.error().message);
      return std::nullopt;
    }
    // An action commands what vcu-fsm or can-tx owns (shared/config/catalog.hpp): its internal
    // signals, the send groups and the signals this VCU transmits.
    const signals::SignalInfo& info = m_catalog[*found];
    if (info.direction == signals::SignalDirection::Received) {
      m_check.error(keyPath, key + " is not transmitted by " + m_vehicle.node +
                                 ": an action can only command signals this VCU sends or internal signals");
      return std::nullopt;
    }
    if (const config::GpioLine* line = m_vehicle.gpio.inputBoundTo(key)) {
      m_check.error(keyPath, key + " is read from GPIO input line " + line->name + "; an action cannot command it");
      return std::nullopt;
    }
    const bool commandable = info.owner == config::writerOf(config::ServiceId::Fsm) ||
                             info.owner == config::writerOf(config::ServiceId::CanTx);
    if (info.reported || !commandable) {
      m_check.error(keyPath, key + " is a status the stack reports; an action cannot command it");
      return std::nullopt;
    }
    return *found;
  }

  /// {"signal": K, "from": SOURCE}: K commanded with SOURCE's value when the action runs.
  std::optional<Action> copySignal(const std::string& key, const std::string& source, const std::string& keyPath,
                                   const std::string& sourcePath) {
    const auto target = commandable(key, keyPath);
    auto from = m_catalog.find(source);
    if (!from) m_check.error(sourcePath, from.error().message);
    if (!target || !from) return std::nullopt;
    Action action;
    action.kind = ActionKind::SetSignal;
    action.signal = *target;
    action.copy = true;
    action.source = *from;
    return action;
  }

  std::optional<Action> setSignal(const std::string& key, const Json& value, const std::string& keyPath,
                                  const std::string& valuePath) {
    const auto found = commandable(key, keyPath);
    if (!found) return std::nullopt;
    const signals::SignalInfo& info = m_catalog[*found];
    const auto constant = signalValue(info, value, valuePath);
    if (!constant) return std::nullopt;
    if (info.minimum < info.maximum && (*constant < info.minimum || *constant > info.maximum)) {
      m_check.error(valuePath, number(*constant) + " is outside " + key + "'s range [" + number(info.minimum) + ", " +
                                   number(info.maximum) + "]");
      return std::nullopt;
    }
    Action action;
    action.kind = ActionKind::SetSignal;
    action.signal = *found;
    action.value = *constant;
    return action;
  }

  /// The signal of a send group of can-tx's schedule ("groups": {NAME: {"signal": KEY}}).
  std::optional<std::string> sendGroupSignal(const std::string& name, const std::string& path) {
    if (!m_groupsLoaded) {
      m_groupsLoaded = true;
      if (!m_vehicle.scheduleFile.empty()) {
        if (auto schedule = config::readJsonFile(m_vehicle.scheduleFile); schedule && schedule->is_object()) {
          if (const auto groups = schedule->find("groups"); groups != schedule->end() && groups->is_object()) {
            for (const auto& item : groups->items()) {
              if (item.value().is_object() && item.value().contains("signal") && item.value()["signal"].is_string()) {
                m_groups.emplace_back(item.key(), item.value()["signal"].get<std::string>());
              }
            }
          }
        }
      }
    }
    std::vector<std::string> names;
    for (const auto& [group, key] : m_groups) {
      if (group == name) return key;
      names.push_back(group);
    }
    std::string message = "unknown send group " + inQuotes(name);
    if (m_vehicle.scheduleFile.empty()) {
      message += ": the configuration names no schedule file (groups are defined there)";
    } else if (const auto suggestion = text::didYouMean(name, names)) {
      message += " (did you mean " + inQuotes(*suggestion) + "?)";
    } else {
      message += " in " + m_vehicle.scheduleFile;
    }
    m_check.error(path, std::move(message));
    return std::nullopt;
  }

  JsonChecker& m_check;
  const config::VehicleConfig& m_vehicle;
  const signals::Catalog& m_catalog;
  Machine m_machine;
  std::unordered_map<std::string, std::uint32_t> m_stateIndex;  ///< state name -> its first index
  std::unordered_map<signals::SignalIndex, std::uint32_t> m_slots;
  std::vector<std::pair<std::string, std::string>> m_groups;
  std::vector<std::string> m_targetPaths;
  bool m_groupsLoaded{};
  bool m_initialDefined{};
};

Result<Machine> compile(std::string_view text, const std::string& fileName, const config::VehicleConfig& vehicle,
                        const signals::Catalog& catalog, std::vector<Error>* diagnostics) {
  auto parsed = config::parseJson(text, fileName);
  if (!parsed) {
    if (diagnostics != nullptr) diagnostics->push_back(parsed.error());
    return parsed.error();
  }
  JsonChecker check(fileName);
  Loader loader(check, vehicle, catalog);
  loader.load(*parsed);
  Machine machine = loader.take();
  machine.file = fileName;
  checkMachineGraph(check, machine, catalog, loader.initialDefined());
  checkSpinningCycles(check, machine, catalog);
  for (State& state : machine.states) collectStateSignals(machine, state);
  if (diagnostics != nullptr) {
    diagnostics->insert(diagnostics->end(), check.diagnostics().begin(), check.diagnostics().end());
  }
  if (!check.ok()) return check.firstError();
  return machine;
}

}  // namespace

std::string_view compareOpName(CompareOp op) noexcept {
  switch (op) {
    case CompareOp::Eq: return "eq";
    case CompareOp::Ne: return "ne";
    case CompareOp::Lt: return "lt";
    case CompareOp::Gt: return "gt";
    case CompareOp::Le: return "le";
    case CompareOp::Ge: return "ge";
    case CompareOp::In: return "in";
  }
  return "?";
}

std::optional<std::uint32_t> Machine::findState(std::string_view name) const noexcept {
  for (std::size_t s = 0; s < states.size(); ++s) {
    if (states[s].name == name) return static_cast<std::uint32_t>(s);
  }
  return std::nullopt;
}

Result<Machine> parseMachine(std::string_view text, const std::string& fileName, const config::VehicleConfig& vehicle,
                             const signals::Catalog& catalog, std::vector<Error>* diagnostics) {
  return compile(text, fileName, vehicle, catalog, diagnostics);
}

Result<Machine> loadMachine(const std::string& path, const config::VehicleConfig& vehicle,
                            const signals::Catalog& catalog, std::vector<Error>* diagnostics) {
  std::string reason;
  const auto content = text::readFile(path, &reason);
  if (!content) {
    Error error{"cannot read the FSM file: " + reason, Location{path, 0, 0, {}}};
    if (diagnostics != nullptr) diagnostics->push_back(error);
    return error;
  }
  return compile(*content, path, vehicle, catalog, diagnostics);
}

std::vector<Error> checkMachine(const std::string& path, const config::VehicleConfig& vehicle,
                                const signals::Catalog& catalog) {
  std::vector<Error> diagnostics;
  (void)loadMachine(path, vehicle, catalog, &diagnostics);
  return diagnostics;
}

}  // namespace openvcu::fsm
