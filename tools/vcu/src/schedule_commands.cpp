// `vcu schedule ...`: import, cycle, enable, disable, default. Each subcommand's
// description and footer are its manual (`vcu schedule import --help`).
#include "schedule_commands.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>

#include "dbc_loading.hpp"
#include "diagnostics.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/schedule/schedule_import.hpp"

namespace openvcu::cli {
namespace {

constexpr const char* CONFIG_NOTE =
    "The stack: --config FILE or $OPENVCU_CONFIG (required: there is no default), and\n"
    "--instance to talk to a stack started with another instance name.\n";

constexpr const char* IMPORT_DESCRIPTION = "Convert the thesis' schedule sheet (CSV) into the schedule JSON";
constexpr const char* IMPORT_FOOTER =
    "FILE.csv is the original workbook's table exported as CSV. Header (first line, any\n"
    "order, nothing else): NodeName,SheetName,UniqueID,Message,Signal,DeltaTime,IsSHM,\n"
    "CycleTime,Value. One row = one signal's default value in one message:\n"
    "  messages.<Message>.values.<Signal> = Value   a physical number in the DBC range\n"
    "  CycleTime (ms, whole, 1..3600000) -> cycleMs, always written\n"
    "  IsSHM 1/true/yes -> the message is a J1939-76 SDM: safety.deltaUs =\n"
    "      round(DeltaTime ms * 1000) (0.292 -> 292); DeltaTime > 0 and < the cycle\n"
    "  NodeName -> group NodeName, switched by internal.tx.<NodeName> (declare it in\n"
    "      vehicle.json, or --group-signal NODE=KEY to use an existing key)\n"
    "  UniqueID (optional) -> must be the message's CAN ID or J1939 PGN\n"
    "  SheetName is informational ('shm'/'nonshm' contradicting IsSHM: a warning).\n"
    "The per-message columns may be empty on all rows of a message but one; the values\n"
    "given must agree. Rows with Signal and Value empty only list their message.\n"
    "\"include\" lists exactly the imported messages, in the order first seen.\n"
    "Messages and signals are checked against the DBC: the configuration's (--config or\n"
    "$OPENVCU_CONFIG, node from it) or --dbc files (repeat --dbc for several; --node\n"
    "NAME warns about messages another node transmits). Every problem is printed as\n"
    "'sched.csv:14: error: unknown signal ...' with a 'did you mean'; with any error\n"
    "nothing is written. Quoted fields, CRLF and a UTF-8 BOM are fine.\n"
    "Output: the JSON on stdout, or -o FILE (written to a temporary file in the same\n"
    "folder, then renamed over FILE) and a summary line.\n"
    "\n"
    "Examples:\n"
    "  vcu schedule import sched.csv --config config/hhea/vehicle.json -o config/hhea/schedule.json\n"
    "  vcu schedule import sched.csv --dbc hhea.dbc --node Vehicle_Control_Unit \\\n"
    "      --group-signal Battery=internal.tx.keepAlive\n"
    "Exit: 0 converted (warnings allowed), 1 errors in the sheet, the DBC or the\n"
    "configuration, or the output could not be written, 2 usage error.\n";

constexpr const char* CYCLE_DESCRIPTION = "Change the cycle time of a scheduled message (vcu-can-tx answers)";
constexpr const char* CYCLE_FOOTER =
    "Sends ScheduleCycle: MESSAGE (a DBC message name) is sent every MS milliseconds\n"
    "(1..3600000) from its next frame on, and stays so across restarts (can-tx's overlay).\n"
    "An unknown message is refused here with a 'did you mean'; can-tx refuses a message\n"
    "it does not schedule, or a cycle not longer than the message's J1939-76 delta.\n"
    "\n"
    "Example:\n"
    "  vcu schedule cycle HC1_Demands 50 --note 'bench: slower'\n"
    "Exit: 0 accepted, 1 refused, unknown message, bad MS, or no answer within the\n"
    "timeout (default 2 s), 2 usage error.\n";

constexpr const char* ADD_DESCRIPTION = "Add a DBC message to the transmit schedule (vcu-can-tx answers)";
constexpr const char* ADD_FOOTER =
    "Sends ScheduleAdd: vcu-can-tx starts sending MESSAGE (any DBC message on a\n"
    "configured bus, also one another node transmits: the bench stands in for it) at\n"
    "once and then every MS milliseconds (1..3600000), with its DBC start values; set its\n"
    "signals with 'vcu schedule default' or an override, stop it with 'vcu schedule\n"
    "disable'. Kept across restarts (can-tx's overlay). An unknown message is refused here\n"
    "with a 'did you mean'; can-tx refuses a message it already schedules, a J1939-76\n"
    "safety header and one longer than a frame.\n"
    "\n"
    "Example:\n"
    "  vcu schedule add HVESSD2_PGN61585 100 --note 'bench: stand in for the VIC'\n"
    "Exit: 0 accepted, 1 refused, unknown message, bad MS, or no answer within the\n"
    "timeout (default 2 s), 2 usage error.\n";

constexpr const char* ENABLE_DESCRIPTION = "Send a scheduled message again (vcu-can-tx answers)";
constexpr const char* DISABLE_DESCRIPTION = "Stop sending a scheduled message (vcu-can-tx answers)";
constexpr const char* ENABLE_FOOTER =
    "Sends ScheduleEnable with value 1 (enable) or 0 (disable) for MESSAGE, a DBC\n"
    "message name; kept across restarts (can-tx's overlay). A disabled message of a\n"
    "J1939-76 pair takes its safety header with it. An unknown message is refused here\n"
    "with a 'did you mean'; can-tx refuses a message it does not schedule.\n"
    "\n"
    "Examples:\n"
    "  vcu schedule disable CMD_MOT_9\n"
    "  vcu schedule enable CMD_MOT_9\n"
    "Exit: 0 accepted, 1 refused, unknown message or no answer within the timeout\n"
    "(default 2 s), 2 usage error.\n";

constexpr const char* DEFAULT_DESCRIPTION =
    "Change the value sent for a signal while nothing commands it (vcu-can-tx answers)";
constexpr const char* DEFAULT_FOOTER =
    "Sends ScheduleDefault: KEY ('Transmitter.Message.Signal', see 'vcu signal list') is\n"
    "sent as VALUE while no service commands it and no override is set; kept across\n"
    "restarts (can-tx's overlay). VALUE is a number or a text of the signal's value\n"
    "table. An unknown key, an internal signal or a bad value is refused here with a\n"
    "'did you mean'; can-tx checks that the message is scheduled and the value is in\n"
    "the DBC range.\n"
    "\n"
    "Example:\n"
    "  vcu schedule default Vehicle_Control_Unit.HC1_Demands.ControlWord 6\n"
    "Exit: 0 accepted, 1 refused, unknown key, bad value or no answer within the\n"
    "timeout (default 2 s), 2 usage error.\n";

// ---- import --------------------------------------------------------------------------------

Error fileError(const std::string& path, std::string_view what, int reason) {
  return Error{std::string(what) + ": " + (reason != 0 ? std::strerror(reason) : "unknown error"),
               Location{path, 0, 0, {}}};
}

/// Writes `content` to `path` so that a reader sees the old file or the whole new one:
/// a temporary file in the same folder, fsync, rename over `path`, fsync of the folder.
Status writeFileAtomically(const std::string& path, std::string_view content) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string temporary = (folder / ("." + target.filename().string() + ".XXXXXX")).string();
  const int fd = ::mkstemp(temporary.data());
  if (fd < 0) return fileError(path, "cannot create a temporary file beside it", errno);
  const auto fail = [&](std::string_view what) {
    const int reason = errno;
    ::close(fd);
    ::unlink(temporary.c_str());
    return fileError(path, what, reason);
  };
  const mode_t mask = ::umask(0);  // mkstemp makes 0600; give the file the usual 0666 & ~umask
  ::umask(mask);
  if (::fchmod(fd, 0666 & ~mask) != 0) return fail("cannot set the permissions of the temporary file");
  std::size_t written = 0;
  while (written < content.size()) {
    const ssize_t count = ::write(fd, content.data() + written, content.size() - written);
    if (count < 0) {
      if (errno == EINTR) continue;
      return fail("cannot write");
    }
    written += static_cast<std::size_t>(count);
  }
  if (::fsync(fd) != 0) return fail("cannot write");
  if (::close(fd) != 0) {
    const int reason = errno;
    ::unlink(temporary.c_str());
    return fileError(path, "cannot write", reason);
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const int reason = errno;
    ::unlink(temporary.c_str());
    return fileError(path, "cannot replace", reason);
  }
  if (const int folderFd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); folderFd >= 0) {
    ::fsync(folderFd);  // the rename itself on disk; a failure here loses nothing already written
    ::close(folderFd);
  }
  return {};
}

/// "NODE=KEY" pairs; reports each malformed or repeated one. Empty optional on any error.
std::optional<std::vector<std::pair<std::string, std::string>>> parseGroupSignals(const std::vector<std::string>& texts,
                                                                                  Sink& err) {
  std::vector<std::pair<std::string, std::string>> pairs;
  bool good = true;
  for (const std::string& text : texts) {
    const std::size_t equals = text.find('=');
    if (equals == std::string::npos || equals == 0 || equals + 1 == text.size()) {
      reportError(err, "--group-signal '" + text + "': expected NODE=KEY, e.g. Battery=internal.tx.keepAlive");
      good = false;
      continue;
    }
    std::string node = text.substr(0, equals);
    if (std::any_of(pairs.begin(), pairs.end(), [&](const auto& pair) { return pair.first == node; })) {
      reportError(err, "--group-signal: node '" + node + "' is mapped twice");
      good = false;
      continue;
    }
    pairs.emplace_back(std::move(node), text.substr(equals + 1));
  }
  if (!good) return std::nullopt;
  return pairs;
}

/// true when `node` is a node of `database`; else reports it with a suggestion.
bool knownNode(const dbc::Database& database, const std::string& node, Sink& err) {
  if (database.findNode(node) != nullptr) return true;
  std::vector<std::string> names;
  names.reserve(database.nodes.size());
  for (const dbc::Node& candidate : database.nodes) names.push_back(candidate.name);
  std::string message = "--node '" + node + "' is not a node of the DBC";
  if (const auto maybeName = text::didYouMean(node, names)) message += " (did you mean '" + *maybeName + "'?)";
  reportError(err, message);
  return false;
}

std::string plural(std::size_t count, std::string_view noun) {
  return std::to_string(count) + " " + std::string(noun) + (count == 1 ? "" : "s");
}

/// "5 messages (2 J1939-76 SDMs), 31 values, 2 groups"
std::string summaryText(const nlohmann::ordered_json& schedule) {
  std::size_t values = 0;
  std::size_t safety = 0;
  for (const auto& [name, message] : schedule["messages"].items()) {
    if (message.contains("values")) values += message["values"].size();
    if (message.contains("safety")) ++safety;
  }
  const std::size_t groups = schedule.contains("groups") ? schedule["groups"].size() : 0;
  return plural(schedule["messages"].size(), "message") + " (" + plural(safety, "J1939-76 SDM") + "), " +
         plural(values, "value") + ", " + plural(groups, "group");
}

// ---- runtime commands ----------------------------------------------------------------------

/// The bus message named `name`, or nullptr after reporting it with a "did you mean".
const dbc::Message* findBusMessage(const dbc::Database& database, const std::string& name, Sink& err) {
  if (const dbc::Message* message = database.findMessage(name); message != nullptr && !message->pseudo) return message;
  std::vector<std::string> names;
  for (const dbc::Message& message : database.messages) {
    if (!message.pseudo) names.push_back(message.name);
  }
  std::string text = "unknown message '" + name + "'";
  if (const auto maybeName = text::didYouMean(name, names)) text += " (did you mean '" + *maybeName + "'?)";
  reportError(err, text);
  return nullptr;
}

std::optional<double> parseMilliseconds(const std::string& text) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc{} || ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

// ---- registration --------------------------------------------------------------------------

void addImport(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<ScheduleImportOptions>();
  CLI::App* importCommand = group.add_subcommand("import", IMPORT_DESCRIPTION);
  importCommand->footer(IMPORT_FOOTER);
  importCommand->add_option("FILE", options->csvFile, "the sheet, as CSV")->required()->type_name("");
  CLI::Option* config =
      importCommand
          ->add_option("-c,--config", options->configPath, "the vehicle configuration (default: $OPENVCU_CONFIG)")
          ->option_text("FILE");
  CLI::Option* dbc = importCommand->add_option("--dbc", options->dbcFiles, "check against this DBC file (repeatable)")
                         ->expected(1)
                         ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
                         ->option_text("FILE");
  config->excludes(dbc);
  importCommand->add_option("--node", options->node, "this VCU's DBC node (default: the configuration's)")
      ->option_text("NAME");
  importCommand
      ->add_option("--group-signal", options->groupSignals,
                   "switch NodeName's group with this catalog key instead of internal.tx.NODE (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->option_text("NODE=KEY");
  importCommand->add_option("-o,--output", options->outputFile, "write the JSON here (atomically) instead of stdout")
      ->option_text("FILE");
  importCommand->callback([options, &context] { context.exitCode = runScheduleImport(*options, context.streams); });
}

/// The options every runtime command shares.
void addCommandOptions(CLI::App& command, ScheduleCommandOptions& options) {
  command.add_option("--timeout", options.timeoutSeconds, "seconds to wait for the answer (default 2)")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  command.add_option("--note", options.note, "free text carried with the request (why)")->option_text("TEXT");
  addStackOptions(command, options.stack);
}

void addCycle(CLI::App& group, CommandContext& context, ScheduleAction action) {
  auto options = std::make_shared<ScheduleCommandOptions>();
  options->action = action;
  const bool add = action == ScheduleAction::Add;
  CLI::App* cycle = group.add_subcommand(add ? "add" : "cycle", add ? ADD_DESCRIPTION : CYCLE_DESCRIPTION);
  cycle->footer(std::string(add ? ADD_FOOTER : CYCLE_FOOTER) + CONFIG_NOTE);
  cycle->add_option("MESSAGE", options->target, "DBC message name")->required()->type_name("");
  cycle->add_option("MS", options->value, "cycle time, ms (1..3600000)")->required()->type_name("");
  addCommandOptions(*cycle, *options);
  cycle->callback([options, &context] { context.exitCode = runScheduleCommand(*options, context.streams); });
}

void addEnable(CLI::App& group, CommandContext& context, ScheduleAction action) {
  auto options = std::make_shared<ScheduleCommandOptions>();
  options->action = action;
  const bool enable = action == ScheduleAction::Enable;
  CLI::App* command =
      group.add_subcommand(enable ? "enable" : "disable", enable ? ENABLE_DESCRIPTION : DISABLE_DESCRIPTION);
  command->footer(std::string(ENABLE_FOOTER) + CONFIG_NOTE);
  command->add_option("MESSAGE", options->target, "DBC message name")->required()->type_name("");
  addCommandOptions(*command, *options);
  command->callback([options, &context] { context.exitCode = runScheduleCommand(*options, context.streams); });
}

void addDefault(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<ScheduleCommandOptions>();
  options->action = ScheduleAction::Default;
  CLI::App* command = group.add_subcommand("default", DEFAULT_DESCRIPTION);
  command->footer(std::string(DEFAULT_FOOTER) + CONFIG_NOTE);
  command->add_option("KEY", options->target, "signal key")->required()->type_name("");
  command->add_option("VALUE", options->value, "a number or a value text")->required()->type_name("");
  addCommandOptions(*command, *options);
  command->callback([options, &context] { context.exitCode = runScheduleCommand(*options, context.streams); });
}

}  // namespace

ExitCode runScheduleImport(const ScheduleImportOptions& options, Streams streams) {
  const auto maybeGroupSignals = parseGroupSignals(options.groupSignals, streams.err);
  if (!maybeGroupSignals) return ExitCode::Usage;
  schedule::ImportOptions importOptions;
  importOptions.groupSignals = *maybeGroupSignals;
  importOptions.node = options.node;

  std::optional<Stack> maybeStack;
  std::optional<dbc::Database> maybeDatabase;
  if (!options.dbcFiles.empty()) {
    maybeDatabase = loadDatabase(options.dbcFiles, streams.err, false);
    if (!maybeDatabase) return ExitCode::Failure;
  } else {
    const char* fromEnvironment = std::getenv(std::string(CONFIG_ENVIRONMENT_VARIABLE).c_str());
    if (options.configPath.empty() && (fromEnvironment == nullptr || *fromEnvironment == '\0')) {
      reportError(streams.err, "no DBC to check against: give --config FILE, --dbc FILE or set " +
                                   std::string(CONFIG_ENVIRONMENT_VARIABLE));
      return ExitCode::Usage;
    }
    ExitCode exitCode = ExitCode::Ok;
    maybeStack = loadStack(StackOptions{options.configPath, {}}, streams.err, &exitCode);
    if (!maybeStack) return exitCode;
    if (importOptions.node.empty()) importOptions.node = maybeStack->config.node;
    importOptions.catalog = &maybeStack->catalog;
  }
  const dbc::Database& database = maybeDatabase ? *maybeDatabase : maybeStack->config.database;
  if (!options.node.empty() && !knownNode(database, options.node, streams.err)) return ExitCode::Failure;

  Result<std::string> readResult = readFileBytes(options.csvFile, input::TEXT_FILE);
  if (!readResult) {
    report(streams.err, readResult.error());
    return ExitCode::Failure;
  }
  std::vector<Error> diagnostics;
  auto importResult = schedule::importScheduleCsv(*readResult, options.csvFile, database, importOptions, &diagnostics);
  std::size_t errors = 0;
  for (const Error& diagnostic : diagnostics) {
    report(streams.err, diagnostic);
    if (diagnostic.severity == Severity::Error) ++errors;
  }
  if (!importResult) {
    report(streams.err,
           Error{plural(errors, "error") + ": nothing written", Location{options.csvFile, 0, 0, {}}, Severity::Note});
    return ExitCode::Failure;
  }
  const std::string text = importResult->dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
  if (options.outputFile.empty()) {
    streams.out.write(text);
    return ExitCode::Ok;
  }
  if (Status writeResult = writeFileAtomically(options.outputFile, text); !writeResult) {
    report(streams.err, writeResult.error());
    return ExitCode::Failure;
  }
  streams.out.write(options.outputFile + ": " + summaryText(*importResult) + " from " + options.csvFile + "\n");
  return ExitCode::Ok;
}

ExitCode runScheduleCommand(const ScheduleCommandOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const Stack& stack = *maybeStack;
  ipc::CommandRequest request;
  request.text = options.note;
  // Everything below is answered here, before anything is sent.
  if (options.action == ScheduleAction::Default) {
    const auto found = stack.catalog.find(options.target);
    if (!found) {
      reportError(streams.err, found.error().message);
      return ExitCode::Failure;
    }
    const signals::SignalInfo& signal = stack.catalog[*found];
    if (signal.kind != signals::SignalKind::Bus) {
      reportError(streams.err, "'" + signal.key +
                                   "' is an internal signal, not one of a DBC message: schedule defaults are for "
                                   "the signals can-tx sends (internal signals: 'vcu signal set')");
      return ExitCode::Failure;
    }
    const auto valueResult = parseValue(signal, options.value);
    if (!valueResult || !std::isfinite(*valueResult)) {
      reportError(streams.err,
                  valueResult ? "'" + options.value + "' is not a finite number" : valueResult.error().message);
      return ExitCode::Failure;
    }
    request.kind = ipc::CommandKind::ScheduleDefault;
    request.key = signal.key;
    request.value = *valueResult;
  } else {
    const dbc::Message* message = findBusMessage(stack.config.database, options.target, streams.err);
    if (message == nullptr) return ExitCode::Failure;
    request.key = message->name;
    if (options.action == ScheduleAction::Cycle || options.action == ScheduleAction::Add) {
      const auto maybeMs = parseMilliseconds(options.value);
      if (!maybeMs) {
        reportError(streams.err,
                    "cycle time '" + options.value + "': expected milliseconds, 1.." +
                        std::to_string(config::MAX_CYCLE_MS));
        return ExitCode::Failure;
      }
      if (const auto problem = config::checkCycleMs(*maybeMs)) {  // whole ms, the limits every reader uses
        reportError(streams.err, "cycle time '" + options.value + "': " + *problem);
        return ExitCode::Failure;
      }
      request.kind = options.action == ScheduleAction::Add ? ipc::CommandKind::ScheduleAdd
                                                           : ipc::CommandKind::ScheduleCycle;
      request.value = *maybeMs;
    } else {
      request.kind = ipc::CommandKind::ScheduleEnable;
      request.value = options.action == ScheduleAction::Enable ? 1.0 : 0.0;
    }
  }
  return sendCommandRequest(stack.config, std::move(request), options.timeoutSeconds, streams);
}

void registerScheduleCommands(CLI::App& app, CommandContext& context) {
  CLI::App* group = app.add_subcommand(
      "schedule", "vcu-can-tx's transmit schedule: import the thesis' sheet; add messages, change cycles, enables and defaults");
  addImport(*group, context);
  addCycle(*group, context, ScheduleAction::Cycle);
  addCycle(*group, context, ScheduleAction::Add);
  addEnable(*group, context, ScheduleAction::Enable);
  addEnable(*group, context, ScheduleAction::Disable);
  addDefault(*group, context);
}

}  // namespace openvcu::cli
