#pragma once
// The `vcu schedule` group: vcu-can-tx's transmit schedule (docs/design/can-tx.md).
//
//   vcu schedule import sched.csv --config vehicle.json -o schedule.json   the thesis' sheet -> JSON
//   vcu schedule cycle HC1_Demands 50            cycle time of a scheduled message, ms
//   vcu schedule disable CMD_MOT_9               stop sending a message (enable: again)
//   vcu schedule default Vehicle_Control_Unit.HC1_Demands.ControlWord 6   value sent while nothing commands it
//
// import works offline (openvcu/schedule/schedule_import.hpp has the sheet's rules). The
// others are checked commands answered by vcu-can-tx ("accepted" / "refused: reason"),
// effective at the next frame and kept across restarts in its overlay; an unknown message
// or key is refused here, with a "did you mean", before anything is sent.

#include <cstdint>
#include <string>
#include <vector>

#include "cli.hpp"
#include "command_request.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct ScheduleImportOptions {
  std::string csvFile;
  std::string configPath;                 ///< --config; empty: $OPENVCU_CONFIG, unless --dbc is given
  std::vector<std::string> dbcFiles;      ///< --dbc, merged in order, instead of a configuration
  std::string node;                       ///< --node; empty: the configuration's (none with --dbc)
  std::vector<std::string> groupSignals;  ///< --group-signal NODE=KEY
  std::string outputFile;                 ///< -o; empty: standard output
};

enum class ScheduleAction : std::uint8_t { Cycle, Enable, Disable, Default, Add };

struct ScheduleCommandOptions {
  StackOptions stack;
  ScheduleAction action{ScheduleAction::Cycle};
  std::string target;  ///< a message name (cycle, enable, disable) or a signal key (default)
  std::string value;   ///< MS (cycle) or VALUE (default); unused otherwise
  double timeoutSeconds{DEFAULT_ACK_TIMEOUT_SECONDS};
  std::string note;  ///< free text carried in the request (the operator's reason)
};

/// `vcu schedule import`: diagnostics on err; the JSON on out, or written atomically to
/// outputFile (then a summary line on out). Nothing is written when there is an error.
ExitCode runScheduleImport(const ScheduleImportOptions& options, Streams streams);

/// `vcu schedule cycle|enable|disable|default`: local checks, then one command request.
ExitCode runScheduleCommand(const ScheduleCommandOptions& options, Streams streams);

/// Adds `schedule` and its subcommands to `app`.
void registerScheduleCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
