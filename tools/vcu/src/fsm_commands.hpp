#pragma once
// The `vcu fsm` group: the vehicle's state machine file (docs/fsm.md).
//
//   vcu fsm check fsm.json --config vehicle.json     every error and warning; exit 1 on errors
//   vcu fsm graph fsm.json [--mermaid]               Graphviz DOT (or Mermaid) of states and transitions
//   vcu fsm replay fsm.json --config vehicle.json trace.log   the transition timeline of a recorded log
//   vcu fsm reload [FILE] --config vehicle.json      vcu-fsm switches to the file, or refuses and keeps its machine
//
// check and replay load the configuration for its DBC and catalog; graph needs none (it
// draws any file that parses, the thesis' listing included).

#include <string>

#include "cli.hpp"
#include "command_request.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct FsmFileOptions {
  StackOptions stack;
  std::string file;
  std::string log;      ///< replay: the CAN log
  bool mermaid{};       ///< graph: Mermaid instead of DOT
  bool quiet{};         ///< check: errors only
  double timeoutSeconds{DEFAULT_ACK_TIMEOUT_SECONDS};  ///< reload
};

ExitCode runFsmCheck(const FsmFileOptions& options, Streams streams);
ExitCode runFsmGraph(const FsmFileOptions& options, Streams streams);
ExitCode runFsmReplay(const FsmFileOptions& options, Streams streams);
ExitCode runFsmReload(const FsmFileOptions& options, Streams streams);

/// Adds `fsm` and its subcommands to `app`.
void registerFsmCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
