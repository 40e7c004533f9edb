// `vcu fleet watch|get`. The descriptions and footers are their manual. An MQTT v5 client
// on libmosquitto driven from this thread (mosquitto_loop), folding every message into a
// fleet::FleetView (shared/fleet: the topic layout and payload parsing shared with vcu-telemetry).
#include "fleet_commands.hpp"

#include <mosquitto.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "cli_checks.hpp"
#include "diagnostics.hpp"
#include "openvcu/config/telemetry.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/fleet/fleet_view.hpp"
#include "stack_access.hpp"
#include "stop_signal.hpp"
#include "text_table.hpp"

namespace openvcu::cli {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int KEEPALIVE_S = 10;
constexpr int QOS_AT_LEAST_ONCE = 1;
/// How long to wait for the broker's CONNACK and SUBACKs before giving up.
constexpr auto CONNECT_TIMEOUT = std::chrono::seconds(5);
/// --once and get end after this long without a message (the retained ones come at once).
constexpr auto QUIET_END = std::chrono::milliseconds(1000);
/// A terminal is redrawn at most this often (2 Hz), and at least once a second for the ages.
constexpr auto REDRAW_MIN = std::chrono::milliseconds(500);
constexpr auto REDRAW_MAX = std::chrono::milliseconds(1000);
constexpr int LOOP_TIMEOUT_MS = 100;

constexpr const char* FLEET_DESCRIPTION = "The vehicles on an MQTT broker as vcu-telemetry publishes them";
constexpr const char* WATCH_DESCRIPTION = "Every vehicle the broker knows, one line each, refreshed live";
constexpr const char* WATCH_FOOTER =
    "Subscribes to openvcu/+/status, birth, state, faults, health and signals (the topics\n"
    "of docs/design/telemetry.md) and shows one line per vehicle: VEHICLE, LINK (online or\n"
    "offline: the retained status, the last will when the link died; ? before one came),\n"
    "STATE (the FSM state of its last transition), FAULTS (active fault events with the\n"
    "worst severity, and the DM1 DTCs of its nodes: \"2 error + 1 DTC\"), SOC (the newest\n"
    "value of --soc-signal NAME, else of the first of its telemetry signals whose name ends\n"
    "in SOC), LAST (age of its newest message's time stamp \"t\", the vehicle's clock).\n"
    "Only status and birth are retained by the broker: the state, faults, health and signals\n"
    "of a vehicle show once it sends them (a transition, a change, health every 10 s).\n"
    "On a terminal the table is redrawn (at most twice a second); in a pipe one line per\n"
    "change of a vehicle's line (the time, then the columns). --once collects for at most\n"
    "--wait seconds (default 3; less when 1 s passes without a message), prints the table\n"
    "and exits.\n"
    "\n"
    "Examples:\n"
    "  vcu fleet watch --broker mqtt://127.0.0.1:1883\n"
    "  vcu fleet watch --once --broker mqtts://fleet.example.com --username ops --password-file pw\n"
    "Exit: 0 shown, 1 the broker cannot be reached or refused the login, 2 usage error.\n";
constexpr const char* GET_DESCRIPTION = "One value of one vehicle: status, state, faults, health or a signal";
constexpr const char* GET_FOOTER =
    "Collects as watch --once does (at most --wait seconds; it returns as soon as the value\n"
    "is known) and prints one value: status (online, offline), state (the FSM state of its\n"
    "last transition), faults (\"2 active, worst error: source/name text; ...\"), health\n"
    "(\"6/6 services Ready; queue 0 pending, 0 dropped\"), or a signal's name (its newest\n"
    "value). State, faults, health and signals are not retained: they are known once the\n"
    "vehicle sends them within the wait.\n"
    "\n"
    "Examples:\n"
    "  vcu fleet get hhea-01 status --broker mqtt://127.0.0.1:1883\n"
    "  vcu fleet get hhea-01 VIC.HVESSD2_PGN61585.HS_FastUpdSOC --broker mqtt://127.0.0.1:1883 --wait 5\n"
    "Exit: 0 printed, 1 the broker cannot be reached, the vehicle is unknown or has not told\n"
    "the value, 2 usage error.\n";

/// libmosquitto is set up once per process (lib_init/lib_cleanup are not reference counted).
void initLibrary() {
  static const int once = [] { return mosquitto_lib_init(); }();
  (void)once;
}

/// An MQTT v5 subscriber to the fleet's topics, driven by pump() from one thread.
/// @note restricted thread-safe: one thread creates, pumps and destroys it.
class FleetClient {
 public:
  FleetClient() = default;
  FleetClient(const FleetClient&) = delete;
  FleetClient& operator=(const FleetClient&) = delete;
  ~FleetClient() {
    if (m_mosq == nullptr) return;
    if (m_connected) mosquitto_disconnect_v5(m_mosq, 0, nullptr);
    mosquitto_destroy(m_mosq);
  }

  /// Connects and subscribes; returns once the broker acknowledged every subscription, or
  /// an error saying why not (unreachable, refused login, timeout).
  Status open(const FleetOptions& options) {
    initLibrary();
    auto address = config::parseBrokerUrl(options.broker);
    if (!address) return Error{"--broker " + address.error().message};
    m_url = options.broker;
    m_mosq = mosquitto_new(nullptr, true, this);
    if (m_mosq == nullptr) return Error{"libmosquitto: cannot create a client (out of memory)"};
    mosquitto_int_option(m_mosq, MOSQ_OPT_PROTOCOL_VERSION, MQTT_PROTOCOL_V5);
    mosquitto_connect_v5_callback_set(m_mosq, [](mosquitto*, void* self, int reason, int, const mosquitto_property*) {
      static_cast<FleetClient*>(self)->onConnect(reason);
    });
    mosquitto_disconnect_v5_callback_set(m_mosq, [](mosquitto*, void* self, int, const mosquitto_property*) {
      static_cast<FleetClient*>(self)->m_connected = false;
    });
    mosquitto_subscribe_v5_callback_set(m_mosq,
                                        [](mosquitto*, void* self, int, int, const int*, const mosquitto_property*) {
                                          ++static_cast<FleetClient*>(self)->m_subscribed;
                                        });
    mosquitto_message_v5_callback_set(
        m_mosq, [](mosquitto*, void* self, const mosquitto_message* message, const mosquitto_property*) {
          static_cast<FleetClient*>(self)->onMessage(message);
        });
    if (!options.username.empty()) {
      std::string password;
      if (!options.passwordFile.empty()) {
        std::ifstream in(options.passwordFile);
        if (!in || !std::getline(in, password)) return Error{options.passwordFile + ": cannot read the password"};
      }
      if (const int rc = mosquitto_username_pw_set(m_mosq, options.username.c_str(),
                                                   options.passwordFile.empty() ? nullptr : password.c_str());
          rc != MOSQ_ERR_SUCCESS) {
        return Error{std::string("libmosquitto: username: ") + mosquitto_strerror(rc)};
      }
    } else if (!options.passwordFile.empty()) {
      return Error{"--password-file goes with --username"};
    }
    if (address->tls) {
      const bool systemStore = options.caFile.empty();
      if (const int rc = mosquitto_tls_set(m_mosq, systemStore ? nullptr : options.caFile.c_str(),
                                           systemStore ? "/etc/ssl/certs" : nullptr, nullptr, nullptr, nullptr);
          rc != MOSQ_ERR_SUCCESS) {
        return Error{std::string("libmosquitto: TLS: ") + mosquitto_strerror(rc)};
      }
    } else if (!options.caFile.empty()) {
      return Error{"--ca-file goes with an mqtts:// broker"};
    }
    const int rc = mosquitto_connect_async(m_mosq, address->host.c_str(), address->port, KEEPALIVE_S);
    if (rc != MOSQ_ERR_SUCCESS) return unreachable(rc);
    const auto deadline = Clock::now() + CONNECT_TIMEOUT;
    while (m_subscribed < static_cast<int>(fleet::ALL_TOPICS.size())) {
      if (!m_refusal.empty()) return Error{"the broker " + m_url + " refused the connection: " + m_refusal};
      if (Clock::now() >= deadline) {
        return Error{"the broker " + m_url +
                     (m_connected ? " did not acknowledge the subscriptions" : " did not answer") + " within " +
                     std::to_string(CONNECT_TIMEOUT.count()) + " s"};
      }
      if (stopRequested()) return Error{"stopped"};
      if (const int looped = mosquitto_loop(m_mosq, LOOP_TIMEOUT_MS, 1); looped != MOSQ_ERR_SUCCESS) {
        if (!m_refusal.empty()) continue;  // said above
        return unreachable(looped);
      }
    }
    return {};
  }

  /// Handles network traffic for at most `timeoutMs`; reconnects a lost link (once a second).
  void pump(int timeoutMs) {
    if (m_connected || m_subscribed == 0) {
      if (mosquitto_loop(m_mosq, timeoutMs, 1) == MOSQ_ERR_SUCCESS) return;
    }
    // the link is down: libmosquitto's loop does not reconnect by itself
    if (m_linkUp) {
      m_linkUp = false;
      m_linkChanged = true;
    }
    if (Clock::now() >= m_nextReconnect) {
      m_nextReconnect = Clock::now() + std::chrono::seconds(1);
      m_subscribed = 0;
      if (mosquitto_reconnect_async(m_mosq) == MOSQ_ERR_SUCCESS) {
        (void)mosquitto_loop(m_mosq, timeoutMs, 1);
        return;
      }
    }
    usleep(static_cast<useconds_t>(timeoutMs) * 1000);
  }

  fleet::FleetView& fleet() { return m_fleet; }
  /// Vehicles whose view changed since the last call.
  std::set<std::string> takeChanged() { return std::exchange(m_changed, {}); }
  /// Payloads that were not the format, since the last call ("topic: problem").
  std::vector<std::string> takeErrors() { return std::exchange(m_errors, {}); }
  /// True once after the link went down or came back; `up` says which.
  bool takeLinkChange(bool& up) {
    up = m_linkUp;
    return std::exchange(m_linkChanged, false);
  }
  [[nodiscard]] Clock::time_point lastMessage() const { return m_lastMessage; }

 private:
  Error unreachable(int rc) const {
    const std::string reason = rc == MOSQ_ERR_ERRNO ? std::string(std::strerror(errno)) : mosquitto_strerror(rc);
    return Error{"cannot reach the broker " + m_url + ": " + reason};
  }

  void onConnect(int reason) {
    if (reason != 0) {
      m_refusal = mosquitto_reason_string(reason);
      return;
    }
    m_connected = true;
    if (!m_linkUp) {
      m_linkUp = true;
      m_linkChanged = m_everConnected;
    }
    m_everConnected = true;
    m_subscribed = 0;
    for (const fleet::Topic topic : fleet::ALL_TOPICS) {
      mosquitto_subscribe_v5(m_mosq, nullptr, fleet::fleetFilter(topic).c_str(), QOS_AT_LEAST_ONCE, 0, nullptr);
    }
  }

  void onMessage(const mosquitto_message* message) {
    m_lastMessage = Clock::now();
    const std::string_view payload(static_cast<const char*>(message->payload),
                                   static_cast<std::size_t>(message->payloadlen));
    auto applied = m_fleet.apply(message->topic, payload);
    if (!applied) {
      m_errors.push_back(applied.error().message);
      return;
    }
    if (*applied) {
      if (const auto name = fleet::parseTopic(message->topic)) m_changed.insert(name->vehicleId);
    }
  }

  mosquitto* m_mosq{nullptr};
  std::string m_url;
  fleet::FleetView m_fleet;
  std::set<std::string> m_changed;
  std::vector<std::string> m_errors;
  std::string m_refusal;  ///< the CONNACK's reason when the broker refused
  int m_subscribed{};     ///< SUBACKs since the last connect
  bool m_connected{};
  bool m_everConnected{};
  bool m_linkUp{};
  bool m_linkChanged{};
  Clock::time_point m_nextReconnect{};
  Clock::time_point m_lastMessage{Clock::now()};
};

/// "0.4 s", "12 s", "3 min", "2 h" since `unixMs`; "-" when 0.
std::string ageText(std::int64_t unixMs, std::int64_t nowUnixMs) {
  if (unixMs <= 0) return "-";
  const std::int64_t ms = std::max<std::int64_t>(0, nowUnixMs - unixMs);
  if (ms < 10'000) return fleet::formatNumber(static_cast<double>(ms / 100) / 10) + " s";
  if (ms < 120'000) return std::to_string(ms / 1000) + " s";
  if (ms < 7'200'000) return std::to_string(ms / 60'000) + " min";
  return std::to_string(ms / 3'600'000) + " h";
}

const std::vector<std::string> COLUMNS{"VEHICLE", "LINK", "STATE", "FAULTS", "SOC", "LAST"};

/// The cells of a vehicle's line (COLUMNS).
std::vector<std::string> cellsOf(const fleet::VehicleView& vehicle, const std::string& socOption,
                                 std::int64_t nowUnixMs) {
  std::string link = "?";
  if (vehicle.online) link = *vehicle.online ? std::string(fleet::STATUS_ONLINE) : std::string(fleet::STATUS_OFFLINE);
  std::string faults = "-";
  if (vehicle.faults) {
    // "0", "2 error" (fault events and the worst severity), "1 DTC" (DM1), "2 error + 1 DTC"
    const std::int64_t dtcs = fleet::activeDtcCount(vehicle);
    const std::int64_t events = fleet::activeFaultCount(vehicle) - dtcs;
    faults = events > 0 || dtcs == 0 ? std::to_string(events) : std::string();
    if (const auto worst = fleet::worstFaultLevel(vehicle)) faults += " " + std::string(fleet::faultLevelName(*worst));
    if (dtcs > 0) faults += (faults.empty() ? "" : " + ") + std::to_string(dtcs) + " DTC";
  }
  std::string soc = "-";
  const std::string socName = fleet::socSignalOf(vehicle, socOption);
  if (const auto sample = vehicle.signals.find(socName); !socName.empty() && sample != vehicle.signals.end()) {
    soc = fleet::formatNumber(sample->second.value);
    if (vehicle.birth) {
      for (const fleet::BirthSignal& signal : vehicle.birth->signals) {
        if (signal.name == socName && !signal.unit.empty()) soc += " " + signal.unit;
      }
    }
  }
  return {vehicle.vehicleId,
          link,
          vehicle.state ? vehicle.state->state : "-",
          faults,
          soc,
          ageText(vehicle.newestUnixMs, nowUnixMs)};
}

/// "SOC: NAME (...)": which signal the SOC column shows.
std::string socNote(const fleet::FleetView& fleet, const std::string& socOption) {
  if (!socOption.empty()) return "SOC: " + socOption + " (--soc-signal)\n";
  std::set<std::string> names;
  for (const auto& [id, vehicle] : fleet.vehicles()) {
    if (std::string name = fleet::socSignalOf(vehicle); !name.empty()) names.insert(name);
  }
  std::string out = "SOC: ";
  if (names.empty()) return out + "no telemetry signal ending in SOC seen (--soc-signal NAME)\n";
  bool first = true;
  for (const std::string& name : names) {
    out += (first ? "" : ", ") + name;
    first = false;
  }
  return out + " (the signal ending in SOC; --soc-signal NAME)\n";
}

std::string tableText(const fleet::FleetView& fleet, const FleetOptions& options) {
  const std::int64_t now = clock::realtimeNs() / 1'000'000;
  std::string out = "openvcu fleet: " + options.broker + ", " + std::to_string(fleet.vehicles().size()) +
                    " vehicle(s), " + formatUtc(clock::realtimeNs()) + "\n";
  TextTable table(COLUMNS);
  for (const auto& [id, vehicle] : fleet.vehicles()) table.addRow(cellsOf(vehicle, options.socSignal, now));
  if (table.empty()) {
    out += "(no vehicle on this broker)\n";
    return out;
  }
  table.appendTo(out);
  return out + socNote(fleet, options.socSignal);
}

/// Collects retained and live messages until `done()`, QUIET_END without a message, or `wait`.
template <typename Done>
void collect(FleetClient& client, double waitSeconds, Done done) {
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(waitSeconds));
  while (!stopRequested() && Clock::now() < end && !done()) {
    if (Clock::now() - std::max(start, client.lastMessage()) >= QUIET_END) break;
    client.pump(LOOP_TIMEOUT_MS);
  }
}

void reportBadPayloads(FleetClient& client, Sink& err) {
  for (const std::string& problem : client.takeErrors())
    err.write("vcu fleet: warning: ignored a message: " + problem + "\n");
}

std::string timeOfDay() {
  const std::string utc = formatUtc(clock::realtimeNs());  // "2026-11-27T19:24:14.123Z"
  const auto t = utc.find('T');
  return t == std::string::npos ? utc : utc.substr(t + 1, 8);
}

}  // namespace

ExitCode runFleetWatch(const FleetOptions& options, Streams streams, bool terminal) {
  const StopSignalScope stopScope;
  FleetClient client;
  if (Status opened = client.open(options); !opened) {
    reportError(streams.err, opened.error().message);
    return ExitCode::Failure;
  }
  if (options.once) {
    collect(client, options.waitSeconds, [] { return false; });
    reportBadPayloads(client, streams.err);
    streams.out.write(tableText(client.fleet(), options));
    return ExitCode::Ok;
  }
  const auto end = options.forSeconds > 0 ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                               std::chrono::duration<double>(options.forSeconds))
                                          : Clock::time_point::max();
  std::map<std::string, std::vector<std::string>> shown;  ///< pipe: each vehicle's last line without its age
  auto lastDraw = Clock::time_point{};
  bool dirty = true;
  if (!terminal)
    streams.out.write("# TIME " + [] {
      std::string header;
      for (const std::string& column : COLUMNS) header += (header.empty() ? "" : " ") + column;
      return header;
    }() + "\n");
  while (!stopRequested() && Clock::now() < end) {
    client.pump(LOOP_TIMEOUT_MS);
    reportBadPayloads(client, streams.err);
    const auto changed = client.takeChanged();
    dirty = dirty || !changed.empty();
    bool up = false;
    const bool linkChanged = client.takeLinkChange(up);
    if (terminal) {
      const auto now = Clock::now();
      if ((dirty && now - lastDraw >= REDRAW_MIN) || now - lastDraw >= REDRAW_MAX) {
        streams.out.write("\x1b[H\x1b[2J" + tableText(client.fleet(), options) +
                          (up || lastDraw == Clock::time_point{} ? "" : "(broker link lost; reconnecting)\n") +
                          "(Ctrl-C to stop)\n");
        streams.out.flush();
        lastDraw = now;
        dirty = false;
      }
      continue;
    }
    if (linkChanged)
      streams.out.write(timeOfDay() + (up ? " # broker link back\n" : " # broker link lost; reconnecting\n"));
    const std::int64_t nowMs = clock::realtimeNs() / 1'000'000;
    for (const std::string& id : changed) {
      const fleet::VehicleView* vehicle = client.fleet().find(id);
      if (vehicle == nullptr) continue;
      std::vector<std::string> cells = cellsOf(*vehicle, options.socSignal, nowMs);
      std::vector<std::string> key(cells.begin(), cells.end() - 1);
      if (shown[id] == key) continue;
      shown[id] = std::move(key);
      std::string line = timeOfDay();
      for (const std::string& cell : cells) line += " " + cell;
      streams.out.write(line + "\n");
    }
    streams.out.flush();
  }
  return ExitCode::Ok;
}

ExitCode runFleetGet(const FleetOptions& options, const std::string& vehicleId, const std::string& key,
                     Streams streams) {
  const StopSignalScope stopScope;
  FleetClient client;
  if (Status opened = client.open(options); !opened) {
    reportError(streams.err, opened.error().message);
    return ExitCode::Failure;
  }
  const auto known = [&] {
    const fleet::VehicleView* vehicle = client.fleet().find(vehicleId);
    return vehicle != nullptr && fleet::fleetValue(*vehicle, key).has_value();
  };
  collect(client, options.waitSeconds, known);
  reportBadPayloads(client, streams.err);
  const fleet::VehicleView* vehicle = client.fleet().find(vehicleId);
  if (vehicle == nullptr) {
    std::string ids;
    for (const auto& [id, view] : client.fleet().vehicles()) ids += (ids.empty() ? "" : ", ") + id;
    reportError(streams.err, "vehicle '" + vehicleId + "' is not on the broker " + options.broker +
                                 (ids.empty() ? " (no vehicle is)" : " (known: " + ids + ")"));
    return ExitCode::Failure;
  }
  const auto value = fleet::fleetValue(*vehicle, key);
  if (!value) {
    std::string signalNames;
    for (const auto& [name, sample] : vehicle->signals) signalNames += ", " + name;
    reportError(streams.err, "vehicle '" + vehicleId + "' has not told '" + key + "' within " +
                                 fleet::formatNumber(options.waitSeconds) + " s (keys: status, state, faults, health" +
                                 signalNames + "; state, faults, health and signals come only when it sends them)");
    return ExitCode::Failure;
  }
  streams.out.write(*value + "\n");
  return ExitCode::Ok;
}

void registerFleetCommands(CLI::App& app, CommandContext& context) {
  CLI::App* fleetCommand = app.add_subcommand("fleet", FLEET_DESCRIPTION);
  const auto addBrokerOptions = [](CLI::App& command, FleetOptions& options) {
    command.add_option("--broker", options.broker, "mqtt://HOST[:PORT] (1883) or mqtts://HOST[:PORT] (8883)")
        ->required();
    command.add_option("--username", options.username, "log in as this user");
    command.add_option("--password-file", options.passwordFile, "the password: the first line of FILE")
        ->check(CLI::ExistingFile);
    command.add_option("--ca-file", options.caFile, "mqtts://: the broker's CA (default: the system's store)")
        ->check(CLI::ExistingFile);
    command.add_option("--wait", options.waitSeconds, "--once and get: collect at most SECONDS (default 3)")
        ->check(nonNegativeNumber());
    command.add_option("--soc-signal", options.socSignal, "the SOC column's signal (default: the one ending in SOC)");
  };

  auto watchOptions = std::make_shared<FleetOptions>();
  CLI::App* watch = fleetCommand->add_subcommand("watch", WATCH_DESCRIPTION);
  watch->footer(WATCH_FOOTER);
  addBrokerOptions(*watch, *watchOptions);
  watch->add_flag("--once", watchOptions->once, "print the table once, then exit");
  watch->add_option("--for", watchOptions->forSeconds, "stop after SECONDS")->check(nonNegativeNumber());
  watch->callback([watchOptions, &context] {
    context.exitCode = runFleetWatch(*watchOptions, context.streams, isatty(STDOUT_FILENO) == 1);
  });

  auto getOptions = std::make_shared<FleetOptions>();
  auto vehicleId = std::make_shared<std::string>();
  auto key = std::make_shared<std::string>();
  CLI::App* get = fleetCommand->add_subcommand("get", GET_DESCRIPTION);
  get->footer(GET_FOOTER);
  get->add_option("VEHICLE", *vehicleId, "the vehicle id")->required();
  get->add_option("KEY", *key, "status, state, faults, health or a signal's name")->required();
  addBrokerOptions(*get, *getOptions);
  get->callback([getOptions, vehicleId, key, &context] {
    context.exitCode = runFleetGet(*getOptions, *vehicleId, *key, context.streams);
  });
}

}  // namespace openvcu::cli
