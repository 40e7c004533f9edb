#include "openvcu/schedule/schedule_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "openvcu/can/frame.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/safety.hpp"

namespace openvcu::schedule {
namespace {

constexpr std::int64_t NS_PER_MS = 1'000'000;
constexpr double MAX_OFFSET_MS = config::MAX_CYCLE_MS;
constexpr std::string_view GROUP_PREFIX = "internal.";
/// A DBC writes a 29-bit identifier with this bit set (BO_ 2566869221 = 0x18FF50E5 | flag).
constexpr std::uint32_t DBC_EXTENDED_FLAG = 0x80000000u;

using config::Json;
using config::JsonChecker;

struct AlgorithmName {
  std::string_view name;
  FieldAlgorithm algorithm;
};
constexpr std::array<AlgorithmName, 5> ALGORITHMS = {{{"counter", FieldAlgorithm::Counter},
                                                      {"sum8", FieldAlgorithm::Sum8},
                                                      {"xor8", FieldAlgorithm::Xor8},
                                                      {"crc8-sae-j1850", FieldAlgorithm::Crc8SaeJ1850},
                                                      {"j1939-checksum4", FieldAlgorithm::J1939Checksum4}}};

std::optional<std::uint32_t> parseAddress(const Json& value) {
  if (value.is_number_unsigned()) {
    const auto number = value.get<std::uint64_t>();
    return number <= 0xFF ? std::optional<std::uint32_t>(static_cast<std::uint32_t>(number)) : std::nullopt;
  }
  if (!value.is_string()) return std::nullopt;
  const std::string text = value.get<std::string>();
  if (text.empty()) return std::nullopt;
  try {
    std::size_t used = 0;
    const unsigned long parsed = std::stoul(text, &used, 0);
    if (used != text.size() || parsed > 0xFF) return std::nullopt;
    return static_cast<std::uint32_t>(parsed);
  } catch (...) {
    return std::nullopt;
  }
}

std::string suggestion(std::string_view word, const std::vector<std::string>& candidates) {
  if (auto maybe = text::didYouMean(word, candidates)) return " (did you mean '" + *maybe + "'?)";
  return {};
}

std::vector<std::string> messageNames(const config::VehicleConfig& vehicle) {
  std::vector<std::string> names;
  for (const auto& message : vehicle.database.messages) names.push_back(message.name);
  return names;
}

bool isSafetyHeader(const dbc::Message& message) {
  return message.extended && j1939::pgnOf(message.id) == j1939::PGN_SAFETY_HEADER;
}

double initialOf(const config::VehicleConfig& vehicle, std::string_view key) {
  for (const auto& internal : vehicle.internalSignals) {
    if (key.size() == config::INTERNAL_PREFIX.size() + internal.name.size() &&
        key.starts_with(config::INTERNAL_PREFIX) && key.substr(config::INTERNAL_PREFIX.size()) == internal.name) {
      return internal.initial;
    }
  }
  return 0.0;
}

class Loader {
 public:
  Loader(const config::VehicleConfig& vehicle, const signals::Catalog& catalog, JsonChecker& check)
      : m_vehicle(vehicle), m_catalog(catalog), m_check(check) {}

  Schedule run(const Json* root) {
    Schedule schedule;
    schedule.file = m_vehicle.scheduleFile;
    schedule.overlay = defaultOverlayPath();
    if (root != nullptr) {
      if (!m_check.isObject(*root, "")) return schedule;
      m_check.onlyKeys(*root, "",
                       {"include", "exclude", "messages", "groups", "writers", "safeValues", "timeDate",
                        "realtimePriority", "sdmSpinUs", "overlay", "comment"});
    }
    groups(root, schedule);
    selectMessages(root, schedule);
    if (root != nullptr) {
      messageSettings(*root, schedule);
      writers(*root, schedule);
      safeValues(*root, schedule);
      timeDate(*root, schedule);
      if (auto priority = m_check.number(*root, "", "realtimePriority", false)) {
        if (!(*priority >= 0 && *priority <= 99) || *priority != std::floor(*priority)) {
          m_check.error("/realtimePriority", "must be a whole number from 0 (normal scheduling) to 99");
        } else {
          schedule.realtimePriority = static_cast<int>(*priority);
        }
      }
      if (auto spin = m_check.number(*root, "", "sdmSpinUs", false)) {
        if (!(*spin >= 0 && *spin <= static_cast<double>(MAX_SDM_SPIN_US)) || *spin != std::floor(*spin)) {
          m_check.error("/sdmSpinUs",
                        "must be a whole number of microseconds from 0 (the transmit thread always "
                        "sleeps) to " +
                            std::to_string(MAX_SDM_SPIN_US));
        } else {
          schedule.sdmSpinNs = static_cast<std::int64_t>(*spin) * 1000;
        }
      }
      if (auto overlay = m_check.string(*root, "", "overlay", false)) {
        if (overlay->empty()) {
          m_check.error("/overlay", "must name a file");
        } else {
          schedule.overlay = resolve(*overlay);
        }
      }
    }
    return schedule;
  }

 private:
  std::string resolve(const std::string& path) const {
    if (path.empty() || path.front() == '/') return path;
    const std::string base =
        std::filesystem::path(m_vehicle.scheduleFile.empty() ? m_vehicle.path : m_vehicle.scheduleFile)
            .parent_path()
            .string();
    return base.empty() ? path : base + "/" + path;
  }

  std::string defaultOverlayPath() const {
    if (!m_vehicle.scheduleFile.empty()) {
      std::filesystem::path file(m_vehicle.scheduleFile);
      return (file.parent_path() / (file.stem().string() + ".overlay.json")).string();
    }
    return resolve("schedule.overlay.json");
  }

  /// The message named `name`, or empty with an error at `path`. `toSend`: the schedule
  /// would send it, so it must be a message the vehicle's node transmits (or one the DBC
  /// gives no transmitter).
  std::optional<std::size_t> messageByName(const std::string& name, const std::string& path, bool toSend) {
    const auto& messages = m_vehicle.database.messages;
    for (std::size_t m = 0; m < messages.size(); ++m) {
      if (messages[m].name != name || messages[m].pseudo) continue;
      if (m_vehicle.busOf(m) == nullptr) {
        m_check.error(path, "message '" + name + "' is on no configured bus");
        return std::nullopt;
      }
      if (toSend && !sendable(messages[m], path)) return std::nullopt;
      if (isSafetyHeader(messages[m])) {
        m_check.error(path, "'" + name +
                                "' is a J1939-76 safety header (PGN 0x0E00): it goes out with its SDM; "
                                "give the SDM \"safety\": {\"deltaUs\": ...} instead");
        return std::nullopt;
      }
      return m;
    }
    m_check.error(path, "unknown message '" + name + "'" + suggestion(name, messageNames(m_vehicle)));
    return std::nullopt;
  }

  /// False, with an error at `path`, when the DBC names transmitters of `message` and the
  /// vehicle's node is not one of them: sending it would impersonate another node. A node
  /// that really sends another's message (a gateway) is named in the DBC's BO_TX_BU_.
  bool sendable(const dbc::Message& message, const std::string& path) {
    if (message.transmitter.empty() || message.transmitter == dbc::NO_NODE) return true;
    if (config::sentBy(message, m_vehicle.node)) return true;
    std::string senders;
    for (const std::string& sender : message.transmitters()) senders += (senders.empty() ? "" : ",") + sender;
    const std::uint32_t dbcId = message.id | (message.extended ? DBC_EXTENDED_FLAG : 0u);
    m_check.error(path, "message '" + message.name + "' is sent by " + senders + " (its DBC transmitter), not by " +
                            m_vehicle.node + ": scheduling it would make the VCU impersonate " + senders + "; if " +
                            m_vehicle.node +
                            " really sends it (a gateway), name it among the message's transmitters in the DBC "
                            "(BO_TX_BU_ " +
                            std::to_string(dbcId) + " : " + senders + "," + m_vehicle.node + ";)");
    return false;
  }

  void groups(const Json* root, Schedule& schedule) {
    const Json* map = root != nullptr ? m_check.member(*root, "", "groups", false) : nullptr;
    if (map == nullptr || !m_check.isObject(*map, "/groups")) return;
    for (const auto& [name, settings] : map->items()) {
      const std::string path = JsonChecker::join("/groups", name);
      if (!m_check.isObject(settings, path)) continue;
      m_check.onlyKeys(settings, path, {"signal", "comment"});
      const auto key = m_check.string(settings, path, "signal");
      if (!key) continue;
      const auto index = m_catalog.indexOf(*key);
      if (!index) {
        std::string text = "unknown signal '" + *key + "'";
        if (auto maybe = m_catalog.suggest(*key)) text += " (did you mean '" + *maybe + "'?)";
        if (key->starts_with(GROUP_PREFIX)) text += "; declare it in the vehicle configuration's internalSignals";
        m_check.error(path + "/signal", std::move(text));
        continue;
      }
      schedule.groups.push_back(SendGroup{name, *index, initialOf(m_vehicle, *key)});
    }
  }

  void addMessage(Schedule& schedule, std::size_t index) {
    if (schedule.find(index) != nullptr) return;
    const dbc::Message& message = m_vehicle.database.messages[index];
    ScheduledMessage entry;
    entry.message = index;
    const config::BusConfig* bus = m_vehicle.busOf(index);
    entry.bus = static_cast<std::size_t>(bus - m_vehicle.buses.data());
    entry.canId = message.id;
    entry.extended = message.extended;
    entry.cycleNs = message.cycleTimeMs ? static_cast<std::int64_t>(*message.cycleTimeMs) * NS_PER_MS : 0;
    entry.defaults.assign(message.signals.size(), std::nullopt);
    for (const dbc::Signal& signal : message.signals) {
      entry.keys.push_back(m_catalog.indexOf(config::signalKey(message, signal)));
    }
    schedule.messages.push_back(std::move(entry));
  }

  void selectMessages(const Json* root, Schedule& schedule) {
    const auto& messages = m_vehicle.database.messages;
    const Json* include = root != nullptr ? m_check.member(*root, "", "include", false) : nullptr;
    if (include == nullptr || (include->is_string() && include->get<std::string>() == "transmitted")) {
      for (std::size_t m = 0; m < messages.size(); ++m) {
        if (!messages[m].pseudo && config::sentBy(messages[m], m_vehicle.node) && m_vehicle.busOf(m) != nullptr &&
            !isSafetyHeader(messages[m])) {
          addMessage(schedule, m);
        }
      }
    } else if (include->is_array()) {
      for (std::size_t i = 0; i < include->size(); ++i) {
        const std::string path = JsonChecker::join("/include", i);
        if (!(*include)[i].is_string()) {
          m_check.error(path, "must be a message name");
          continue;
        }
        if (auto index = messageByName((*include)[i].get<std::string>(), path, true)) addMessage(schedule, *index);
      }
    } else {
      m_check.error("/include", "must be \"transmitted\" or a list of message names");
    }
    if (root != nullptr) {
      if (const Json* messagesMap = m_check.member(*root, "", "messages", false);
          messagesMap && messagesMap->is_object()) {
        for (const auto& [name, settings] : messagesMap->items()) {
          if (auto index = messageByName(name, JsonChecker::join("/messages", name), true)) {
            addMessage(schedule, *index);
          }
        }
      }
    }
    const Json* exclude = root != nullptr ? m_check.array(*root, "", "exclude", false) : nullptr;
    if (exclude == nullptr) return;
    for (std::size_t i = 0; i < exclude->size(); ++i) {
      const std::string path = JsonChecker::join("/exclude", i);
      if (!(*exclude)[i].is_string()) {
        m_check.error(path, "must be a message name");
        continue;
      }
      const auto index = messageByName((*exclude)[i].get<std::string>(), path, false);
      if (!index) continue;
      if (root->contains("messages") && (*root)["messages"].is_object() &&
          (*root)["messages"].contains(messages[*index].name)) {
        m_check.error(path, "'" + messages[*index].name + "' is excluded but configured under /messages");
        continue;
      }
      std::erase_if(schedule.messages, [&](const ScheduledMessage& entry) { return entry.message == *index; });
    }
  }

  std::optional<std::uint32_t> signalOf(const dbc::Message& message, const std::string& name, const std::string& path) {
    for (std::uint32_t s = 0; s < message.signals.size(); ++s) {
      if (message.signals[s].name == name) return s;
    }
    std::vector<std::string> names;
    for (const auto& signal : message.signals) names.push_back(signal.name);
    m_check.error(path, "unknown signal '" + name + "' in message '" + message.name + "'" + suggestion(name, names));
    return std::nullopt;
  }

  void messageSettings(const Json& root, Schedule& schedule) {
    const Json* map = m_check.member(root, "", "messages", false);
    if (map == nullptr || !m_check.isObject(*map, "/messages")) return;
    for (const auto& [name, settings] : map->items()) {
      const std::string path = JsonChecker::join("/messages", name);
      const dbc::Message* message = m_vehicle.database.findMessage(name);
      if (message == nullptr) continue;  // reported by selectMessages
      const auto index = static_cast<std::size_t>(message - m_vehicle.database.messages.data());
      ScheduledMessage* entry = schedule.find(index);
      if (entry == nullptr || !m_check.isObject(settings, path)) continue;
      m_check.onlyKeys(settings, path,
                       {"cycleMs", "offsetMs", "enabled", "group", "values", "computed", "onChange", "minIntervalMs",
                        "destination", "source", "safety", "comment"});
      timing(settings, path, *entry);
      if (auto group = m_check.string(settings, path, "group", false)) {
        std::vector<std::string> names;
        for (std::size_t g = 0; g < schedule.groups.size(); ++g) {
          if (schedule.groups[g].name == *group) entry->group = g;
          names.push_back(schedule.groups[g].name);
        }
        if (!entry->group) {
          m_check.error(path + "/group", "unknown send group '" + *group + "'" + suggestion(*group, names) +
                                             "; define it under /groups");
        }
      }
      values(settings, path, *message, *entry);
      computed(settings, path, *message, *entry);
      addresses(settings, path, *message, *entry);
      safety(settings, path, *message, *entry);
    }
  }

  void timing(const Json& settings, const std::string& path, ScheduledMessage& entry) {
    if (auto cycle = m_check.number(settings, path, "cycleMs", false)) {
      if (auto problem = config::checkCycleMs(*cycle)) {
        // 0 would silently never send the message: a cycle is given or left to the DBC
        if (*cycle == 0) {
          *problem += "; leave \"cycleMs\" out for the DBC's GenMsgCycleTime (a message without one is not cyclic)";
        }
        m_check.error(path + "/cycleMs", *problem);
      } else {
        entry.cycleNs = static_cast<std::int64_t>(*cycle) * NS_PER_MS;
      }
    }
    if (auto offset = m_check.number(settings, path, "offsetMs", false)) {
      if (!(*offset >= 0 && *offset <= MAX_OFFSET_MS)) {
        m_check.error(path + "/offsetMs", "must be from 0 to 3600000 ms");
      } else {
        entry.offsetNs = static_cast<std::int64_t>(std::llround(*offset * NS_PER_MS));
      }
    }
    if (auto enabled = m_check.boolean(settings, path, "enabled", false)) entry.enabled = *enabled;
    if (auto onChange = m_check.boolean(settings, path, "onChange", false)) entry.onChange = *onChange;
    if (auto interval = m_check.number(settings, path, "minIntervalMs", false)) {
      if (!(*interval >= 1 && *interval <= 60'000)) {
        m_check.error(path + "/minIntervalMs", "must be from 1 to 60000 ms");
      } else {
        entry.minIntervalNs = static_cast<std::int64_t>(std::llround(*interval * NS_PER_MS));
      }
    }
  }

  void values(const Json& settings, const std::string& path, const dbc::Message& message, ScheduledMessage& entry) {
    const Json* map = m_check.member(settings, path, "values", false);
    if (map == nullptr || !m_check.isObject(*map, path + "/values")) return;
    for (const auto& [name, value] : map->items()) {
      const std::string valuePath = JsonChecker::join(path + "/values", name);
      const auto signal = signalOf(message, name, valuePath);
      if (!signal) continue;
      if (!value.is_number()) {
        m_check.error(valuePath, "must be a number (the physical value)");
        continue;
      }
      const double number = value.get<double>();
      if (auto problem = checkSignalValue(message.signals[*signal], number)) {
        m_check.error(valuePath, *problem);
        continue;
      }
      entry.defaults[*signal] = number;
    }
  }

  void computed(const Json& settings, const std::string& path, const dbc::Message& message, ScheduledMessage& entry) {
    const Json* list = m_check.array(settings, path, "computed", false);
    if (list == nullptr) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string itemPath = JsonChecker::join(path + "/computed", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, itemPath)) continue;
      m_check.onlyKeys(item, itemPath, {"signal", "algorithm", "modulo", "start", "comment"});
      const auto name = m_check.string(item, itemPath, "signal");
      const auto algorithmName = m_check.string(item, itemPath, "algorithm");
      if (!name || !algorithmName) continue;
      const auto signal = signalOf(message, *name, itemPath + "/signal");
      if (!signal) continue;
      const dbc::Signal& dbcSignal = message.signals[*signal];
      ComputedField field;
      field.signal = *signal;
      const auto found = std::find_if(ALGORITHMS.begin(), ALGORITHMS.end(),
                                      [&](const AlgorithmName& known) { return known.name == *algorithmName; });
      if (found == ALGORITHMS.end()) {
        std::vector<std::string> names;
        for (const auto& known : ALGORITHMS) names.emplace_back(known.name);
        m_check.error(itemPath + "/algorithm", "unknown algorithm '" + *algorithmName + "'" +
                                                   suggestion(*algorithmName, names) +
                                                   "; known: counter, sum8, xor8, crc8-sae-j1850, j1939-checksum4");
        continue;
      }
      field.algorithm = found->algorithm;
      if (dbcSignal.valueType != dbc::ValueType::Integer || dbcSignal.isSigned || dbcSignal.size > 32 ||
          dbcSignal.muxRole == dbc::MuxRole::Multiplexed) {
        m_check.error(itemPath + "/signal",
                      "a computed field is an unsigned integer signal of 1..32 bits, not "
                      "multiplexed; '" +
                          *name + "' is not");
        continue;
      }
      const std::uint64_t span = std::uint64_t{1} << dbcSignal.size;
      if (field.algorithm == FieldAlgorithm::Counter) {
        if (auto modulo = m_check.number(item, itemPath, "modulo", false)) {
          if (!(*modulo >= 2 && *modulo <= static_cast<double>(span)) || *modulo != std::floor(*modulo)) {
            m_check.error(itemPath + "/modulo", "must be a whole number from 2 to " + std::to_string(span));
            continue;
          }
          field.modulo = static_cast<std::uint64_t>(*modulo);
        }
        const std::uint64_t modulo = field.modulo != 0 ? field.modulo : span;
        if (auto start = m_check.number(item, itemPath, "start", false)) {
          if (!(*start >= 0 && *start < static_cast<double>(modulo)) || *start != std::floor(*start)) {
            m_check.error(itemPath + "/start", "must be a whole number from 0 to " + std::to_string(modulo - 1));
            continue;
          }
          field.start = static_cast<std::uint64_t>(*start);
        }
      } else if (item.contains("modulo") || item.contains("start")) {
        m_check.error(itemPath, "\"modulo\" and \"start\" belong to the counter algorithm");
        continue;
      }
      if (field.algorithm == FieldAlgorithm::J1939Checksum4 && !message.extended) {
        m_check.error(itemPath + "/algorithm",
                      "j1939-checksum4 covers the 29-bit identifier; '" + message.name + "' has an 11-bit one");
        continue;
      }
      for (const ComputedField& existing : entry.computed) {
        if (existing.signal == field.signal) m_check.error(itemPath + "/signal", "'" + *name + "' is computed twice");
      }
      entry.computed.push_back(field);
    }
    // counters first: checksums cover them
    std::stable_partition(entry.computed.begin(), entry.computed.end(),
                          [](const ComputedField& field) { return field.algorithm == FieldAlgorithm::Counter; });
  }

  void addresses(const Json& settings, const std::string& path, const dbc::Message& message, ScheduledMessage& entry) {
    for (const char* key : {"destination", "source"}) {
      if (!settings.contains(key)) continue;
      const std::string keyPath = path + "/" + key;
      if (!message.extended) {
        m_check.error(keyPath,
                      "address substitution needs a 29-bit J1939 identifier; '" + message.name + "' has an 11-bit one");
        continue;
      }
      const auto address = parseAddress(settings.at(key));
      if (!address) {
        m_check.error(keyPath, "must be an address from 0 to 0xFF (a number or \"0x..\")");
        continue;
      }
      j1939::Id id = j1939::Id::fromCanId(entry.canId);
      if (std::string_view(key) == "destination") {
        if (!id.isPdu1()) {
          m_check.error(keyPath, "'" + message.name + "' is PDU2 (broadcast): it has no destination address");
          continue;
        }
        id.pduSpecific = static_cast<std::uint8_t>(*address);
      } else {
        id.sourceAddress = static_cast<std::uint8_t>(*address);
      }
      entry.canId = id.toCanId();
    }
  }

  void safety(const Json& settings, const std::string& path, const dbc::Message& message, ScheduledMessage& entry) {
    const Json* object = m_check.member(settings, path, "safety", false);
    if (object == nullptr || !m_check.isObject(*object, path + "/safety")) return;
    m_check.onlyKeys(*object, path + "/safety", {"deltaUs", "comment"});
    const auto delta = m_check.number(*object, path + "/safety", "deltaUs");
    if (!delta) return;
    if (!message.extended || message.length != j1939::SAFETY_MESSAGE_LENGTH) {
      m_check.error(path + "/safety",
                    "a J1939-76 safety data message is an 8-byte 29-bit frame; '" + message.name + "' is not");
      return;
    }
    if (!(*delta >= 1 && *delta <= 100'000) || *delta != std::floor(*delta)) {
      m_check.error(path + "/safety/deltaUs", "must be a whole number of microseconds from 1 to 100000");
      return;
    }
    const auto deltaNs = static_cast<std::int64_t>(*delta) * 1000;
    if (entry.cycleNs > 0 && deltaNs >= entry.cycleNs) {
      m_check.error(path + "/safety/deltaUs",
                    "must be shorter than the cycle (" + std::to_string(entry.cycleNs / 1000) + " us)");
      return;
    }
    entry.safetyDeltaNs = deltaNs;
  }

  void writers(const Json& root, Schedule& schedule) {
    const Json* list = m_check.array(root, "", "writers", false);
    if (list == nullptr) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = JsonChecker::join("/writers", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"service", "timeoutMs", "comment"});
      const auto service = m_check.string(item, path, "service");
      const auto timeout = m_check.number(item, path, "timeoutMs");
      if (!service || !timeout) continue;
      const auto heartbeat = m_catalog.indexOf("internal.service." + *service + ".heartbeat");
      if (!heartbeat) {
        std::vector<std::string> names(config::SERVICES.begin(), config::SERVICES.end());
        m_check.error(path + "/service", "unknown service '" + *service + "'" + suggestion(*service, names));
        continue;
      }
      if (*service == "can-tx") {
        m_check.error(path + "/service", "can-tx cannot watch its own heartbeat");
        continue;
      }
      if (!(*timeout > 1000 && *timeout <= 600'000)) {
        m_check.error(path + "/timeoutMs", "must be above 1000 (the heartbeat period) and at most 600000 ms");
        continue;
      }
      schedule.writers.push_back(
          WatchedWriter{*service, *heartbeat, static_cast<std::int64_t>(std::llround(*timeout * NS_PER_MS))});
    }
  }

  void safeValues(const Json& root, Schedule& schedule) {
    const Json* map = m_check.member(root, "", "safeValues", false);
    if (map == nullptr || !m_check.isObject(*map, "/safeValues")) return;
    if (!map->empty() && !root.contains("writers")) {
      m_check.error("/safeValues", "safe values apply when a watched writer dies; list the writers under /writers");
    }
    for (const auto& [key, value] : map->items()) {
      const std::string path = JsonChecker::join("/safeValues", key);
      const auto index = m_catalog.indexOf(key);
      if (!index) {
        std::string text = "unknown signal '" + key + "'";
        if (auto maybe = m_catalog.suggest(key)) text += " (did you mean '" + *maybe + "'?)";
        m_check.error(path, std::move(text));
        continue;
      }
      if (!value.is_number() || !std::isfinite(value.get<double>())) {
        m_check.error(path, "must be a number (the physical value)");
        continue;
      }
      const signals::SignalInfo& info = m_catalog[*index];
      const double number = value.get<double>();
      if (info.minimum < info.maximum && (number < info.minimum || number > info.maximum)) {
        std::ostringstream text;
        text << "value " << number << " is outside the range [" << info.minimum << ", " << info.maximum << "]";
        m_check.error(path, text.str());
        continue;
      }
      schedule.safeValues.push_back(SafeValue{*index, number});
    }
  }

  void timeDate(const Json& root, Schedule& schedule) {
    const Json* object = m_check.member(root, "", "timeDate", false);
    if (object == nullptr || !m_check.isObject(*object, "/timeDate")) return;
    m_check.onlyKeys(*object, "/timeDate", {"localHourOffset", "localMinuteOffset", "comment"});
    if (auto hours = m_check.number(*object, "/timeDate", "localHourOffset", false)) {
      if (!(*hours >= -23 && *hours <= 23) || *hours != std::floor(*hours)) {
        m_check.error("/timeDate/localHourOffset", "must be a whole number from -23 to 23");
      } else {
        schedule.localHourOffset = static_cast<std::int8_t>(*hours);
      }
    }
    if (auto minutes = m_check.number(*object, "/timeDate", "localMinuteOffset", false)) {
      if (!(*minutes >= -59 && *minutes <= 59) || *minutes != std::floor(*minutes)) {
        m_check.error("/timeDate/localMinuteOffset", "must be a whole number from -59 to 59");
      } else {
        schedule.localMinuteOffset = static_cast<std::int8_t>(*minutes);
      }
    }
  }

  const config::VehicleConfig& m_vehicle;
  const signals::Catalog& m_catalog;
  JsonChecker& m_check;
};

}  // namespace

std::optional<std::string> checkSignalValue(const dbc::Signal& signal, double value) {
  if (!std::isfinite(value)) return "the value must be a finite number";
  if (signal.minimum < signal.maximum && (value < signal.minimum || value > signal.maximum)) {
    std::ostringstream text;
    text << "value " << value << " is outside the range [" << signal.minimum << ", " << signal.maximum << "]"
         << (signal.unit.empty() ? "" : " " + signal.unit) << " of '" << signal.name << "'";
    return text.str();
  }
  return std::nullopt;
}

std::string_view fieldAlgorithmName(FieldAlgorithm algorithm) noexcept {
  for (const auto& known : ALGORITHMS) {
    if (known.algorithm == algorithm) return known.name;
  }
  return "?";
}

const ScheduledMessage* Schedule::find(std::size_t messageIndex) const noexcept {
  for (const ScheduledMessage& entry : messages) {
    if (entry.message == messageIndex) return &entry;
  }
  return nullptr;
}

ScheduledMessage* Schedule::find(std::size_t messageIndex) noexcept {
  for (ScheduledMessage& entry : messages) {
    if (entry.message == messageIndex) return &entry;
  }
  return nullptr;
}

Result<Schedule> loadSchedule(const config::VehicleConfig& vehicle, const signals::Catalog& catalog) {
  std::optional<Json> document;
  const std::string fileName = vehicle.scheduleFile.empty() ? vehicle.path : vehicle.scheduleFile;
  if (!vehicle.scheduleFile.empty()) {
    auto jsonResult = config::readJsonFile(vehicle.scheduleFile);
    if (!jsonResult) return jsonResult.error();
    document = std::move(*jsonResult);
  }
  JsonChecker check(fileName);
  Loader loader(vehicle, catalog, check);
  Schedule schedule = loader.run(document ? &*document : nullptr);
  if (!check.ok()) return check.firstError();
  if (auto problem = checkBusLoad(schedule, vehicle)) return Error{*problem, Location::json(fileName, "/")};
  return schedule;
}

std::optional<std::string> checkBusLoad(const Schedule& schedule, const config::VehicleConfig& vehicle) {
  struct Share {
    std::size_t message{};
    double load{};
  };
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    const config::BusConfig& bus = vehicle.buses[b];
    std::vector<config::CyclicFrame> frames;
    std::vector<Share> shares;
    for (const ScheduledMessage& entry : schedule.messages) {
      if (entry.bus != b || entry.cycleNs <= 0) continue;
      const dbc::Message& message = vehicle.database.messages[entry.message];
      const auto length = static_cast<std::uint8_t>(std::min<std::size_t>(message.length, can::MAX_DATA_LENGTH));
      const std::size_t first = frames.size();
      frames.push_back(config::CyclicFrame{entry.canId, entry.extended, length, entry.cycleNs});
      if (entry.safetyDeltaNs) {  // the SHM goes out before every SDM
        frames.push_back(config::CyclicFrame{j1939::safetyHeaderCanId(entry.canId), true,
                                             static_cast<std::uint8_t>(j1939::SAFETY_MESSAGE_LENGTH), entry.cycleNs});
      }
      shares.push_back(Share{entry.message, config::cyclicBusLoad(std::span(frames).subspan(first), bus)});
    }
    const double load = config::cyclicBusLoad(frames, bus);
    if (load <= config::MAX_CYCLIC_BUS_LOAD) continue;
    std::sort(shares.begin(), shares.end(),
              [](const Share& left, const Share& right) { return left.load > right.load; });
    const auto percent = [](double share) {
      std::ostringstream text;
      text << std::fixed << std::setprecision(1) << share * 100 << " %";
      return text.str();
    };
    std::string heaviest;
    for (std::size_t i = 0; i < std::min<std::size_t>(3, shares.size()); ++i) {
      const ScheduledMessage& entry = *schedule.find(shares[i].message);
      heaviest += std::string(i == 0 ? "" : ", ") + vehicle.database.messages[shares[i].message].name + " every " +
                  config::formatNumber(static_cast<double>(entry.cycleNs) / NS_PER_MS) +
                  " ms: " + percent(shares[i].load);
    }
    return "the cyclic frames on bus '" + bus.name + "' would take " + percent(load) + " of its " +
           std::to_string(bus.bitrate) + " bit/s, more than the " + percent(config::MAX_CYCLIC_BUS_LOAD) +
           " the VCU may use (largest: " + heaviest + "); lengthen those cycles";
  }
  return std::nullopt;
}

std::vector<std::string> safetyIdentityWarnings(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                                std::optional<std::size_t> only) {
  const auto hex = [](std::uint32_t value, int digits) {
    std::ostringstream text;
    text << "0x" << std::uppercase << std::hex << std::setw(digits) << std::setfill('0') << value;
    return text.str();
  };
  const auto describe = [&](const ScheduledMessage& message) {
    return vehicle.database.messages[message.message].name + " (" + hex(message.canId, 8) +
           (message.safetyDeltaNs ? ", J1939-76 SDM)" : ")");
  };
  std::vector<std::string> warnings;
  const std::vector<ScheduledMessage>& messages = schedule.messages;
  for (std::size_t a = 0; a < messages.size(); ++a) {
    for (std::size_t b = a + 1; b < messages.size(); ++b) {
      const ScheduledMessage& first = messages[a];
      const ScheduledMessage& second = messages[b];
      if (only && *only != a && *only != b) continue;
      if (!first.extended || !second.extended || first.bus != second.bus) continue;
      if (!first.safetyDeltaNs && !second.safetyDeltaNs) continue;
      if (!j1939::sameSafetyIdentity(first.canId, second.canId)) continue;
      const j1939::Id id = j1939::Id::fromCanId(first.canId);
      warnings.push_back(describe(first) + " and " + describe(second) + " have the same PGN " + hex(id.pgn(), 4) +
                         ", source " + hex(id.sourceAddress, 2) + " and destination " + hex(id.destination(), 2) +
                         " on bus " + vehicle.buses[first.bus].name +
                         ": a J1939-76 receiver tells an SDM by these alone, not the priority (can-tx never sends "
                         "one between the other's SHM and SDM)");
    }
  }
  return warnings;
}

std::optional<std::string> checkCycle(const ScheduledMessage& message, double cycleMs) {
  if (auto problem = config::checkCycleMs(cycleMs)) return problem;
  if (message.safetyDeltaNs && static_cast<double>(*message.safetyDeltaNs) >= cycleMs * NS_PER_MS) {
    return "the cycle must be longer than the SHM-to-SDM delta (" + std::to_string(*message.safetyDeltaNs / 1000) +
           " us)";
  }
  return std::nullopt;
}

Result<ScheduledMessage> runtimeMessage(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                        const signals::Catalog& catalog, std::string_view name, double cycleMs) {
  const dbc::Message* message = vehicle.database.findMessage(name);
  if (message == nullptr || message->pseudo) {
    return Error{"unknown message '" + std::string(name) + "'" + suggestion(name, messageNames(vehicle))};
  }
  const auto index = static_cast<std::size_t>(message - vehicle.database.messages.data());
  const config::BusConfig* bus = vehicle.busOf(index);
  if (bus == nullptr) return Error{"message '" + message->name + "' is on no configured bus"};
  if (isSafetyHeader(*message)) {
    return Error{"'" + message->name + "' is a J1939-76 safety header: it goes out with its SDM"};
  }
  if (message->length > can::MAX_DATA_LENGTH) {
    return Error{"'" + message->name + "' is " + std::to_string(message->length) +
                 " bytes: longer than a CAN frame (transport protocol sending is not supported)"};
  }
  if (schedule.find(index) != nullptr) {
    return Error{"'" + message->name +
                 "' is already in the transmit schedule (change it with ScheduleCycle / ScheduleEnable)"};
  }
  ScheduledMessage entry;
  entry.message = index;
  entry.bus = static_cast<std::size_t>(bus - vehicle.buses.data());
  entry.canId = message->id;
  entry.extended = message->extended;
  entry.added = true;
  if (auto problem = checkCycle(entry, cycleMs)) return Error{*problem};
  entry.cycleNs = static_cast<std::int64_t>(std::llround(cycleMs * NS_PER_MS));
  entry.defaults.assign(message->signals.size(), std::nullopt);
  for (const dbc::Signal& signal : message->signals) {
    entry.keys.push_back(catalog.indexOf(config::signalKey(*message, signal)));
  }
  Schedule withEntry = schedule;  // a copy per added message: commands and overlay loading, never per frame
  withEntry.messages.push_back(entry);
  if (auto problem = checkBusLoad(withEntry, vehicle)) return Error{*problem};
  return entry;
}

Result<std::size_t> findScheduled(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                  std::string_view name) {
  const dbc::Message* message = vehicle.database.findMessage(name);
  if (message == nullptr) {
    return Error{"unknown message '" + std::string(name) + "'" + suggestion(name, messageNames(vehicle))};
  }
  const auto index = static_cast<std::size_t>(message - vehicle.database.messages.data());
  for (std::size_t s = 0; s < schedule.messages.size(); ++s) {
    if (schedule.messages[s].message == index) return s;
  }
  std::string text(name);
  text.insert(0, 1, '\'');
  text += "' is not in the transmit schedule";
  return Error{std::move(text)};
}

Result<SignalRef> findScheduledSignal(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                      const signals::Catalog& catalog, std::string_view key) {
  const auto index = catalog.indexOf(key);
  if (!index) {
    std::string text = "unknown signal '" + std::string(key) + "'";
    if (auto maybe = catalog.suggest(key)) text += " (did you mean '" + *maybe + "'?)";
    return Error{text};
  }
  for (std::size_t s = 0; s < schedule.messages.size(); ++s) {
    const ScheduledMessage& entry = schedule.messages[s];
    for (std::uint32_t i = 0; i < entry.keys.size(); ++i) {
      if (entry.keys[i] == index) return SignalRef{s, i};
    }
  }
  (void)vehicle;
  std::string text(key);
  text.insert(0, 1, '\'');
  text += "' is not a signal of a scheduled message";
  return Error{std::move(text)};
}

}  // namespace openvcu::schedule
