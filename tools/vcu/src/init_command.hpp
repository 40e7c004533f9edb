#pragma once
// `vcu init DIR --dbc FILE... --node NAME [--force]`: writes a complete, checked vehicle
// folder for one node of the DBC files (issue 22; the generator is init_plan.hpp).
//
//   vcu init tractor --dbc tractor.dbc --node VCU
//   (stdout) wrote tractor/vehicle.json ... next: vcu check --config tractor/vehicle.json

#include <string>
#include <vector>

#include "cli.hpp"
#include "sink.hpp"

namespace CLI {
class App;
}

namespace openvcu::cli {

struct InitOptions {
  std::string dir;                    ///< the folder to write
  std::vector<std::string> dbcFiles;  ///< one bus each
  std::string node;                   ///< the VCU's BU_ name
  std::string instance;               ///< empty: the folder's name
  bool force{};                       ///< replace existing files
};

/// Writes the folder: all files or none (staged inside DIR, checked with `vcu check`'s
/// loaders, then renamed). Errors on streams.err; the list of files and the next commands
/// on streams.out.
ExitCode runInit(const InitOptions& options, Streams streams);

/// Adds `init` to `app`.
void registerInitCommand(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
