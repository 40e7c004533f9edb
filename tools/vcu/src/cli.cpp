#include "cli.hpp"

#include <CLI/CLI.hpp>
#include <exception>
#include <sstream>

#include "bus_commands.hpp"
#include "check_commands.hpp"
#include "dbc_commands.hpp"
#include "diagnostics.hpp"
#include "fleet_commands.hpp"
#include "fsm_commands.hpp"
#include "gpio_commands.hpp"
#include "init_command.hpp"
#include "inject_commands.hpp"
#include "j1939_commands.hpp"
#include "record_commands.hpp"
#include "safety_commands.hpp"
#include "sim_commands.hpp"
#include "top_commands.hpp"
#include "trace_commands.hpp"
#include "schedule_commands.hpp"
#include "signal_commands.hpp"
#include "status_commands.hpp"

namespace openvcu::cli {
namespace {

constexpr const char* DESCRIPTION =
    "vcu: the openvcu command-line tool. Checks, lists and decodes DBC files and CAN logs; reads and commands the signals of a running stack.";

constexpr const char* FOOTER =
    "Run 'vcu COMMAND --help' (e.g. 'vcu dbc decode --help') for a command's manual.\n"
    "Exit codes: 0 success (warnings allowed), 1 errors in the input (DBC errors,\n"
    "unreadable files, malformed log lines) or a failed write, 2 usage error.\n";

/// Help and version (CLI11 reports them as "errors" with exit code 0) go to out; real
/// usage errors become one diagnostic line and ExitCode::Usage.
int usage(CLI::App& app, const CLI::ParseError& error, Streams streams) {
  if (error.get_exit_code() == 0) {
    std::ostringstream out;
    std::ostringstream err;
    app.exit(error, out, err);
    streams.out.write(out.str());
    streams.err.write(err.str());
    return static_cast<int>(ExitCode::Ok);
  }
  reportError(streams.err, std::string(error.what()) + " (see --help)");
  return static_cast<int>(ExitCode::Usage);
}

/// "vcu dbc" for the app's `dbc` subcommand; empty for no app.
std::string commandPath(const CLI::App* app) {
  if (app == nullptr) return {};
  std::string parent = commandPath(app->get_parent());
  return parent.empty() ? app->get_name() : parent + ' ' + app->get_name();
}

/// The innermost command given that has subcommands but none was chosen, or nullptr. A
/// command that also runs alone (`vcu j1939` shows) says so with require_subcommand(0, 1).
const CLI::App* commandWithoutSubcommand(const CLI::App& app) {
  if (app.get_subcommands({}).empty()) return nullptr;  // a leaf command: it ran
  const auto chosen = app.get_subcommands();
  if (chosen.empty()) {
    const bool runsAlone = app.get_require_subcommand_min() == 0 && app.get_require_subcommand_max() == 1;
    return runsAlone ? nullptr : &app;
  }
  return commandWithoutSubcommand(*chosen.front());
}

}  // namespace

int run(int argc, const char* const* argv, Streams streams) noexcept {
  int exitCode = static_cast<int>(ExitCode::Failure);
  try {
    CLI::App app(DESCRIPTION, "vcu");
    app.footer(FOOTER);
    app.set_version_flag("--version", std::string("vcu (openvcu) ") + OPENVCU_VERSION);
    app.get_formatter()->column_width(36);
    CommandContext context{streams};
    registerDbcCommands(app, context);
    registerSignalCommands(app, context);
    registerStatusCommands(app, context);
    registerBusCommands(app, context);
    registerScheduleCommands(app, context);
    registerFsmCommands(app, context);
    registerGpioCommands(app, context);
    registerSimCommands(app, context);
    registerInjectCommands(app, context);
    registerSafetyCommands(app, context);
    registerRecordCommands(app, context);
    registerTopCommands(app, context);
    registerCheckCommands(app, context);
    registerTraceCommands(app, context);
    registerInitCommand(app, context);
    registerJ1939Commands(app, context);
    registerFleetCommands(app, context);
    try {
      app.parse(argc, argv);
      exitCode = static_cast<int>(context.exitCode);
      if (const CLI::App* incomplete = commandWithoutSubcommand(app)) {  // "vcu", "vcu dbc": show the menu
        streams.err.write(incomplete->help(commandPath(incomplete->get_parent())));
        exitCode = static_cast<int>(ExitCode::Usage);
      }
    } catch (const CLI::ParseError& error) {
      exitCode = usage(app, error, streams);
    }
  } catch (const std::exception& error) {  // bad_alloc and the like; CLI11 set-up errors
    reportError(streams.err, std::string("internal error: ") + error.what());
  }
  if (!streams.out.flush() && exitCode == static_cast<int>(ExitCode::Ok)) {  // else the command said why
    reportError(streams.err, "cannot write the output: " + streams.out.errorMessage());
    exitCode = static_cast<int>(ExitCode::Failure);
  }
  streams.err.flush();
  return exitCode;
}

int run(const std::vector<std::string>& arguments, Streams streams) noexcept {
  try {
    std::vector<const char*> argv{"vcu"};
    for (const std::string& argument : arguments) argv.push_back(argument.c_str());
    return run(static_cast<int>(argv.size()), argv.data(), streams);
  } catch (const std::exception& error) {
    reportError(streams.err, std::string("internal error: ") + error.what());
    return static_cast<int>(ExitCode::Failure);
  }
}

}  // namespace openvcu::cli
