#pragma once
// `vcu check`: every file of a vehicle, checked with the loaders the services use, every
// problem reported (issue 19; also what `./run.sh --check` runs).
//
//   vcu check config/hhea            (the folder, the file, or --config FILE: the same)
//   (stderr) schedule.json:4:21: error: syntax error while parsing object - unexpected '}'
//   (stdout) config/hhea/vehicle.json: 0 errors, 0 warnings
//            config/hhea/hhea.dbc: 0 errors, 0 warnings
//            ...
//            vehicle 'hhea': 8 files, 1 error, 0 warnings
//
// What is checked with which loader:
// - vehicle.json, its DBC files and the GPIO map: config::checkVehicleConfig (shared/config:
//   the loader every service starts with), then config::buildCatalog;
// - the FSM file: fsm::checkMachine (the openvcu_fsm library vcu-fsm runs, already linked
//   by `vcu fsm`), after the schedule's JSON (the machine's send groups come from it);
// - the schedule, simulation and receive files and the HMI dashboard (dashboard.json beside
//   vehicle.json, as vcu-hmi finds it): read with config::readJsonFile (JSON syntax, with
//   line:column) and required to be a JSON object, then loaded with the loader the service
//   starts with: schedule::loadSchedule (shared/schedule; vcu-can-tx), config::loadSimConfig
//   (vcu-ecu-sim), config::loadReceiveConfig (vcu-can-rx) and config::loadDashboardConfig
//   (vcu-hmi), all in shared/ (STYLE.md 16). Each reports its first error, with the file
//   and the JSON path.
// When vehicle.json itself has errors, the other files named in it and the dashboard get the
// JSON check only (the loaders need the vehicle and its catalog).

#include <cstddef>
#include <string>

#include "cli.hpp"
#include "openvcu/core/error.hpp"
#include "sink.hpp"
#include "stack_access.hpp"

namespace CLI {
class App;
}

namespace openvcu::cli {

struct VehicleCheckOptions {
  std::string path;    ///< PATH: vehicle.json or its folder; empty: stack.configPath decides
  StackOptions stack;  ///< --config (the instance is not used)
  bool quiet{};        ///< errors only on stderr (warnings still counted)
};

/// Errors and warnings found in one file.
struct FileCounts {
  std::size_t errors{};
  std::size_t warnings{};
};

/// Checks the FSM file `file` against `stack` and reports on err (warnings unless quiet):
/// a schedule that does not parse is reported as its own error and the machine's
/// send-group actions are then left unchecked (one note), rather than blamed on the FSM
/// file. Counts the schedule's error too.
FileCounts checkFsmFile(const std::string& file, const Stack& stack, bool quiet, Sink& err);

ExitCode runCheck(const VehicleCheckOptions& options, Streams streams);

/// Adds `check` to `app`.
void registerCheckCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
