#pragma once
// `vcu status` (which services of a running stack are alive, from their heartbeats) and
// `vcu spy` (lcm-spy with the project's event types).
//
//   vcu status --config config/hhea/vehicle.json
//   SERVICE              PID   UPTIME    LAST BEAT   STATUS  COUNTERS
//   vcu-fsm              4242  12.04 s   0.31 s ago  ready   transitions=3 commands_accepted=1 ...
//
//     NOT HEARD  LAST BEAT   STATUS
//     vcu-gpio   4.10 s ago  silent for 4.10 s          (exit code 1)
//
//   vcu spy                    # java lcm.spy.Spy via shared/ipc/lcm-spy.sh, argv only (no shell)

#include <string>

#include "cli.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

/// How long `vcu status` listens by default: every service beats once a second.
inline constexpr double DEFAULT_STATUS_WAIT_SECONDS = 1.5;

struct StatusOptions {
  StackOptions stack;
  double waitSeconds{DEFAULT_STATUS_WAIT_SECONDS};
  bool stats{};  ///< also the per-bus and per-message statistics (STATS channel)
};

struct SpyOptions {
  StackOptions stack;    ///< optional here: gives the LCM URL
  std::string lcmUrl;    ///< overrides the configuration's
  std::string typesJar;  ///< overrides the build's openvcu-lcm-types.jar
  bool dryRun{};         ///< print the command instead of running it
};

ExitCode runStatus(const StatusOptions& options, Streams streams);
ExitCode runSpy(const SpyOptions& options, Streams streams);

/// Adds `status` and `spy` to `app`.
void registerStatusCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
