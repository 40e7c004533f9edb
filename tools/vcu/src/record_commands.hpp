#pragma once
// `vcu record` and `vcu replay`: a session of a running stack to a folder and back.
//
//   vcu record drive1 --for 60 --config config/hhea/vehicle.json
//   drive1/vehicle.log      every frame of bus "vehicle", candump -L:
//                           (1700000000.123456) vehicle 18FEF121#0102030405060708
//   drive1/events.lcmlog    the LCM events, written by Debian's lcm-logger (a child process)
//
//   vcu replay drive1 --speed 2 --config config/hhea/vehicle.json
//                           every *.log of the folder onto the configured buses, with the
//                           recorded timing (absolute deadlines from the first frame)
//
// Both register with iox-roudi as "vcu-record-<pid>" / "vcu-replay-<pid>" when a bus is
// sim:NAME. README.md and each command's --help have the details.

#include <string>

#include "cli.hpp"
#include "stack_access.hpp"

namespace CLI {
class App;
}

namespace openvcu::cli {

struct RecordOptions {
  StackOptions stack;
  std::string directory;                ///< where <bus>.log and events.lcmlog go (created)
  double forSeconds{};                  ///< stop after this long; 0: until SIGINT/SIGTERM
  bool force{};                         ///< overwrite files a previous recording left
  std::string lcmLogger{"lcm-logger"};  ///< the program (PATH lookup for a bare name)
};

struct ReplayOptions {
  StackOptions stack;
  std::string directory;  ///< holds the *.log files (candump -L, the channel is the bus)
  double speed{1.0};      ///< 2 = twice as fast; 0 = as fast as possible
  bool loop{};            ///< start again at the end until SIGINT/SIGTERM
};

ExitCode runRecord(const RecordOptions& options, Streams streams);
ExitCode runReplay(const ReplayOptions& options, Streams streams);

/// Adds `record` and `replay` to `app`.
void registerRecordCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
