#pragma once
// The top-level configuration every service takes with --config (the HHEA one is
// config/hhea/vehicle.json). Paths in the file resolve relative to the file.
//
//   {
//     "instance": "hhea",
//     "node": "Vehicle_Control_Unit",
//     "dbc": ["hhea.dbc"],
//     "buses": [{"name": "vehicle", "link": "sim:vehicle", "bitrate": 500000, "messages": "all"}],
//     "fsm": "fsm.json", "schedule": "schedule.json", "gpio": "gpio.json", "simulation": "simulation.json",
//     "receive": "receive.json", "diagnostics": "diagnostics.json", "safety": "safety.json",
//     "internalSignals": [{"name": "operator.Start", "min": 0, "max": 1, "values": {"0": "Stop", "1": "Start"}}],
//     "lcm": "udpm://239.255.76.67:7667?ttl=0"
//   }
// Reference: docs/config.md.

#include "openvcu/can/link.hpp"
#include "openvcu/config/bus_j1939.hpp"
#include "openvcu/config/gpio.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/model.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::config {

/// The link kinds are the CAN links' own (shared/can/link.hpp).
using LinkKind = can::LinkKind;

/// "socketcan:can0", "sim:vehicle" or "replay:FILE".
struct Link {
  LinkKind kind{LinkKind::Sim};
  std::string target;  ///< interface, simulated bus name, or the replay file (resolved path)
  [[nodiscard]] std::string toString() const;
};

/// What a link lets through to the services ("filter" in the bus object).
enum class BusFilter : std::uint8_t {
  Dbc,  ///< the bus' DBC messages (exact or by PGN) plus the J1939 protocol PGNs (default)
  All,  ///< every frame (unknown IDs are then counted)
};

/// "replay" in the bus object: how a replay:FILE link plays its log.
struct ReplaySettings {
  double speed{1.0};    ///< 1 = original timing, 2 = twice as fast, 0 = as fast as possible
  bool loop{false};     ///< start again at the end
  std::string channel;  ///< only this log channel ("can0"); empty: all
};

struct BusConfig {
  std::string name;                      ///< logical name: "vehicle", "battery"
  Link link;
  std::uint32_t bitrate{500000};         ///< nominal bit rate, bit/s
  std::uint32_t dataBitrate{2000000};    ///< CAN FD data-phase bit rate, bit/s
  bool fd{};                             ///< CAN FD
  BusFilter filter{BusFilter::Dbc};
  ReplaySettings replay;
  std::vector<std::size_t> messages;     ///< indices into VehicleConfig::database.messages
  std::optional<BusJ1939> j1939;         ///< this VCU's J1939-81 NAME and address claim here

  /// The link settings this bus gives every service that opens it (no filters: the
  /// receiver adds its own).
  [[nodiscard]] can::LinkOptions linkOptions() const;
};

struct InternalSignal {
  std::string name;  ///< "operator.Start"; its table key is "internal.operator.Start"
  std::string unit;
  double minimum{0.0};
  double maximum{1.0};
  double initial{0.0};
  std::string comment;
  std::vector<dbc::ValueDescription> values;
};

inline constexpr std::string_view DEFAULT_LCM_URL = "udpm://239.255.76.67:7667?ttl=0";

struct VehicleConfig {
  std::string path;       ///< the file as given
  std::string directory;  ///< its folder: relative paths resolve against it
  std::string instance;   ///< names this stack's shared objects; letters, digits, '-', '_'
  std::string node;       ///< this VCU's DBC node name
  std::vector<std::string> dbcFiles;  ///< resolved paths
  dbc::Database database;             ///< all DBC files merged
  std::vector<BusConfig> buses;
  std::string fsmFile;         ///< resolved; empty when not configured
  std::string scheduleFile;
  std::string gpioFile;
  std::string simulationFile;
  std::string receiveFile;     ///< can-rx's receive settings (receive.json); empty: defaults
  std::string diagnosticsFile; ///< the VCU's own DTCs and identification (diagnostics.json); empty: none
  std::string webFile;         ///< vcu-web's settings (web.json); empty: its defaults
  std::string telemetryFile;   ///< vcu-telemetry's settings (telemetry.json); empty: no telemetry
  std::string safetyFile;      ///< the safety case (safety.json, openvcu::safety); empty: none
  std::vector<InternalSignal> internalSignals;
  GpioMap gpio;                ///< loaded from gpioFile; empty when not configured
  std::string lcmUrl{DEFAULT_LCM_URL};
  /// Besides root and the stack's own user, members of this Unix group may command the
  /// stack (its command sockets are group-owned; docs/design/security.md).
  std::string commandGroup{"openvcu"};

  /// The bus carrying a DBC message, or nullptr.
  [[nodiscard]] const BusConfig* busOf(std::size_t messageIndex) const noexcept;
  [[nodiscard]] const BusConfig* findBus(std::string_view name) const noexcept;
};

/// Loads and validates the whole configuration (the DBC files included). Any error
/// refuses the file: the first one is returned, with file and JSON path (or DBC
/// file:line:col). Warnings are appended to *warnings when given.
Result<VehicleConfig> loadVehicleConfig(const std::string& path, std::vector<Error>* warnings = nullptr);

/// Every problem of a configuration, for `vcu config check`: errors and warnings.
std::vector<Error> checkVehicleConfig(const std::string& path);

/// Parses a link text; `baseDirectory` resolves replay files.
Result<Link> parseLink(std::string_view text, const std::string& baseDirectory);

/// Letters, digits, '-' and '_', 1..32 characters.
bool validInstanceName(std::string_view name) noexcept;

}  // namespace openvcu::config
