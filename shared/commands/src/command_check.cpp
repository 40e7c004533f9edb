#include "openvcu/commands/command_check.hpp"

#include "openvcu/config/json.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace openvcu::commands {
namespace {

using Json = nlohmann::json;

constexpr std::string_view KINDS = "operator, set, clear, faultReset, scheduleEnable, scheduleCycle";

/// The number of `value`, or the raw value of one of the signal's value texts.
Result<double> valueOf(const Json& value, const signals::SignalInfo* signal) {
  if (value.is_number()) {
    const double number = value.get<double>();
    if (!std::isfinite(number)) return Error{"/value: not a finite number"};
    return number;
  }
  if (value.is_string() && signal != nullptr) {
    const std::string text = value.get<std::string>();
    std::string known;
    for (const auto& [raw, name] : signal->valueTexts) {
      if (name == text) return static_cast<double>(raw);
      known += (known.empty() ? "'" : ", '") + name + "'";
    }
    return Error{"/value: '" + text + "' is not a value of " + signal->key +
                 (known.empty() ? " (it has no value texts: give a number)" : " (" + known + ")")};
  }
  return Error{"/value: expected a number" + std::string(signal != nullptr && !signal->valueTexts.empty()
                                                             ? " or one of the signal's value texts"
                                                             : "")};
}

}  // namespace

Result<ipc::CommandRequest> parseCommand(std::string_view body, const signals::Catalog& catalog,
                                            const dbc::Database& database) {
  auto parsed = config::parseJson(body, "");
  if (!parsed) return Error{config::bodyErrorText(parsed.error())};
  const Json& root = *parsed;
  if (!root.is_object()) return Error{"/: expected an object {\"kind\", \"key\", \"value\"}"};
  for (const auto& [name, member] : root.items()) {
    if (name != "kind" && name != "key" && name != "value") return Error{"/" + name + ": unknown member"};
  }
  const auto kindIt = root.find("kind");
  if (kindIt == root.end() || !kindIt->is_string()) return Error{"/kind: expected one of " + std::string(KINDS)};
  const std::string kind = kindIt->get<std::string>();
  std::string key;
  if (const auto keyIt = root.find("key"); keyIt != root.end()) {
    if (!keyIt->is_string()) return Error{"/key: expected a string"};
    key = keyIt->get<std::string>();
  }
  const auto valueIt = root.find("value");
  ipc::CommandRequest request;
  request.key = key;

  if (kind == "faultReset") {
    // as the HMI's Reset: the FSM's reset switch (its transitions read it), not a latched key
    if (!catalog.indexOf(FAULT_RESET_KEY)) {
      return Error{"/kind: this vehicle has no " + std::string(FAULT_RESET_KEY) + " (its vehicle.json internalSignals)"};
    }
    request.kind = ipc::CommandKind::SetSignal;
    request.key = std::string(FAULT_RESET_KEY);
    request.value = 1;
    return request;
  }
  if (kind == "scheduleEnable" || kind == "scheduleCycle") {
    const dbc::Message* message = database.findMessage(key);
    if (key.empty() || message == nullptr || message->pseudo) return Error{"/key: no DBC message '" + key + "'"};
    if (valueIt == root.end()) return Error{"/value: missing"};
    auto value = valueOf(*valueIt, nullptr);
    if (!value) return value.error();
    if (kind == "scheduleEnable") {
      if (*value != 0 && *value != 1) return Error{"/value: 1 (transmit) or 0 (stop)"};
      request.kind = ipc::CommandKind::ScheduleEnable;
    } else {
      if (*value <= 0 || *value > 3'600'000 || *value != std::floor(*value)) {
        return Error{"/value: a cycle of 1 to 3600000 ms"};
      }
      request.kind = ipc::CommandKind::ScheduleCycle;
    }
    request.value = *value;
    return request;
  }
  if (kind != "operator" && kind != "set" && kind != "clear") {
    return Error{"/kind: unknown kind '" + kind + "'; expected one of " + std::string(KINDS)};
  }
  const auto index = catalog.indexOf(key);
  if (key.empty() || !index) return Error{"/key: unknown signal '" + key + "'"};
  const signals::SignalInfo& signal = catalog[*index];
  if (kind == "clear") {
    request.kind = ipc::CommandKind::ClearOverride;
    return request;
  }
  if (kind == "operator") {
    if (!key.starts_with(OPERATOR_PREFIX) || key == FAULT_RESET_KEY) {
      return Error{"/key: '" + key + "' is not an operator switch (internal.operator.*; FaultReset is kind faultReset)"};
    }
    request.kind = ipc::CommandKind::OperatorSwitch;
  } else {
    request.kind = ipc::CommandKind::SetSignal;
  }
  if (valueIt == root.end()) return Error{"/value: missing"};
  auto value = valueOf(*valueIt, &signal);
  if (!value) return value.error();
  request.value = *value;
  return request;
}

std::string describeCommand(const ipc::CommandRequest& request) {
  std::string kind;
  switch (request.kind) {
    case ipc::CommandKind::OperatorSwitch:
      kind = "operator";
      break;
    case ipc::CommandKind::SetSignal:
      kind = "set";
      break;
    case ipc::CommandKind::ClearOverride:
      return "clear " + request.key;
    case ipc::CommandKind::FaultReset:
      return "fault reset" + (request.key.empty() ? std::string() : " " + request.key);
    case ipc::CommandKind::ScheduleEnable:
      kind = "schedule enable";
      break;
    case ipc::CommandKind::ScheduleCycle:
      kind = "schedule cycle";
      break;
    default:
      kind = "command " + std::to_string(static_cast<int>(request.kind));
  }
  char value[32];
  std::snprintf(value, sizeof value, "%.17g", request.value);
  return kind + " " + request.key + " = " + value;
}

}  // namespace openvcu::commands
