#include "openvcu/config/vehicle.hpp"

#include "bus_j1939.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/dbc/parser.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <unordered_map>

namespace openvcu::config {

namespace fs = std::filesystem;

std::string Link::toString() const {
  switch (kind) {
    case LinkKind::SocketCan: return "socketcan:" + target;
    case LinkKind::Sim: return "sim:" + target;
    case LinkKind::Replay: return "replay:" + target;
  }
  return target;
}

bool validInstanceName(std::string_view name) noexcept {
  if (name.empty() || name.size() > 32) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
  });
}

namespace {

/// fs::exists without exceptions: a name over 255 characters (ENAMETOOLONG) made the
/// throwing overload end every service in std::terminate (fuzz_vehicle). Such a path
/// counts as missing; the file's own open reports the reason.
bool existsNoThrow(const std::string& path) noexcept {
  std::error_code error;
  return fs::exists(path, error);
}

bool validSignalName(std::string_view name) {
  if (name.empty() || name.front() == '.' || name.back() == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.';
  });
}

std::string resolvePath(const std::string& directory, const std::string& file) {
  const fs::path p(file);
  return p.is_absolute() ? p.lexically_normal().string() : (fs::path(directory) / p).lexically_normal().string();
}

}  // namespace

Result<Link> parseLink(std::string_view text, const std::string& baseDirectory) {
  const auto colon = text.find(':');
  const std::string_view scheme = text.substr(0, colon);
  const std::string target(colon == std::string_view::npos ? std::string_view{} : text.substr(colon + 1));
  const Error usage{"unknown link '" + std::string(text) + "'; expected socketcan:IFACE, sim:NAME or replay:FILE"};
  if (colon == std::string_view::npos || target.empty()) return usage;
  if (scheme == "socketcan") {
    if (target.size() > 15 || target.find('/') != std::string::npos) {
      return Error{"'" + target + "' is not a network interface name (at most 15 characters, no '/')"};
    }
    return Link{LinkKind::SocketCan, target};
  }
  if (scheme == "sim") {
    if (!validInstanceName(target)) return Error{"simulated bus name '" + target + "' must be letters, digits, '-', '_'"};
    return Link{LinkKind::Sim, target};
  }
  if (scheme == "replay") return Link{LinkKind::Replay, resolvePath(baseDirectory, target)};
  return usage;
}

can::LinkOptions BusConfig::linkOptions() const {
  can::LinkOptions options;
  options.bitrate = bitrate;
  options.dataBitrate = dataBitrate;
  options.fd = fd;
  options.replaySpeed = replay.speed;
  options.replayLoop = replay.loop;
  options.replayChannel = replay.channel;
  return options;
}

const BusConfig* VehicleConfig::busOf(std::size_t messageIndex) const noexcept {
  for (const BusConfig& bus : buses) {
    if (std::find(bus.messages.begin(), bus.messages.end(), messageIndex) != bus.messages.end()) return &bus;
  }
  return nullptr;
}

const BusConfig* VehicleConfig::findBus(std::string_view name) const noexcept {
  for (const BusConfig& bus : buses) {
    if (bus.name == name) return &bus;
  }
  return nullptr;
}

namespace {

class Loader {
 public:
  Loader(const std::string& path, JsonChecker& check) : m_check(check) {
    m_config.path = path;
    m_config.directory = fs::path(path).parent_path().string();
    if (m_config.directory.empty()) m_config.directory = ".";
  }

  void run(const Json& root) {
    if (!m_check.isObject(root, "")) return;
    m_check.onlyKeys(root, "", {"instance", "node", "dbc", "buses", "fsm", "schedule", "gpio", "simulation",
                                "receive", "diagnostics", "web", "telemetry", "safety", "internalSignals", "lcm", "commandGroup", "comment"});
    instance(root);
    dbcFiles(root);
    node(root);
    buses(root);
    files(root);
    internalSignals(root);
    lcm(root);
    commandGroup(root);
    gpio();
  }

  VehicleConfig& config() { return m_config; }

 private:
  void instance(const Json& root) {
    const auto name = m_check.string(root, "", "instance");
    if (!name) return;
    if (!validInstanceName(*name)) {
      m_check.error("/instance", "'" + *name + "' must be 1-32 letters, digits, '-' or '_'");
      return;
    }
    m_config.instance = *name;
  }

  void dbcFiles(const Json& root) {
    const Json* list = m_check.member(root, "", "dbc", true);
    if (!list) return;
    std::vector<std::string> files;
    if (list->is_string()) {
      files.push_back(list->get<std::string>());
    } else if (list->is_array() && !list->empty()) {
      for (std::size_t i = 0; i < list->size(); ++i) {
        if (!(*list)[i].is_string()) {
          m_check.error(JsonChecker::join("/dbc", i), "must be a file name");
          return;
        }
        files.push_back((*list)[i].get<std::string>());
      }
    } else {
      m_check.error("/dbc", "must be a file name or a non-empty list of file names");
      return;
    }
    for (const auto& file : files) m_config.dbcFiles.push_back(resolvePath(m_config.directory, file));
    std::vector<Error> warnings;
    auto loaded = dbc::loadFiles(m_config.dbcFiles, &warnings);
    for (Error& warning : warnings) m_dbcWarnings.push_back(std::move(warning));
    if (!loaded) {
      m_dbcError = loaded.error();
      m_check.error("/dbc", "cannot be loaded: " + loaded.error().toString());
      return;
    }
    m_config.database = std::move(*loaded);
    m_dbcLoaded = true;
  }

  void node(const Json& root) {
    const auto name = m_check.string(root, "", "node");
    if (!name || !m_dbcLoaded) return;
    if (!m_config.database.findNode(*name)) {
      std::vector<std::string> names;
      for (const auto& n : m_config.database.nodes) names.push_back(n.name);
      std::string message = "node '" + *name + "' is not in the DBC's BU_ list";
      if (auto suggestion = text::didYouMean(*name, names)) message += "; did you mean '" + *suggestion + "'?";
      m_check.error("/node", std::move(message));
      return;
    }
    m_config.node = *name;
  }

  void buses(const Json& root) {
    const Json* list = m_check.array(root, "", "buses");
    if (!list) return;
    if (list->empty()) m_check.error("/buses", "at least one bus is needed");
    std::unordered_map<std::size_t, std::string> owner;  // message index -> bus
    std::optional<std::uint8_t> vcuAddress;  // the default J1939 preferredAddress
    if (const dbc::Node* self = m_config.database.findNode(m_config.node)) {
      vcuAddress = nodeAddress(m_config.database, *self);
    }
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = JsonChecker::join("/buses", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"name", "link", "bitrate", "dataBitrate", "fd", "filter", "replay", "messages",
                                      "j1939", "comment"});
      BusConfig bus;
      if (auto name = m_check.string(item, path, "name")) {
        if (!validInstanceName(*name)) m_check.error(path + "/name", "bus names are letters, digits, '-', '_'");
        if (m_config.findBus(*name)) m_check.error(path + "/name", "bus '" + *name + "' is defined twice");
        bus.name = *name;
      }
      if (auto link = m_check.string(item, path, "link")) {
        auto parsed = parseLink(*link, m_config.directory);
        if (!parsed) {
          m_check.error(path + "/link", parsed.error().message);
        } else {
          bus.link = *parsed;
          if (bus.link.kind == LinkKind::Replay && !existsNoThrow(bus.link.target)) {
            m_check.error(path + "/link", "replay file '" + bus.link.target + "' does not exist");
          }
        }
      }
      if (auto bitrate = m_check.number(item, path, "bitrate", false)) {
        if (*bitrate < 10000 || *bitrate > 8000000 || *bitrate != std::floor(*bitrate)) {
          m_check.error(path + "/bitrate", "must be a whole number of bit/s between 10000 and 8000000");
        } else {
          bus.bitrate = static_cast<std::uint32_t>(*bitrate);
        }
      }
      if (auto dataBitrate = m_check.number(item, path, "dataBitrate", false)) {
        if (*dataBitrate < 10000 || *dataBitrate > 16000000 || *dataBitrate != std::floor(*dataBitrate)) {
          m_check.error(path + "/dataBitrate", "must be a whole number of bit/s between 10000 and 16000000");
        } else {
          bus.dataBitrate = static_cast<std::uint32_t>(*dataBitrate);
        }
      }
      if (auto fd = m_check.boolean(item, path, "fd", false)) bus.fd = *fd;
      if (auto filter = m_check.string(item, path, "filter", false)) {
        if (*filter == "dbc") {
          bus.filter = BusFilter::Dbc;
        } else if (*filter == "all") {
          bus.filter = BusFilter::All;
        } else {
          m_check.error(path + "/filter", "must be \"dbc\" (the bus' DBC messages) or \"all\"");
        }
      }
      replay(item, path, bus);
      messages(item, path, bus, owner);
      loadBusJ1939(item, path, vcuAddress, m_check, bus.j1939);
      m_config.buses.push_back(std::move(bus));
    }
  }

  void replay(const Json& item, const std::string& path, BusConfig& bus) {
    const Json* settings = m_check.member(item, path, "replay", false);
    if (!settings) return;
    const std::string replayPath = path + "/replay";
    if (!m_check.isObject(*settings, replayPath)) return;
    m_check.onlyKeys(*settings, replayPath, {"speed", "loop", "channel", "comment"});
    if (bus.link.kind != LinkKind::Replay) {
      m_check.error(replayPath, "only a replay:FILE link takes replay settings");
    }
    if (auto speed = m_check.number(*settings, replayPath, "speed", false)) {
      if (!(*speed >= 0.0 && *speed <= 1000.0)) {
        m_check.error(replayPath + "/speed", "must be between 0 (as fast as possible) and 1000");
      } else {
        bus.replay.speed = *speed;
      }
    }
    if (auto loop = m_check.boolean(*settings, replayPath, "loop", false)) bus.replay.loop = *loop;
    if (auto channel = m_check.string(*settings, replayPath, "channel", false)) bus.replay.channel = *channel;
  }

  void messages(const Json& item, const std::string& path, BusConfig& bus,
                std::unordered_map<std::size_t, std::string>& owner) {
    const Json* list = m_check.member(item, path, "messages", true);
    if (!list || !m_dbcLoaded) return;
    const auto& messages = m_config.database.messages;
    const std::string listPath = path + "/messages";
    auto claim = [&](std::size_t index, const std::string& where) {
      const auto [it, inserted] = owner.emplace(index, bus.name);
      if (!inserted) {
        m_check.error(where, "message '" + messages[index].name + "' is already on bus '" + it->second +
                                 "'; a message lives on one bus");
        return;
      }
      bus.messages.push_back(index);
    };
    if (list->is_string() && list->get<std::string>() == "all") {
      // Every frame message not claimed by an earlier bus.
      for (std::size_t m = 0; m < messages.size(); ++m) {
        if (!messages[m].pseudo && !owner.count(m)) claim(m, listPath);
      }
      return;
    }
    if (!list->is_array()) {
      m_check.error(listPath, "must be \"all\" or a list of DBC message names");
      return;
    }
    std::vector<std::string> names;
    for (const auto& msg : messages) names.push_back(msg.name);
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string where = JsonChecker::join(listPath, i);
      if (!(*list)[i].is_string()) {
        m_check.error(where, "must be a message name");
        continue;
      }
      const std::string name = (*list)[i].get<std::string>();
      const dbc::Message* msg = m_config.database.findMessage(name);
      if (!msg || msg->pseudo) {
        std::string message = "no message '" + name + "' in the DBC";
        if (auto suggestion = text::didYouMean(name, names)) message += "; did you mean '" + *suggestion + "'?";
        m_check.error(where, std::move(message));
        continue;
      }
      claim(static_cast<std::size_t>(msg - messages.data()), where);
    }
  }

  void files(const Json& root) {
    const std::pair<std::string_view, std::string*> entries[] = {{"fsm", &m_config.fsmFile},
                                                                 {"schedule", &m_config.scheduleFile},
                                                                 {"gpio", &m_config.gpioFile},
                                                                 {"simulation", &m_config.simulationFile},
                                                                 {"receive", &m_config.receiveFile},
                                                                 {"diagnostics", &m_config.diagnosticsFile},
                                                                 {"web", &m_config.webFile},
                                                                 {"telemetry", &m_config.telemetryFile},
                                                                 {"safety", &m_config.safetyFile}};
    for (const auto& [key, target] : entries) {
      const auto file = m_check.string(root, "", key, false);
      if (!file) continue;
      *target = resolvePath(m_config.directory, *file);
      if (!existsNoThrow(*target)) m_check.error("/" + std::string(key), "file '" + *target + "' does not exist");
    }
  }

  void internalSignals(const Json& root) {
    const Json* list = m_check.array(root, "", "internalSignals", false);
    if (!list) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = JsonChecker::join("/internalSignals", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"name", "unit", "min", "max", "initial", "comment", "values"});
      InternalSignal sig;
      if (auto name = m_check.string(item, path, "name")) {
        if (!validSignalName(*name)) {
          m_check.error(path + "/name", "'" + *name + "' must be letters, digits, '_' and '.'");
        }
        // A hashed set: a linear search here made 100,000 signals take 17 s to load.
        if (const auto [where, fresh] = m_internalNames.emplace(*name, path); !fresh) {
          m_check.error(path + "/name",
                        "internal signal '" + *name + "' is declared twice (first at " + where->second + ")");
        }
        sig.name = *name;
      }
      sig.unit = m_check.string(item, path, "unit", false).value_or("");
      sig.comment = m_check.string(item, path, "comment", false).value_or("");
      sig.minimum = m_check.number(item, path, "min", false).value_or(0.0);
      sig.maximum = m_check.number(item, path, "max", false).value_or(1.0);
      sig.initial = m_check.number(item, path, "initial", false).value_or(sig.minimum);
      if (sig.minimum > sig.maximum) m_check.error(path + "/min", "min is above max");
      if (sig.initial < sig.minimum || sig.initial > sig.maximum) {
        m_check.error(path + "/initial", "initial value outside [min, max]");
      }
      if (const Json* values = m_check.member(item, path, "values", false)) {
        if (!values->is_object()) {
          m_check.error(path + "/values", "must be an object {\"0\": \"Off\", \"1\": \"On\"}");
        } else {
          for (const auto& entry : values->items()) {
            const std::string where = path + "/values/" + entry.key();
            std::int64_t key = 0;
            const auto& k = entry.key();
            const auto parsed = std::from_chars(k.data(), k.data() + k.size(), key);
            if (parsed.ec != std::errc{} || parsed.ptr != k.data() + k.size()) {
              m_check.error(where, "value keys must be integers");
            } else if (!entry.value().is_string()) {
              m_check.error(where, "value text must be a string");
            } else {
              sig.values.push_back(dbc::ValueDescription{key, entry.value().get<std::string>()});
            }
          }
        }
      }
      m_config.internalSignals.push_back(std::move(sig));
    }
  }

  /// The GPIO map is part of the configuration: its lines add status keys to the catalog.
  void gpio() {
    if (m_config.gpioFile.empty() || !existsNoThrow(m_config.gpioFile)) return;
    auto map = loadGpioMap(m_config.gpioFile, m_config.internalSignals, m_otherFiles);
    if (map) m_config.gpio = std::move(*map);
  }

  void commandGroup(const Json& root) {
    const auto group = m_check.string(root, "", "commandGroup", false);
    if (!group) return;
    const bool valid = !group->empty() && group->size() <= 32 && std::all_of(group->begin(), group->end(), [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    });
    if (!valid) {
      m_check.error("/commandGroup", "must be a Unix group name (1-32 letters, digits, '_' or '-')");
      return;
    }
    m_config.commandGroup = *group;
  }

  void lcm(const Json& root) {
    const auto url = m_check.string(root, "", "lcm", false);
    if (!url) return;
    if (url->rfind("tcpq://", 0) == 0) {
      m_check.error("/lcm",
                    "tcpq:// is refused: its hub relays events from any client that reaches its port, "
                    "so events could come from another host; use udpm://...?ttl=0");
      return;
    }
    static constexpr std::string_view SCHEMES[] = {"udpm://", "memq://", "file://"};
    const bool known = std::any_of(std::begin(SCHEMES), std::end(SCHEMES),
                                   [&](std::string_view scheme) { return url->rfind(scheme, 0) == 0; });
    if (!known) {
      m_check.error("/lcm", "LCM URL must start with udpm://, memq:// or file://");
      return;
    }
    if (url->rfind("udpm://", 0) == 0 && url->find("ttl=0") == std::string::npos) {
      m_check.warning("/lcm", "udpm without ttl=0 sends events beyond this host");
    }
    m_config.lcmUrl = *url;
  }

 public:
  std::vector<Error> m_dbcWarnings;
  std::optional<Error> m_dbcError;
  std::vector<Error> m_otherFiles;  ///< diagnostics of the files loaded with it (gpio.json)

 private:
  JsonChecker& m_check;
  VehicleConfig m_config;
  std::unordered_map<std::string, std::string> m_internalNames;  ///< internal signal name -> its JSON path
  bool m_dbcLoaded{false};
};

}  // namespace

std::vector<Error> checkVehicleConfig(const std::string& path) {
  auto json = readJsonFile(path);
  if (!json) return {json.error()};
  JsonChecker check(path);
  Loader loader(path, check);
  loader.run(*json);
  std::vector<Error> all = loader.m_dbcWarnings;
  if (loader.m_dbcError) all.push_back(*loader.m_dbcError);
  for (const Error& diagnostic : check.diagnostics()) all.push_back(diagnostic);
  for (const Error& diagnostic : loader.m_otherFiles) all.push_back(diagnostic);
  return all;
}

Result<VehicleConfig> loadVehicleConfig(const std::string& path, std::vector<Error>* warnings) {
  auto json = readJsonFile(path);
  if (!json) return json.error();
  JsonChecker check(path);
  Loader loader(path, check);
  loader.run(*json);
  if (loader.m_dbcError) return *loader.m_dbcError;
  if (!check.ok()) return check.firstError();
  for (const Error& diagnostic : loader.m_otherFiles) {
    if (diagnostic.severity == Severity::Error) return diagnostic;
  }
  if (warnings) {
    warnings->insert(warnings->end(), loader.m_dbcWarnings.begin(), loader.m_dbcWarnings.end());
    for (const Error& diagnostic : check.diagnostics()) warnings->push_back(diagnostic);
    warnings->insert(warnings->end(), loader.m_otherFiles.begin(), loader.m_otherFiles.end());
  }
  return std::move(loader.config());
}

}  // namespace openvcu::config
