// safety.json: the file on its own (safety_case.hpp); the checks against the vehicle are in
// safety_check.cpp.
#include "openvcu/safety/safety_case.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <utility>

#include "openvcu/config/json.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/core/text.hpp"

namespace openvcu::safety {
namespace {

using config::Json;
using config::JsonChecker;

/// Every kind name, in enum order (detectionKindName / injectKindName index these).
constexpr std::array<std::string_view, 8> DETECTION_KINDS = {
    "receiveTimeout", "j1939_76", "dm1", "dtc", "gpioInput", "serviceWatchdog", "addressLoss", "statusSignal"};
constexpr std::array<std::string_view, 14> INJECT_KINDS = {"silence", "delay",     "corrupt", "freezeCounter", "replay",
                                                           "babble",  "spoof",     "busOff",  "addressClaim",  "kill",
                                                           "stop",    "gpioStuck", "signal",  "simFault"};
/// Processes a kill or stop may name besides the VCU's services.
constexpr std::array<std::string_view, 2> OTHER_PROCESSES = {"roudi", "supervisor"};
/// A day: an FTTI or silence longer than this is a typing error, not a time budget.
constexpr double MAX_MS = 86'400'000;

bool validId(std::string_view id) {
  if (id.empty() || id.size() > 64) return false;
  for (const char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    if (!ok) return false;
  }
  return true;
}

/// "PL a".."PL e" (ISO 13849), "AgPL a".."AgPL e" (ISO 25119), "ASIL QM", "ASIL A".."ASIL D" (ISO 26262), "SIL 1".."SIL
/// 4" (IEC 61508).
bool validSeverity(std::string_view tag) {
  if (tag.size() == 4 && tag.substr(0, 3) == "PL ") return tag[3] >= 'a' && tag[3] <= 'e';
  if (tag.size() == 6 && tag.substr(0, 5) == "AgPL ") return tag[5] >= 'a' && tag[5] <= 'e';
  if (tag == "ASIL QM") return true;
  if (tag.size() == 6 && tag.substr(0, 5) == "ASIL ") return tag[5] >= 'A' && tag[5] <= 'D';
  if (tag.size() == 5 && tag.substr(0, 4) == "SIL ") return tag[4] >= '1' && tag[4] <= '4';
  return false;
}

/// A simulated vehicle's fault name: "pdu", "silent.VIC", "bms_fault".
bool validFaultName(std::string_view name) {
  if (name.size() > 64) return false;
  for (const char c : name) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

bool knownProcess(std::string_view name) {
  if (config::findService(name) != nullptr) return true;
  for (const std::string_view other : OTHER_PROCESSES) {
    if (name == other) return true;
  }
  return false;
}

std::string serviceNames() {
  std::string text;
  for (const config::ServiceEntry& entry : config::SERVICES)
    text += (text.empty() ? "" : ", ") + std::string(entry.name);
  return text;
}

template <std::size_t N>
std::string quotedList(const std::array<std::string_view, N>& names) {
  std::string text;
  for (const std::string_view name : names) text += (text.empty() ? "\"" : ", \"") + std::string(name) + "\"";
  return text;
}

template <std::size_t N>
std::optional<std::size_t> indexOfName(const std::array<std::string_view, N>& names, std::string_view name) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == name) return i;
  }
  return std::nullopt;
}

class Parser {
 public:
  explicit Parser(JsonChecker& check) : m_check(check) {}

  void run(const Json& root, SafetyCase& out) {
    if (!m_check.isObject(root, "")) return;
    m_check.onlyKeys(root, "", {"hazards", "watchdog", "comment"});
    if (const Json* watchdog = m_check.member(root, "", "watchdog", false)) out.watchdog = watchdogPolicy(*watchdog);
    const Json* hazards = m_check.array(root, "", "hazards");
    if (!hazards) return;
    std::set<std::string> ids;
    for (std::size_t i = 0; i < hazards->size(); ++i) {
      const std::string path = JsonChecker::join("/hazards", i);
      Hazard parsed = hazard((*hazards)[i], path);
      if (!parsed.id.empty() && !ids.insert(parsed.id).second) {
        m_check.error(path + "/id", "hazard '" + parsed.id + "' is defined twice");
      }
      out.hazards.push_back(std::move(parsed));
    }
  }

 private:
  /// A whole number of ms in (0, MAX_MS].
  std::optional<std::int64_t> milliseconds(const Json& object, const std::string& path, std::string_view key,
                                           bool required) {
    const auto value = m_check.number(object, path, key, required);
    if (!value) return std::nullopt;
    if (*value <= 0 || *value > MAX_MS || *value != std::floor(*value)) {
      m_check.error(JsonChecker::join(path, key), "must be a whole number of ms above 0 and at most 86400000 (a day)");
      return std::nullopt;
    }
    return static_cast<std::int64_t>(*value);
  }

  /// A string member that must not be empty.
  std::string text(const Json& object, const std::string& path, std::string_view key, bool required = true) {
    const auto value = m_check.string(object, path, key, required);
    if (!value) return {};
    if (value->empty()) m_check.error(JsonChecker::join(path, key), "must not be empty");
    return *value;
  }

  /// 0 or 1 (false/true accepted as well).
  std::optional<bool> level(const Json& object, const std::string& path, std::string_view key) {
    const Json* value = m_check.member(object, path, key, true);
    if (!value) return std::nullopt;
    if (value->is_boolean()) return value->get<bool>();
    if (value->is_number() && (value->get<double>() == 0 || value->get<double>() == 1))
      return value->get<double>() == 1;
    m_check.error(JsonChecker::join(path, key), "must be a level: 0 or 1");
    return std::nullopt;
  }

  std::optional<WatchdogPolicy> watchdogPolicy(const Json& item) {
    const std::string path = "/watchdog";
    if (!m_check.isObject(item, path)) return std::nullopt;
    m_check.onlyKeys(item, path, {"services", "silentAfterMs", "restart", "device", "comment"});
    WatchdogPolicy policy;
    if (const Json* services = m_check.array(item, path, "services")) {
      if (services->empty()) m_check.error(path + "/services", "must list at least one service");
      std::set<std::string> seen;
      for (std::size_t i = 0; i < services->size(); ++i) {
        const std::string where = JsonChecker::join(path + "/services", i);
        const Json& name = (*services)[i];
        if (!name.is_string()) {
          m_check.error(where, "must be a service name (" + serviceNames() + ")");
          continue;
        }
        const std::string service = name.get<std::string>();
        if (config::findService(service) == nullptr) {
          m_check.error(where, "unknown service '" + service + "'; the services are " + serviceNames());
          continue;
        }
        if (!seen.insert(service).second) {
          m_check.error(where, "service '" + service + "' is listed twice");
          continue;
        }
        policy.services.push_back(service);
      }
    }
    if (const auto silent = milliseconds(item, path, "silentAfterMs", true)) policy.silentAfterMs = *silent;
    if (const auto restart = m_check.boolean(item, path, "restart", false)) policy.restart = *restart;
    if (const auto device = m_check.string(item, path, "device", false)) {
      if (!device->empty() && device->front() != '/') {
        m_check.error(path + "/device", "must be an absolute device path (\"/dev/watchdog\") or \"\" for none");
      }
      policy.device = *device;
    }
    return policy;
  }

  Hazard hazard(const Json& item, const std::string& path) {
    Hazard result;
    if (!m_check.isObject(item, path)) return result;
    m_check.onlyKeys(item, path,
                     {"id", "description", "severity", "safetyGoal", "during", "safeState", "detection", "fttiMs",
                      "faults", "comment"});
    result.id = text(item, path, "id");
    if (!result.id.empty() && !validId(result.id)) {
      m_check.error(path + "/id", "'" + result.id + "' must be 1-64 letters, digits, '-' or '_'");
    }
    result.description = text(item, path, "description");
    result.severity = text(item, path, "severity");
    if (!result.severity.empty() && !validSeverity(result.severity)) {
      m_check.error(path + "/severity",
                    "'" + result.severity +
                        "' is not a severity tag; expected \"PL a\"..\"PL e\", \"AgPL a\"..\"AgPL e\", \"ASIL QM\", "
                        "\"ASIL A\"..\"ASIL D\" or \"SIL 1\"..\"SIL 4\"");
    }
    result.safetyGoal = text(item, path, "safetyGoal");
    result.comment = m_check.string(item, path, "comment", false).value_or("");
    result.during = stateNames(item, path, "during");
    if (const Json* state = m_check.member(item, path, "safeState", true)) {
      result.safeState = safeState(*state, path + "/safeState");
    }
    if (const Json* list = m_check.array(item, path, "detection")) {
      if (list->empty()) m_check.error(path + "/detection", "must name at least one detection mechanism");
      for (std::size_t i = 0; i < list->size(); ++i) {
        result.detection.push_back(detection((*list)[i], JsonChecker::join(path + "/detection", i)));
      }
    }
    if (const auto ftti = milliseconds(item, path, "fttiMs", true)) result.fttiMs = *ftti;
    for (std::size_t i = 0; i < result.detection.size(); ++i) {
      const auto within = result.detection[i].withinMs;
      if (within && result.fttiMs > 0 && *within > result.fttiMs) {
        m_check.error(JsonChecker::join(path + "/detection", i) + "/withinMs",
                      "detecting in " + std::to_string(*within) + " ms leaves the hazard's FTTI of " +
                          std::to_string(result.fttiMs) + " ms behind");
      }
    }
    if (const Json* list = m_check.array(item, path, "faults", false)) {
      for (std::size_t i = 0; i < list->size(); ++i) {
        result.faults.push_back(injection((*list)[i], JsonChecker::join(path + "/faults", i)));
      }
    }
    return result;
  }

  /// A list of FSM state names (checked against the FSM by checkSafety()).
  std::vector<std::string> stateNames(const Json& item, const std::string& path, std::string_view key) {
    std::vector<std::string> names;
    const Json* list = m_check.array(item, path, key, false);
    if (!list) return names;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string where = JsonChecker::join(JsonChecker::join(path, key), i);
      if (!(*list)[i].is_string() || (*list)[i].get<std::string>().empty()) {
        m_check.error(where, "must be an FSM state name");
        continue;
      }
      names.push_back((*list)[i].get<std::string>());
    }
    return names;
  }

  SafeState safeState(const Json& item, const std::string& path) {
    SafeState state;
    if (!m_check.isObject(item, path)) return state;
    m_check.onlyKeys(item, path, {"fsmStates", "gpio", "bus", "restarted", "comment"});
    state.fsmStates = stateNames(item, path, "fsmStates");
    if (const Json* list = m_check.array(item, path, "gpio", false)) {
      for (std::size_t i = 0; i < list->size(); ++i) {
        const std::string where = JsonChecker::join(path + "/gpio", i);
        const Json& entry = (*list)[i];
        if (!m_check.isObject(entry, where)) continue;
        m_check.onlyKeys(entry, where, {"line", "level", "comment"});
        SafeLevel safe;
        safe.line = text(entry, where, "line");
        safe.level = level(entry, where, "level").value_or(false);
        state.gpio.push_back(std::move(safe));
      }
    }
    if (const Json* list = m_check.array(item, path, "bus", false)) {
      for (std::size_t i = 0; i < list->size(); ++i) {
        const std::string where = JsonChecker::join(path + "/bus", i);
        const Json& entry = (*list)[i];
        if (!m_check.isObject(entry, where)) continue;
        m_check.onlyKeys(entry, where, {"signal", "value", "comment"});
        SafeCommand command;
        command.signal = text(entry, where, "signal");
        command.value = m_check.number(entry, where, "value").value_or(0.0);
        state.bus.push_back(std::move(command));
      }
    }
    if (const Json* list = m_check.array(item, path, "restarted", false)) {
      for (std::size_t i = 0; i < list->size(); ++i) {
        const std::string where = JsonChecker::join(path + "/restarted", i);
        const Json& name = (*list)[i];
        if (!name.is_string() || config::findService(name.get<std::string>()) == nullptr) {
          m_check.error(where, "must be a service name (" + serviceNames() + ")");
          continue;
        }
        state.restarted.push_back(name.get<std::string>());
      }
    }
    if (state.fsmStates.empty() && state.gpio.empty() && state.bus.empty() && state.restarted.empty()) {
      m_check.error(path, "names no FSM state, GPIO level, bus command or restarted service: a safe state needs one");
    }
    return state;
  }

  /// The one target member a kind takes, from `allowed`; an error when none or two are given.
  std::string target(const Json& item, const std::string& path, std::string_view kindText,
                     std::initializer_list<std::string_view> allowed,
                     std::initializer_list<std::pair<std::string_view, std::string*>> members) {
    std::string given;
    for (const auto& [key, member] : members) {
      const bool takes = std::find(allowed.begin(), allowed.end(), key) != allowed.end();
      if (item.find(std::string(key)) == item.end()) continue;
      if (!takes) {
        m_check.error(JsonChecker::join(path, key),
                      "\"" + std::string(kindText) + "\" takes no \"" + std::string(key) + "\"");
        continue;
      }
      if (!given.empty()) {
        m_check.error(JsonChecker::join(path, key), "give one of \"" + given + "\" and \"" + std::string(key) + "\"");
        continue;
      }
      given = key;
      *member = text(item, path, key);
    }
    if (given.empty()) {
      std::string names;
      for (const std::string_view key : allowed) names += (names.empty() ? "\"" : " or \"") + std::string(key) + "\"";
      m_check.error(path, "\"" + std::string(kindText) + "\" needs " + names);
    }
    return given;
  }

  Detection detection(const Json& item, const std::string& path) {
    Detection result;
    if (!m_check.isObject(item, path)) return result;
    m_check.onlyKeys(item, path,
                     {"kind", "message", "signal", "node", "fault", "line", "service", "bus", "withinMs", "comment"});
    const auto kind = m_check.string(item, path, "kind");
    if (!kind) return result;
    const auto index = indexOfName(DETECTION_KINDS, *kind);
    if (!index) {
      std::string message = "unknown detection kind '" + *kind + "'; expected " + quotedList(DETECTION_KINDS);
      m_check.error(path + "/kind", std::move(message));
      return result;
    }
    result.kind = static_cast<DetectionKind>(*index);
    const std::initializer_list<std::pair<std::string_view, std::string*>> members = {
        {"message", &result.message}, {"signal", &result.signal},   {"node", &result.node}, {"fault", &result.fault},
        {"line", &result.line},       {"service", &result.service}, {"bus", &result.bus}};
    switch (result.kind) {
      case DetectionKind::ReceiveTimeout:
        target(item, path, *kind, {"message", "signal"}, members);
        break;
      case DetectionKind::J1939_76:
        target(item, path, *kind, {"message"}, members);
        break;
      case DetectionKind::Dm1:
        target(item, path, *kind, {"node", "signal"}, members);
        break;
      case DetectionKind::Dtc:
        target(item, path, *kind, {"fault"}, members);
        break;
      case DetectionKind::GpioInput:
        target(item, path, *kind, {"line"}, members);
        break;
      case DetectionKind::ServiceWatchdog:
        target(item, path, *kind, {"service"}, members);
        break;
      case DetectionKind::AddressLoss:
        target(item, path, *kind, {"bus"}, members);
        break;
      case DetectionKind::StatusSignal:
        target(item, path, *kind, {"signal"}, members);
        break;
    }
    if (!result.service.empty() && config::findService(result.service) == nullptr) {
      m_check.error(path + "/service", "unknown service '" + result.service + "'; the services are " + serviceNames());
    }
    result.withinMs = milliseconds(item, path, "withinMs", false);
    return result;
  }

  Injection injection(const Json& item, const std::string& path) {
    Injection result;
    if (!m_check.isObject(item, path)) return result;
    m_check.onlyKeys(item, path,
                     {"inject", "node", "message", "signal", "service", "line", "bus", "value", "level", "validCrc",
                      "delayMs", "loadPercent", "address", "name", "comment"});
    const auto kind = m_check.string(item, path, "inject");
    if (!kind) return result;
    const auto index = indexOfName(INJECT_KINDS, *kind);
    if (!index) {
      m_check.error(path + "/inject", "unknown fault '" + *kind + "'; expected " + quotedList(INJECT_KINDS));
      return result;
    }
    result.kind = static_cast<InjectKind>(*index);
    const std::initializer_list<std::pair<std::string_view, std::string*>> members = {
        {"node", &result.node}, {"message", &result.message}, {"signal", &result.signal}, {"service", &result.service},
        {"line", &result.line}, {"bus", &result.bus},         {"name", &result.name}};
    // The one parameter a kind takes (none: empty); any other is refused.
    std::string_view parameter;
    switch (result.kind) {
      case InjectKind::Silence:
        target(item, path, *kind, {"node", "message"}, members);
        break;
      case InjectKind::Delay:
        target(item, path, *kind, {"node", "message"}, members);
        parameter = "delayMs";
        break;
      case InjectKind::Corrupt:
        target(item, path, *kind, {"message"}, members);
        parameter = "validCrc";
        break;
      case InjectKind::FreezeCounter:
      case InjectKind::Replay:
        target(item, path, *kind, {"message"}, members);
        break;
      case InjectKind::Babble:
        target(item, path, *kind, {"bus"}, members);
        parameter = "loadPercent";
        break;
      case InjectKind::Spoof:
        target(item, path, *kind, {"message"}, members);
        parameter = "address";
        break;
      case InjectKind::BusOff:
        target(item, path, *kind, {"bus"}, members);
        break;
      case InjectKind::AddressClaim:
        optionalBus(item, path, *kind, members, result);
        parameter = "address";
        break;
      case InjectKind::Kill:
      case InjectKind::Stop:
        target(item, path, *kind, {"service"}, members);
        if (!result.service.empty() && !knownProcess(result.service)) {
          m_check.error(path + "/service", "unknown process '" + result.service + "'; expected a service (" +
                                               serviceNames() + "), \"roudi\" or \"supervisor\"");
        }
        break;
      case InjectKind::GpioStuck:
        target(item, path, *kind, {"line"}, members);
        parameter = "level";
        break;
      case InjectKind::SimFault:
        target(item, path, *kind, {"name"}, members);
        if (!result.name.empty() && !validFaultName(result.name)) {
          m_check.error(path + "/name", "'" + result.name + "' is not a fault name: letters, digits, '_', '-' and '.'");
        }
        break;
      case InjectKind::Signal:
        target(item, path, *kind, {"signal"}, members);
        parameter = "value";
        break;
    }
    const auto takes = [&](std::string_view key) { return key == parameter; };
    for (const std::string_view key : {"value", "level", "validCrc", "delayMs", "loadPercent", "address"}) {
      if (item.find(std::string(key)) != item.end() && !takes(key)) {
        m_check.error(JsonChecker::join(path, key), "\"" + *kind + "\" takes no \"" + std::string(key) + "\"");
      }
    }
    if (takes("delayMs")) result.delayMs = milliseconds(item, path, "delayMs", true);
    if (takes("validCrc")) result.validCrc = m_check.boolean(item, path, "validCrc", true);
    if (takes("level")) result.level = level(item, path, "level");
    if (takes("value")) result.value = m_check.number(item, path, "value", true);
    if (takes("loadPercent")) {
      if (const auto load = m_check.number(item, path, "loadPercent", true)) {
        if (*load <= 0 || *load > 100)
          m_check.error(path + "/loadPercent", "must be above 0 and at most 100");
        else
          result.loadPercent = *load;
      }
    }
    if (takes("address")) {
      if (const auto address = m_check.number(item, path, "address", true)) {
        // J1939-81: 0..253 are addresses; 254 is the null address, 255 global.
        if (*address < 0 || *address > 253 || *address != std::floor(*address)) {
          m_check.error(path + "/address", "must be a J1939 source address, a whole number 0-253");
        } else {
          result.address = static_cast<std::uint8_t>(*address);
        }
      }
    }
    return result;
  }

  /// addressClaim: "bus" is optional (empty: every bus with a J1939 address claim).
  void optionalBus(const Json& item, const std::string& path, const std::string& kind,
                   std::initializer_list<std::pair<std::string_view, std::string*>> members, Injection& result) {
    for (const auto& [key, member] : members) {
      if (item.find(std::string(key)) == item.end()) continue;
      if (key != "bus") {
        m_check.error(JsonChecker::join(path, key), "\"" + kind + "\" takes no \"" + std::string(key) + "\"");
        continue;
      }
      result.bus = text(item, path, key);
    }
  }

  JsonChecker& m_check;
};

}  // namespace

std::string_view detectionKindName(DetectionKind kind) noexcept {
  return DETECTION_KINDS[static_cast<std::size_t>(kind)];
}

std::string_view injectKindName(InjectKind kind) noexcept {
  return INJECT_KINDS[static_cast<std::size_t>(kind)];
}

const Hazard* SafetyCase::findHazard(std::string_view id) const noexcept {
  for (const Hazard& hazard : hazards) {
    if (hazard.id == id) return &hazard;
  }
  return nullptr;
}

Result<SafetyCase> parseSafety(std::string_view text, const std::string& fileName) {
  auto json = config::parseJson(text, fileName);
  if (!json) return json.error();
  JsonChecker check(fileName);
  SafetyCase result;
  result.path = fileName;
  Parser(check).run(*json, result);
  if (!check.ok()) return check.firstError();
  return result;
}

Result<SafetyCase> loadSafety(const std::string& path) {
  auto json = config::readJsonFile(path);
  if (!json) return json.error();
  JsonChecker check(path);
  SafetyCase result;
  result.path = path;
  Parser(check).run(*json, result);
  if (!check.ok()) return check.firstError();
  return result;
}

}  // namespace openvcu::safety
