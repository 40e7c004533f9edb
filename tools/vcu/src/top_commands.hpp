#pragma once
// `vcu top`: the live terminal view of a running stack (what ./run.sh shows without the HMI):
// services (pid, uptime, restarts seen, heartbeat age, CPU, RSS, status), the FSM state, key
// signals (SOC, HV connection, contactors, inverters, Cl15), bus load, can-tx's worst period
// error, and the active faults.
//
//   vcu top --config config/hhea/vehicle.json            refresh every second until Ctrl-C
//   vcu top --once --config config/hhea/vehicle.json     one snapshot after 1.5 s (logs, tests)

#include "cli.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct TopOptions {
  StackOptions stack;
  bool once{};
  double forSeconds{};  ///< 0: until Ctrl-C
};

ExitCode runTop(const TopOptions& options, Streams streams);

/// Adds `top` to `app`.
void registerTopCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
