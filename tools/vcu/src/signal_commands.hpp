#pragma once
// The `vcu signal` group: the signal table and operator commands of a running stack.
//
//   vcu signal list 'internal.*'                 keys, units, ranges, kinds, buses (no stack needed)
//   vcu signal get internal.operator.Start        the three planes with time stamps and quality
//   vcu signal set internal.operator.Start Start  a checked command, answered by its service
//   vcu signal set --override X.Y.Z 50            operator override (wins until cleared)
//   vcu signal set --clear-override X.Y.Z
//   vcu signal watch 'VIC.*SOC*' --for 10         changes as they happen
//
// Unknown keys are answered here, before anything is sent, with a "did you mean"; the
// value range and the permission are checked by the service that owns the key (it is the
// authority, and its checks may depend on its state), which answers "accepted" or
// "refused: reason".

#include <cstdint>
#include <string>
#include <vector>

#include "cli.hpp"
#include "command_request.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct SignalListOptions {
  StackOptions stack;
  std::string pattern;  ///< glob ('*', '?'); empty: every signal
};

struct SignalGetOptions {
  StackOptions stack;
  std::vector<std::string> keys;
};

enum class SetMode : std::uint8_t { Command, Override, ClearOverride };

struct SignalSetOptions {
  StackOptions stack;
  std::string key;
  std::string value;  ///< a number or a value text; empty for ClearOverride
  SetMode mode{SetMode::Command};
  double timeoutSeconds{DEFAULT_ACK_TIMEOUT_SECONDS};
  std::string note;  ///< free text carried in the request (the operator's reason)
};

struct SignalWatchOptions {
  StackOptions stack;
  std::string pattern;
  std::uint64_t count{};  ///< stop after this many changes; 0: no limit
  double forSeconds{};    ///< stop after this long; 0: no limit
};

ExitCode runSignalList(const SignalListOptions& options, Streams streams);
ExitCode runSignalGet(const SignalGetOptions& options, Streams streams);
ExitCode runSignalSet(const SignalSetOptions& options, Streams streams);
ExitCode runSignalWatch(const SignalWatchOptions& options, Streams streams);

/// Adds `signal` and its subcommands to `app`.
void registerSignalCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
