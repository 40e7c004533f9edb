#pragma once
// `vcu sim fault NAME [on|off]`: injects a fault into the simulated vehicle (vcu-ecu-sim),
// or clears it; acknowledged or refused with the reason (services/ecu-sim/README.md).
//
//   vcu sim fault battery on --config config/hhea/vehicle.json
//   vcu sim fault silent.VIC on
//   vcu sim fault battery off

#include <string>

#include "cli.hpp"
#include "command_request.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct SimFaultOptions {
  StackOptions stack;
  std::string name;
  std::string state{"on"};
  double timeoutSeconds{DEFAULT_ACK_TIMEOUT_SECONDS};
};

ExitCode runSimFault(const SimFaultOptions& options, Streams streams);

/// Adds `sim` and `sim fault` to `app`.
void registerSimCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
