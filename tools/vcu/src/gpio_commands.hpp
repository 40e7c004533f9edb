#pragma once
// `vcu gpio`: the GPIO lines of the configuration (docs/gpio.md) with what the running stack
// says of them: each line, its chip and offset or name, direction and settings, the level
// vcu-gpio drives or read (internal.gpio.<line>), what is commanded (outputs) or the
// simulated electrical level (inputs on the sim back end), and the bound signal's value.
//
//   vcu gpio --config config/hhea/vehicle.json

#include "cli.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct GpioOptions {
  StackOptions stack;
};

ExitCode runGpio(const GpioOptions& options, Streams streams);

/// Adds `gpio` to `app`.
void registerGpioCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
