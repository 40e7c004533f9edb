// diagnostics.json (diagnostics.hpp): DTC definitions, DM3/DM11 policy, DM1 period,
// identification and the counts file location. Persistence of the counts: dtc_counts.cpp.
#include "openvcu/config/diagnostics.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <utility>

#include "openvcu/config/json.hpp"
#include "openvcu/core/text.hpp"

namespace openvcu::config {

bool DtcConfig::activeFor(double signalValue) const noexcept {
  switch (compare) {
    case DtcCompare::Eq:
      return signalValue == value;
    case DtcCompare::Ne:
      return signalValue != value;
    case DtcCompare::Gt:
      return signalValue > value;
    case DtcCompare::Lt:
      return signalValue < value;
  }
  return false;
}

std::vector<j1939::DtcDefinition> DiagnosticsConfig::definitions() const {
  std::vector<j1939::DtcDefinition> out;
  out.reserve(dtcs.size());
  for (const DtcConfig& dtc : dtcs) out.push_back(dtc.definition);
  return out;
}

namespace {

constexpr double MIN_DM1_PERIOD_MS = 100;
constexpr double MAX_DM1_PERIOD_MS = 10'000;
/// The service appends the build version as one more SOFT field.
constexpr std::size_t MAX_CONFIGURED_SOFTWARE_FIELDS = j1939::SOFT_MAX_FIELDS - 1;

class Loader {
 public:
  Loader(const VehicleConfig& vehicle, const signals::Catalog& catalog, const std::vector<std::string>* fsmStates)
      : m_vehicle(vehicle), m_catalog(catalog), m_fsmStates(fsmStates), m_check(vehicle.diagnosticsFile) {
    m_config.file = vehicle.diagnosticsFile;
  }

  void run(const Json& root) {
    if (!m_check.isObject(root, "")) return;
    m_check.onlyKeys(root, "", {"comment", "dtcs", "dm3", "dm11", "dm1PeriodMs", "identification", "countsFile"});
    dtcs(root);
    m_config.dm3 = policy(root, "dm3", "DM3 (clear previously active DTCs)");
    m_config.dm11 = policy(root, "dm11", "DM11 (clear active DTCs)");
    if (auto period = m_check.number(root, "", "dm1PeriodMs", false)) {
      if (!(*period >= MIN_DM1_PERIOD_MS && *period <= MAX_DM1_PERIOD_MS) || *period != std::floor(*period)) {
        m_check.error("/dm1PeriodMs", "must be a whole number of milliseconds from 100 to 10000 (J1939-73: 1000)");
      } else {
        m_config.dm1PeriodNs = static_cast<std::int64_t>(*period) * 1'000'000;
      }
    }
    identification(root);
    countsFile(root);
  }

  JsonChecker& check() { return m_check; }
  DiagnosticsConfig& config() { return m_config; }

 private:
  void dtcs(const Json& root) {
    const Json* list = m_check.array(root, "", "dtcs", false);
    if (list == nullptr) return;
    if (list->size() > j1939::DM1_MAX_DTCS) {
      m_check.error("/dtcs", std::to_string(list->size()) + " DTCs: one DM1 holds at most " +
                                 std::to_string(j1939::DM1_MAX_DTCS));
      return;
    }
    std::map<std::pair<std::uint32_t, std::uint8_t>, std::string> codes;
    std::map<std::string, std::string> names;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = JsonChecker::join("/dtcs", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path,
                       {"name", "fsmState", "signal", "activeWhen", "spn", "fmi", "lamps", "flash", "comment"});
      DtcConfig dtc;
      dtc.path = path;
      dtc.name = m_check.string(item, path, "name").value_or("");
      if (!dtc.name.empty()) {
        if (const auto [where, fresh] = names.emplace(dtc.name, path); !fresh) {
          m_check.error(path + "/name", "DTC name '" + dtc.name + "' is given twice (first at " + where->second + ")");
        }
      }
      dtc.comment = m_check.string(item, path, "comment", false).value_or("");
      source(item, path, dtc);
      const auto spn = wholeNumber(item, path, "spn", j1939::DTC_MAX_SPN);
      const auto fmi = wholeNumber(item, path, "fmi", j1939::DTC_MAX_FMI);
      if (spn && fmi) {
        dtc.definition.spn = static_cast<std::uint32_t>(*spn);
        dtc.definition.fmi = static_cast<std::uint8_t>(*fmi);
        if (*spn == 0 && *fmi == 0) {
          m_check.error(path + "/spn", "SPN 0 with FMI 0 means \"no DTC\" on the bus");
        } else if (const auto [where, fresh] = codes.emplace(std::pair{dtc.definition.spn, dtc.definition.fmi}, path);
                   !fresh) {
          m_check.error(path, "SPN " + std::to_string(*spn) + " FMI " + std::to_string(*fmi) +
                                  " is already the DTC at " + where->second);
        }
      }
      lamps(item, path, dtc.definition.lamps);
      m_config.dtcs.push_back(std::move(dtc));
    }
  }

  void source(const Json& item, const std::string& path, DtcConfig& dtc) {
    const bool byState = item.contains("fsmState");
    const bool bySignal = item.contains("signal");
    if (byState == bySignal) {
      m_check.error(path, "give exactly one of \"fsmState\" (an FSM state name) and \"signal\" (a table key)");
      return;
    }
    if (byState) {
      dtc.source = DtcSource::FsmState;
      if (item.contains("activeWhen")) m_check.error(path + "/activeWhen", "only a \"signal\" DTC takes activeWhen");
      dtc.fsmState = m_check.string(item, path, "fsmState").value_or("");
      if (dtc.fsmState.empty()) return;
      if (m_vehicle.fsmFile.empty()) {
        m_check.error(path + "/fsmState", "the vehicle has no FSM (no \"fsm\" in " + m_vehicle.path + ")");
      } else if (m_fsmStates != nullptr &&
                 std::find(m_fsmStates->begin(), m_fsmStates->end(), dtc.fsmState) == m_fsmStates->end()) {
        std::string message = "the FSM (" + m_vehicle.fsmFile + ") has no state '" + dtc.fsmState + "'";
        if (auto suggestion = text::didYouMean(dtc.fsmState, *m_fsmStates)) {
          message += "; did you mean '" + *suggestion + "'?";
        }
        m_check.error(path + "/fsmState", std::move(message));
      }
      return;
    }
    dtc.source = DtcSource::Signal;
    dtc.signal = m_check.string(item, path, "signal").value_or("");
    const signals::SignalInfo* info = nullptr;
    if (!dtc.signal.empty()) {
      if (const auto index = m_catalog.indexOf(dtc.signal)) {
        info = &m_catalog[*index];
      } else {
        std::string message = "unknown signal '" + dtc.signal + "'";
        if (auto suggestion = m_catalog.suggest(dtc.signal)) message += "; did you mean '" + *suggestion + "'?";
        m_check.error(path + "/signal", std::move(message));
      }
    }
    activeWhen(item, path, info, dtc);
  }

  void activeWhen(const Json& item, const std::string& path, const signals::SignalInfo* info, DtcConfig& dtc) {
    const Json* when = m_check.member(item, path, "activeWhen", false);
    if (when == nullptr) return;  // default: value != 0
    const std::string wherePath = path + "/activeWhen";
    if (!m_check.isObject(*when, wherePath)) return;
    m_check.onlyKeys(*when, wherePath, {"eq", "ne", "gt", "lt"});
    if (when->size() != 1) {
      m_check.error(wherePath, "give exactly one of \"eq\", \"ne\", \"gt\", \"lt\"");
      return;
    }
    // the one member: its key copied, its value a reference into *when (items() would hand
    // out a proxy that dies at the end of this statement)
    const auto member = when->begin();
    const std::string key = member.key();
    const Json& value = member.value();
    static const std::pair<std::string_view, DtcCompare> COMPARES[] = {
        {"eq", DtcCompare::Eq}, {"ne", DtcCompare::Ne}, {"gt", DtcCompare::Gt}, {"lt", DtcCompare::Lt}};
    for (const auto& [name, compare] : COMPARES) {
      if (key == name) dtc.compare = compare;
    }
    const std::string valuePath = JsonChecker::join(wherePath, key);
    if (value.is_number()) {
      dtc.value = value.get<double>();
    } else if (value.is_string()) {
      // a value-table text of the signal ("Fault"), as FSM conditions take it
      const std::string text = value.get<std::string>();
      if (info == nullptr) return;  // the unknown signal is already an error
      const auto found = std::find_if(info->valueTexts.begin(), info->valueTexts.end(),
                                      [&](const auto& entry) { return entry.second == text; });
      if (found == info->valueTexts.end()) {
        m_check.error(valuePath, "signal '" + dtc.signal + "' has no value named '" + text + "'");
      } else {
        dtc.value = static_cast<double>(found->first);
      }
    } else {
      m_check.error(valuePath, "must be a number or a value name of the signal");
    }
  }

  std::optional<std::uint32_t> wholeNumber(const Json& item, const std::string& path, std::string_view key,
                                           std::uint32_t maximum) {
    const auto value = m_check.number(item, path, key);
    if (!value) return std::nullopt;
    if (!(*value >= 0 && *value <= maximum) || *value != std::floor(*value)) {
      m_check.error(JsonChecker::join(path, key),
                    "must be a whole number from 0 to " + std::to_string(maximum) + ", not " + formatNumber(*value));
      return std::nullopt;
    }
    return static_cast<std::uint32_t>(*value);
  }

  struct LampSlot {
    std::string_view name;
    bool j1939::DtcLampRequest::*on;
    j1939::LampFlash j1939::DtcLampRequest::*flash;
  };
  static constexpr LampSlot LAMPS[] = {
      {"protect", &j1939::DtcLampRequest::protect, &j1939::DtcLampRequest::protectFlash},
      {"amber", &j1939::DtcLampRequest::amberWarning, &j1939::DtcLampRequest::amberWarningFlash},
      {"red", &j1939::DtcLampRequest::redStop, &j1939::DtcLampRequest::redStopFlash},
      {"malfunction", &j1939::DtcLampRequest::malfunction, &j1939::DtcLampRequest::malfunctionFlash},
  };

  static const LampSlot* lampNamed(std::string_view name) {
    for (const LampSlot& slot : LAMPS) {
      if (slot.name == name) return &slot;
    }
    return nullptr;
  }

  void lamps(const Json& item, const std::string& path, j1939::DtcLampRequest& request) {
    const std::vector<std::string> lampNames = {"protect", "amber", "red", "malfunction"};
    if (const Json* list = m_check.array(item, path, "lamps", false)) {
      for (std::size_t i = 0; i < list->size(); ++i) {
        const std::string where = JsonChecker::join(path + "/lamps", i);
        const Json& name = (*list)[i];
        const LampSlot* slot = name.is_string() ? lampNamed(name.get<std::string>()) : nullptr;
        if (slot == nullptr) {
          m_check.error(where, "expected one of \"protect\", \"amber\", \"red\", \"malfunction\"");
          continue;
        }
        if (request.*(slot->on)) m_check.error(where, "lamp '" + std::string(slot->name) + "' is given twice");
        request.*(slot->on) = true;
      }
    }
    const Json* flash = m_check.member(item, path, "flash", false);
    if (flash == nullptr || !m_check.isObject(*flash, path + "/flash")) return;
    for (const auto& [name, speed] : flash->items()) {
      const std::string where = JsonChecker::join(path + "/flash", name);
      const LampSlot* slot = lampNamed(name);
      if (slot == nullptr) {
        std::string message = "unknown lamp '" + name + "'";
        if (auto suggestion = text::didYouMean(name, lampNames)) message += "; did you mean '" + *suggestion + "'?";
        m_check.error(where, std::move(message));
        continue;
      }
      if (!(request.*(slot->on))) {
        m_check.error(where, "lamp '" + name + "' is not in \"lamps\": only a lamp that is on flashes");
        continue;
      }
      const std::string text = speed.is_string() ? speed.get<std::string>() : std::string{};
      if (text == "slow") {
        request.*(slot->flash) = j1939::LampFlash::Slow;
      } else if (text == "fast") {
        request.*(slot->flash) = j1939::LampFlash::Fast;
      } else {
        m_check.error(where, "expected \"slow\" (1 Hz) or \"fast\" (2 Hz or more)");
      }
    }
  }

  /// "accept" is a warning: the request carries nothing but its source address, which any
  /// device on the bus may use, so accepting means accepting from every node.
  ClearPolicy policy(const Json& root, std::string_view key, std::string_view request) {
    const auto text = m_check.string(root, "", key, false);
    if (!text) return ClearPolicy::Refuse;
    if (*text == "accept") {
      m_check.warning(JsonChecker::join("", key),
                      std::string(request) +
                          " is accepted from any node on the bus: any device that can send on it (a node, a "
                          "tool on the diagnostic connector) can erase the fault history; \"refuse\" unless a "
                          "workshop must clear DTCs over J1939");
      return ClearPolicy::Accept;
    }
    if (*text != "refuse") m_check.error(JsonChecker::join("", key), "expected \"accept\" or \"refuse\"");
    return ClearPolicy::Refuse;
  }

  void identification(const Json& root) {
    const Json* ident = m_check.member(root, "", "identification", false);
    if (ident == nullptr || !m_check.isObject(*ident, "/identification")) return;
    m_check.onlyKeys(*ident, "/identification", {"software", "ecu", "component", "comment"});
    IdentificationConfig& out = m_config.identification;
    if (const Json* software = m_check.array(*ident, "/identification", "software", false)) {
      if (software->size() > MAX_CONFIGURED_SOFTWARE_FIELDS) {
        m_check.error("/identification/software", "at most " + std::to_string(MAX_CONFIGURED_SOFTWARE_FIELDS) +
                                                      " fields (SOFT holds 125; the service appends the version)");
      }
      for (std::size_t i = 0; i < software->size(); ++i) {
        const std::string where = JsonChecker::join("/identification/software", i);
        if (!(*software)[i].is_string()) {
          m_check.error(where, "must be a string");
          continue;
        }
        out.software.push_back((*software)[i].get<std::string>());
        field(out.software.back(), where);
      }
    }
    if (const Json* ecu = m_check.member(*ident, "/identification", "ecu", false)) {
      const std::string path = "/identification/ecu";
      if (m_check.isObject(*ecu, path)) {
        m_check.onlyKeys(*ecu, path,
                         {"partNumber", "serialNumber", "location", "type", "manufacturer", "hardwareId", "comment"});
        text(*ecu, path, "partNumber", out.partNumber);
        text(*ecu, path, "serialNumber", out.serialNumber);
        text(*ecu, path, "location", out.location);
        text(*ecu, path, "type", out.type);
        text(*ecu, path, "manufacturer", out.manufacturer);
        text(*ecu, path, "hardwareId", out.hardwareId);
      }
    }
    if (const Json* component = m_check.member(*ident, "/identification", "component", false)) {
      const std::string path = "/identification/component";
      if (m_check.isObject(*component, path)) {
        m_check.onlyKeys(*component, path, {"make", "model", "serialNumber", "unitNumber", "comment"});
        text(*component, path, "make", out.make);
        text(*component, path, "model", out.model);
        text(*component, path, "serialNumber", out.componentSerialNumber);
        text(*component, path, "unitNumber", out.unitNumber);
      }
    }
  }

  void text(const Json& object, const std::string& path, std::string_view key, std::string& target) {
    if (auto value = m_check.string(object, path, key, false)) {
      target = *value;
      field(target, JsonChecker::join(path, key));
    }
  }

  void field(const std::string& value, const std::string& path) {
    if (!j1939::validIdentificationField(value)) {
      m_check.error(path, "an identification field has at most 200 bytes and no '*' (the field delimiter)");
    }
  }

  void countsFile(const Json& root) {
    std::string name(DEFAULT_DTC_COUNTS_FILE);
    if (auto given = m_check.string(root, "", "countsFile", false)) {
      if (given->empty()) {
        m_check.error("/countsFile", "must name a file");
        return;
      }
      name = *given;
    }
    const std::filesystem::path file(name);
    const std::filesystem::path folder = std::filesystem::path(m_config.file).parent_path();
    m_config.countsFile =
        file.is_absolute() ? file.lexically_normal().string() : (folder / file).lexically_normal().string();
  }

  const VehicleConfig& m_vehicle;
  const signals::Catalog& m_catalog;
  const std::vector<std::string>* m_fsmStates;
  JsonChecker m_check;
  DiagnosticsConfig m_config;
};

}  // namespace

Result<DiagnosticsConfig> loadDiagnosticsConfig(const VehicleConfig& vehicle, const signals::Catalog& catalog,
                                                const std::vector<std::string>* fsmStates,
                                                std::vector<Error>* diagnostics) {
  if (vehicle.diagnosticsFile.empty()) return DiagnosticsConfig{};
  auto json = readJsonFile(vehicle.diagnosticsFile);
  if (!json) {
    if (diagnostics != nullptr) diagnostics->push_back(json.error());
    return json.error();
  }
  Loader loader(vehicle, catalog, fsmStates);
  loader.run(*json);
  if (diagnostics != nullptr) {
    diagnostics->insert(diagnostics->end(), loader.check().diagnostics().begin(), loader.check().diagnostics().end());
  }
  if (!loader.check().ok()) return loader.check().firstError();
  return std::move(loader.config());
}

}  // namespace openvcu::config
