#include "openvcu/display/fsm_rules.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "openvcu/config/json.hpp"

namespace openvcu::display {
namespace {

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

}  // namespace openvcu::display
