#include "openvcu/config/simulation.hpp"

#include <span>

#include "openvcu/config/json.hpp"
#include "simulation_peer_loader.hpp"
#include "simulation_rules_loader.hpp"

namespace openvcu::config {
namespace {

using config::Json;
using config::JsonChecker;

/// The keys only the HHEA node models read.
constexpr std::string_view HHEA_KEYS[] = {"battery", "loads", "timing", "wakeSignal"};
/// The keys only the generic model reads (simulation_rules.cpp).
constexpr std::string_view GENERIC_KEYS[] = {"rules", "follow", "integrate", "faults"};

class Loader {
 public:
  Loader(const std::string& path, const config::VehicleConfig& vehicle) : m_check(path), m_vehicle(vehicle) {
    m_config.file = path;
  }

  void run(const Json& root) {
    if (!m_check.isObject(root, "")) return;
    m_check.onlyKeys(root, "",
                     {"model", "tick", "safety", "comment", "battery", "loads", "timing", "wakeSignal", "rules",
                      "follow", "integrate", "faults", "j1939Peer"});
    model(root);
    m_config.tickNs = duration(root, "", "tick", m_config.tickNs);
    if (m_config.tickNs < 1'000'000) m_check.error("/tick", "must be at least 1ms");
    const bool hhea = m_config.model == SimModel::Hhea;
    for (const std::string_view key : hhea ? std::span<const std::string_view>(GENERIC_KEYS)
                                           : std::span<const std::string_view>(HHEA_KEYS)) {
      if (root.contains(std::string(key))) {
        m_check.error(JsonChecker::join("", key), std::string("a key of \"model\": \"") + (hhea ? "generic" : "hhea") +
                                                      "\" (this file's model is " +
                                                      std::string(simModelName(m_config.model)) + ")");
      }
    }
    if (hhea) {
      m_config.wakeSignal = m_check.string(root, "", "wakeSignal", false).value_or("");
      battery(root);
      loads(root);
      timing(root);
    }
    safety(root);
    loadSimPeer(root, m_check, m_vehicle, m_config.peer);
    if (!hhea) loadSimRules(root, m_check, m_vehicle, !m_config.safety.empty(), m_config.rules);
  }

  JsonChecker& check() { return m_check; }
  SimConfig& config() { return m_config; }

 private:
  void model(const Json& root) {
    const auto name = m_check.string(root, "", "model", false);
    if (!name) return;
    if (*name == "generic") {
      m_config.model = SimModel::Generic;
    } else if (*name == "hhea") {
      m_config.model = SimModel::Hhea;
    } else {
      m_check.error("/model", "unknown model '" + *name + "'; expected \"generic\" or \"hhea\"");
    }
  }

  void battery(const Json& root) {
    const Json* battery = m_check.member(root, "", "battery", false);
    if (!battery || !m_check.isObject(*battery, "/battery")) return;
    m_check.onlyKeys(*battery, "/battery", {"capacityAh", "initialSoc", "emptyVoltage", "fullVoltage", "resistanceOhm",
                                            "stateOfHealth", "lowSoc", "highSoc", "chargeVoltageLimit", "chargeCurrentLimit",
                                            "fullSoc", "comment"});
    number(*battery, "/battery", "capacityAh", m_config.capacityAh, 0.1, 10000);
    number(*battery, "/battery", "initialSoc", m_config.initialSoc, 0, 100);
    number(*battery, "/battery", "emptyVoltage", m_config.emptyVoltage, 0, 1100);
    number(*battery, "/battery", "fullVoltage", m_config.fullVoltage, 0, 1100);
    number(*battery, "/battery", "resistanceOhm", m_config.resistanceOhm, 0, 10);
    number(*battery, "/battery", "stateOfHealth", m_config.stateOfHealth, 0, 100);
    number(*battery, "/battery", "lowSoc", m_config.lowSoc, 0, 100);
    number(*battery, "/battery", "highSoc", m_config.highSoc, 0, 100);
    number(*battery, "/battery", "chargeVoltageLimit", m_config.chargeVoltageLimit, 0, 1100);
    number(*battery, "/battery", "chargeCurrentLimit", m_config.chargeCurrentLimit, 0, 1000);
    number(*battery, "/battery", "fullSoc", m_config.fullSoc, 0, 100);
    if (m_config.emptyVoltage >= m_config.fullVoltage) m_check.error("/battery/emptyVoltage", "must be below fullVoltage");
  }

  void loads(const Json& root) {
    const Json* loads = m_check.member(root, "", "loads", false);
    if (!loads || !m_check.isObject(*loads, "/loads")) return;
    m_check.onlyKeys(*loads, "/loads", {"drivingCurrent", "dcdcCurrent", "comment"});
    number(*loads, "/loads", "drivingCurrent", m_config.drivingCurrent, 0, 1600);
    number(*loads, "/loads", "dcdcCurrent", m_config.dcdcCurrent, 0, 200);
  }

  void timing(const Json& root) {
    const Json* timing = m_check.member(root, "", "timing", false);
    if (!timing || !m_check.isObject(*timing, "/timing")) return;
    m_check.onlyKeys(*timing, "/timing", {"keepAliveTimeout", "connect", "disconnect", "inverterStep",
                                          "timeDateAnswer", "comment"});
    m_config.keepAliveTimeoutNs = duration(*timing, "/timing", "keepAliveTimeout", m_config.keepAliveTimeoutNs);
    m_config.connectNs = duration(*timing, "/timing", "connect", m_config.connectNs);
    m_config.disconnectNs = duration(*timing, "/timing", "disconnect", m_config.disconnectNs);
    m_config.inverterStepNs = duration(*timing, "/timing", "inverterStep", m_config.inverterStepNs);
    m_config.timeDateAnswerNs = duration(*timing, "/timing", "timeDateAnswer", m_config.timeDateAnswerNs);
  }

  void safety(const Json& root) {
    const Json* list = m_check.array(root, "", "safety", false);
    if (!list) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = JsonChecker::join("/safety", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"message", "srvt", "sct", "comment"});
      SafetyCheckConfig pair;
      pair.message = m_check.string(item, path, "message").value_or("");
      const dbc::Message* message = m_vehicle.database.findMessage(pair.message);
      if (!pair.message.empty() && message == nullptr) {
        m_check.error(path + "/message", "no message '" + pair.message + "' in the DBC");
      } else if (message != nullptr) {
        pair.dataCanId = message->id;
      }
      pair.srvtNs = duration(item, path, "srvt", pair.srvtNs);
      pair.sctNs = duration(item, path, "sct", pair.sctNs);
      m_config.safety.push_back(std::move(pair));
    }
  }

  void number(const Json& object, const std::string& path, std::string_view key, double& target, double minimum,
              double maximum) {
    const auto value = m_check.number(object, path, key, false);
    if (!value) return;
    if (*value < minimum || *value > maximum) {
      m_check.error(JsonChecker::join(path, key), "must be within [" + config::formatNumber(minimum) + ", " +
                                                      config::formatNumber(maximum) + "], not " +
                                                      config::formatNumber(*value));
      return;
    }
    target = *value;
  }

  std::int64_t duration(const Json& object, const std::string& path, std::string_view key, std::int64_t fallback) {
    const Json* value = m_check.member(object, path, key, false);
    if (value == nullptr) return fallback;
    const auto ns = value->is_string() ? config::parseDurationNs(value->get<std::string>()) : std::nullopt;
    if (!ns) {
      m_check.error(JsonChecker::join(path, key), "expected " + std::string(config::DURATION_FORM));
      return fallback;
    }
    return *ns;
  }

  JsonChecker m_check;
  const config::VehicleConfig& m_vehicle;
  SimConfig m_config;
};

}  // namespace

std::string_view simModelName(SimModel model) noexcept { return model == SimModel::Hhea ? "hhea" : "generic"; }

Result<SimConfig> loadSimConfig(const std::string& path, const config::VehicleConfig& vehicle) {
  if (path.empty()) return SimConfig{};
  auto json = config::readJsonFile(path);
  if (!json) return json.error();
  Loader loader(path, vehicle);
  loader.run(*json);
  if (!loader.check().ok()) return loader.check().firstError();
  return std::move(loader.config());
}

}  // namespace openvcu::config
