#pragma once
// `vcu fleet watch|get`: the vehicles of an MQTT broker as vcu-telemetry publishes them
// (docs/design/telemetry.md; the topics and payloads: shared/fleet).
//
//   vcu fleet watch --broker mqtt://127.0.0.1:1883            live, one line per vehicle
//   vcu fleet watch --broker mqtt://127.0.0.1:1883 --once     the table once, then exit
//   vcu fleet get hhea-01 state --broker mqtt://127.0.0.1:1883
//   -> "Ready"

#include <string>

#include "cli.hpp"

namespace openvcu::cli {

struct FleetOptions {
  std::string broker;        ///< mqtt://HOST[:PORT] or mqtts://HOST[:PORT]
  std::string username;      ///< empty: anonymous
  std::string passwordFile;  ///< the password's first line; only with a username
  std::string caFile;        ///< mqtts://: the CA file (default: the system store)
  std::string socSignal;     ///< the SOC column's signal; empty: the one whose name ends in SOC
  double waitSeconds{3};     ///< --once and get: collect at most this long after subscribing
  double forSeconds{};       ///< live watch: stop after this long (0: until Ctrl-C)
  bool once{};
};

ExitCode runFleetWatch(const FleetOptions& options, Streams streams, bool terminal);
ExitCode runFleetGet(const FleetOptions& options, const std::string& vehicleId, const std::string& key,
                     Streams streams);

/// Adds `fleet` (watch, get) to `app`.
void registerFleetCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
