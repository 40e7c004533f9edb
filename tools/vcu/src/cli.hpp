#pragma once
// The `vcu` command tree. run() builds the CLI11 app, lets every command group register
// its subcommands (registerDbcCommands(), signal, status, bus, schedule), parses the
// arguments, runs the chosen command and returns the process exit code.
//
//   StringSink out, err;
//   int exitCode = run({"dbc", "check", "vehicle.dbc"}, Streams{out, err});
//   // out.text() == "vehicle.dbc: 42 messages, 310 signals, 9 nodes, 0 errors, 0 warnings\n"
//
// Adding a group: write <group>_commands.{hpp,cpp} with
// `void register<Group>Commands(CLI::App&, CommandContext&)` and call it from run().

#include <string>
#include <vector>

#include "sink.hpp"

namespace CLI {
class App;
}

namespace openvcu::cli {

/// Exit codes shared by every command (documented in --help and README.md).
enum class ExitCode : int {
  Ok = 0,       ///< done; warnings allowed
  Failure = 1,  ///< the input had errors (bad DBC, unreadable file, malformed log lines) or output failed
  Usage = 2,    ///< the command line itself was wrong
};

/// Handed to each group's register function: the streams commands write to and the
/// slot where the command that ran leaves its exit code.
struct CommandContext {
  Streams streams;
  ExitCode exitCode{ExitCode::Ok};
};

/// Runs `vcu` on argv (argv[0] is the program name). Never throws: internal failures are
/// reported on streams.err and return ExitCode::Failure.
int run(int argc, const char* const* argv, Streams streams) noexcept;

/// The same with the arguments after the program name (tests).
int run(const std::vector<std::string>& arguments, Streams streams) noexcept;

}  // namespace openvcu::cli
