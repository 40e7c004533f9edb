// `vcu check`: every file of a vehicle (check_commands.hpp says which loader checks what).
#include "check_commands.hpp"

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "cli_checks.hpp"
#include "diagnostics.hpp"
#include "openvcu/check/vehicle_check.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/dashboard.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/receive.hpp"
#include "openvcu/config/simulation.hpp"
#include "openvcu/config/telemetry.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/config/web.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/safety/safety_case.hpp"
#include "openvcu/schedule/schedule_config.hpp"

namespace openvcu::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* DESCRIPTION = "Check every file of a vehicle configuration, as the services load them";
constexpr const char* FOOTER =
    "Checks vehicle.json and through it the DBC files, the GPIO map, the FSM file, the\n"
    "schedule, simulation, receive, diagnostics, web, telemetry and safety files and the HMI dashboard\n"
    "(dashboard.json beside vehicle.json, if present) with the loaders the services use when they start;\n"
    "the safety case (safety.json) also against the FSM's states, the GPIO map, the signals and the\n"
    "services (docs/safety.md).\n"
    "While vehicle.json itself does not load, the files it names get the JSON syntax check\n"
    "only (a note says so). Then the whole-vehicle checks, which the services also run at\n"
    "start: unused received signals, FSM conditions on signals nobody writes, the expected\n"
    "load of each bus (above 70 % a warning, above 100 % an error), colliding J1939\n"
    "addresses and identifiers (docs/config.md, \"Whole-vehicle checks\").\n"
    "Diagnostics on stderr, one per line with file:line:column or\n"
    "the JSON path; then one summary line per file and a total on stdout.\n"
    "The configuration: PATH or --config FILE (vehicle.json or the folder holding it; both\n"
    "given must name the same file), else $OPENVCU_CONFIG, else the running stack's.\n"
    "\n"
    "Examples:\n"
    "  vcu check config/hhea/vehicle.json\n"
    "  vcu check config/hhea\n"
    "Exit: 0 no errors (warnings allowed), 1 errors, 2 usage error.\n";

std::string plural(std::size_t count, const std::string& word) {
  return std::to_string(count) + " " + word + (count == 1 ? "" : "s");
}

std::string normal(const std::string& path) {
  return fs::path(path).lexically_normal().string();
}

/// The files of the vehicle in report order, with their counts.
class FileTally {
 public:
  void add(const std::string& path) {
    if (find(path) == nullptr) m_files.push_back({path, normal(path), {}});
  }

  /// Reports `diagnostic` (warnings unless quiet) and counts it for its file (vehicle.json,
  /// the first file, when it names none of them).
  void report(const Error& diagnostic, bool quiet, Sink& err) {
    Entry* entry = find(diagnostic.location.file);
    if (entry == nullptr) entry = &m_files.front();
    if (diagnostic.severity == Severity::Error) {
      ++entry->counts.errors;
    } else if (diagnostic.severity == Severity::Warning) {
      ++entry->counts.warnings;
    }
    if (diagnostic.severity == Severity::Error || !quiet) cli::report(err, diagnostic);
  }

  void count(const std::string& path, const FileCounts& counts) {
    Entry* entry = find(path);
    if (entry == nullptr) entry = &m_files.front();
    entry->counts.errors += counts.errors;
    entry->counts.warnings += counts.warnings;
  }

  [[nodiscard]] FileCounts total() const {
    FileCounts sum;
    for (const Entry& entry : m_files) {
      sum.errors += entry.counts.errors;
      sum.warnings += entry.counts.warnings;
    }
    return sum;
  }

  void writeSummary(const std::string& vehicle, Sink& out) const {
    std::string text;
    for (const Entry& entry : m_files) {
      text += entry.path + ": " + plural(entry.counts.errors, "error") + ", " +
              plural(entry.counts.warnings, "warning") + "\n";
    }
    const FileCounts sum = total();
    text += vehicle + ": " + plural(m_files.size(), "file") + ", " + plural(sum.errors, "error") + ", " +
            plural(sum.warnings, "warning") + "\n";
    out.write(text);
  }

 private:
  struct Entry {
    std::string path;
    std::string normalPath;
    FileCounts counts;
  };

  Entry* find(const std::string& path) {
    if (path.empty()) return nullptr;
    const std::string wanted = normal(path);
    for (Entry& entry : m_files) {
      if (entry.normalPath == wanted) return &entry;
    }
    return nullptr;
  }

  std::vector<Entry> m_files;
};

/// A file read as JSON: its syntax error (line:column), or an error when the top level is
/// not an object.
std::optional<Error> jsonObjectError(const std::string& path) {
  auto json = config::readJsonFile(path);
  if (!json) return json.error();
  if (!json->is_object()) return Error{"the top level must be a JSON object", Location::json(path, "")};
  return std::nullopt;
}

/// Checks `path` with `load`, the loader of the service that reads it, after the JSON
/// check (syntax with line:column, a top-level object): its first error is reported.
template <typename Loader>
void checkWithLoader(const std::string& path, Loader&& load, FileTally& tally, bool quiet, Sink& err) {
  if (const auto error = jsonObjectError(path)) {
    tally.report(*error, quiet, err);
    return;
  }
  if (auto loadResult = load(); !loadResult) tally.report(loadResult.error(), quiet, err);
}

/// dashboard.json beside vehicle.json, where vcu-hmi looks for it; empty when absent.
std::string dashboardBeside(const std::string& vehiclePath) {
  const fs::path beside = fs::path(vehiclePath).parent_path() / "dashboard.json";
  std::error_code error;
  return fs::exists(beside, error) ? beside.string() : std::string();
}

/// The files vehicle.json names, resolved, read from its JSON alone (used when it does not load).
std::vector<std::string> namedFiles(const std::string& vehiclePath) {
  std::vector<std::string> files;
  auto json = config::readJsonFile(vehiclePath);
  if (!json || !json->is_object()) return files;
  const fs::path directory = fs::path(vehiclePath).parent_path();
  for (const char* key : {"fsm", "schedule", "simulation", "receive", "diagnostics", "web", "telemetry", "safety"}) {
    const auto it = json->find(key);
    if (it == json->end() || !it->is_string()) continue;
    const fs::path file(it->get<std::string>());
    files.push_back((file.is_absolute() ? file : directory / file).lexically_normal().string());
  }
  return files;
}

bool isSendGroupDiagnostic(const Error& diagnostic) {
  constexpr std::string_view SUFFIX = "/sendGroup";
  const std::string& path = diagnostic.location.jsonPath;
  return path.size() >= SUFFIX.size() && path.compare(path.size() - SUFFIX.size(), SUFFIX.size(), SUFFIX) == 0;
}

/// safety.json: its loader's first error, else every cross-check against the vehicle
/// (the FSM's states only when fsm.json loads; its own errors are fsm.json's).
void checkSafetyFile(const Stack& stack, FileTally& tally, bool quiet, Sink& err) {
  const config::VehicleConfig& vehicle = stack.config;
  if (const auto error = jsonObjectError(vehicle.safetyFile)) {
    tally.report(*error, quiet, err);
    return;
  }
  auto safetyCase = safety::loadSafety(vehicle.safetyFile);
  if (!safetyCase) {
    tally.report(safetyCase.error(), quiet, err);
    return;
  }
  std::optional<std::vector<std::string>> states;
  if (!vehicle.fsmFile.empty()) {
    if (auto machine = fsm::loadMachine(vehicle.fsmFile, vehicle, stack.catalog)) {
      states.emplace();
      for (const fsm::State& state : machine->states) states->push_back(state.name);
    }
  } else {
    states.emplace();  // no FSM: every state a hazard names is unknown
  }
  for (const Error& diagnostic :
       safety::checkSafety(*safetyCase, vehicle, stack.catalog, states ? &*states : nullptr)) {
    tally.report(diagnostic, quiet, err);
  }
}

}  // namespace

FileCounts checkFsmFile(const std::string& file, const Stack& stack, bool quiet, Sink& err) {
  FileCounts counts;
  std::optional<Error> scheduleError;
  if (!stack.config.scheduleFile.empty()) {
    if (auto schedule = config::readJsonFile(stack.config.scheduleFile); !schedule) scheduleError = schedule.error();
  }
  if (scheduleError) {
    // The machine's send groups come from the schedule: with the schedule unreadable every
    // sendGroup action would be reported as an unknown group of the FSM file.
    report(err, *scheduleError);
    ++counts.errors;
  }
  std::size_t uncheckedGroups = 0;
  for (const Error& diagnostic : fsm::checkMachine(file, stack.config, stack.catalog)) {
    if (scheduleError && isSendGroupDiagnostic(diagnostic)) {
      ++uncheckedGroups;
      continue;
    }
    const bool error = diagnostic.severity == Severity::Error;
    counts.errors += error ? 1 : 0;
    counts.warnings += error ? 0 : 1;
    if (error || !quiet) report(err, diagnostic);
  }
  if (uncheckedGroups > 0) {
    report(err, Error{plural(uncheckedGroups, "send-group action") + " not checked: the schedule " +
                          stack.config.scheduleFile + " does not parse",
                      Location{file, 0, 0, {}}, Severity::Note});
  }
  return counts;
}

ExitCode runCheck(const VehicleCheckOptions& options, Streams streams) {
  StackOptions stackOptions = options.stack;
  if (!options.path.empty()) {
    if (!stackOptions.configPath.empty() && !sameVehicleFile(options.path, stackOptions.configPath)) {
      reportError(streams.err, "two configurations given: '" + options.path + "' and --config '" +
                                   stackOptions.configPath + "'; give one");
      return ExitCode::Usage;
    }
    stackOptions.configPath = options.path;
  }
  ExitCode exitCode = ExitCode::Ok;
  const auto maybePath = resolveConfigPath(stackOptions, streams.err, &exitCode);
  if (!maybePath) return exitCode;
  const Result<std::string> vehicleFile = vehicleFileOf(*maybePath);
  if (!vehicleFile) {
    report(streams.err, vehicleFile.error());
    return ExitCode::Failure;
  }
  const std::string& vehiclePath = *vehicleFile;
  FileTally tally;
  tally.add(vehiclePath);

  const std::vector<Error> vehicleDiagnostics = config::checkVehicleConfig(vehiclePath);
  auto loaded = config::loadVehicleConfig(vehiclePath);
  std::optional<Stack> stack;
  std::string vehicleName = vehiclePath;
  if (loaded) {
    for (const std::string& dbc : loaded->dbcFiles) tally.add(dbc);
    if (!loaded->gpioFile.empty()) tally.add(loaded->gpioFile);
    vehicleName = "vehicle '" + loaded->instance + "'";
  }
  for (const Error& diagnostic : vehicleDiagnostics) {
    tally.add(diagnostic.location.file.empty() ? vehiclePath : diagnostic.location.file);
    tally.report(diagnostic, options.quiet, streams.err);
  }
  if (loaded) {
    auto catalog = config::buildCatalog(*loaded);
    if (!catalog) {
      tally.report(Error{catalog.error().message, Location{vehiclePath, 0, 0, {}}}, options.quiet, streams.err);
    } else {
      stack = Stack{std::move(*loaded), std::move(*catalog)};
    }
  }

  const std::string dashboard = dashboardBeside(vehiclePath);
  if (stack) {
    const config::VehicleConfig& vehicle = stack->config;
    if (!vehicle.fsmFile.empty()) tally.add(vehicle.fsmFile);
    if (!vehicle.scheduleFile.empty()) tally.add(vehicle.scheduleFile);
    const bool scheduleBroken = !vehicle.scheduleFile.empty() && !config::readJsonFile(vehicle.scheduleFile);
    if (!vehicle.fsmFile.empty()) {
      // checkFsmFile reports a schedule that does not parse itself: counted for the schedule
      FileCounts fsmCounts = checkFsmFile(vehicle.fsmFile, *stack, options.quiet, streams.err);
      if (scheduleBroken) {
        --fsmCounts.errors;
        tally.count(vehicle.scheduleFile, FileCounts{1, 0});
      }
      tally.count(vehicle.fsmFile, fsmCounts);
    }
    if (!vehicle.scheduleFile.empty() && !(scheduleBroken && !vehicle.fsmFile.empty())) {
      checkWithLoader(
          vehicle.scheduleFile, [&] { return schedule::loadSchedule(vehicle, stack->catalog); }, tally, options.quiet,
          streams.err);
    }
    if (!vehicle.simulationFile.empty()) {
      tally.add(vehicle.simulationFile);
      checkWithLoader(
          vehicle.simulationFile, [&] { return config::loadSimConfig(vehicle.simulationFile, vehicle); }, tally,
          options.quiet, streams.err);
    }
    if (!vehicle.receiveFile.empty()) {
      tally.add(vehicle.receiveFile);
      checkWithLoader(
          vehicle.receiveFile, [&] { return config::loadReceiveConfig(vehicle); }, tally, options.quiet, streams.err);
    }
    if (!dashboard.empty()) {
      tally.add(dashboard);
      checkWithLoader(
          dashboard, [&] { return config::loadDashboardConfig(dashboard, stack->catalog); }, tally, options.quiet,
          streams.err);
    }
    if (!vehicle.webFile.empty()) {
      tally.add(vehicle.webFile);
      std::vector<Error> webWarnings;
      auto web = config::loadWebConfig(vehicle.webFile, &webWarnings);
      if (!web) tally.report(web.error(), options.quiet, streams.err);
      for (const Error& warning : webWarnings) tally.report(warning, options.quiet, streams.err);
    }
    if (!vehicle.telemetryFile.empty()) {
      tally.add(vehicle.telemetryFile);
      std::vector<Error> telemetryWarnings;
      auto telemetry = config::loadTelemetryConfig(vehicle.telemetryFile, &telemetryWarnings);
      if (!telemetry) tally.report(telemetry.error(), options.quiet, streams.err);
      for (const Error& warning : telemetryWarnings) tally.report(warning, options.quiet, streams.err);
      if (telemetry) {
        for (const config::TelemetrySignal& signal : telemetry->signals) {
          if (!stack->catalog.indexOf(signal.name)) {
            tally.report(
                Error{"/signals: unknown signal '" + signal.name + "'", Location{vehicle.telemetryFile, 0, 0, {}}},
                options.quiet, streams.err);
          }
        }
      }
    }
    if (!vehicle.safetyFile.empty()) {
      tally.add(vehicle.safetyFile);
      checkSafetyFile(*stack, tally, options.quiet, streams.err);
    }
    // diagnostics.json is loaded by the whole-vehicle check (it needs the FSM's states)
    if (!vehicle.diagnosticsFile.empty()) tally.add(vehicle.diagnosticsFile);
    // The files together (docs/config.md, "Whole-vehicle checks"), as every service does at start.
    for (const Error& diagnostic : check::checkVehicle(vehicle, stack->catalog)) {
      tally.report(diagnostic, options.quiet, streams.err);
    }
  } else {
    if (!options.quiet) {
      report(streams.err, Error{"the files it names and the dashboard get the JSON syntax check only until it loads",
                                Location{vehiclePath, 0, 0, {}}, Severity::Note});
    }
    std::vector<std::string> files = namedFiles(vehiclePath);
    if (!dashboard.empty()) files.push_back(dashboard);
    for (const std::string& path : files) {
      std::error_code error;
      if (!fs::exists(path, error)) continue;  // vehicle.json's own error says so
      tally.add(path);
      if (const auto syntax = jsonObjectError(path)) tally.report(*syntax, options.quiet, streams.err);
    }
  }

  tally.writeSummary(vehicleName, streams.out);
  return tally.total().errors == 0 ? ExitCode::Ok : ExitCode::Failure;
}

void registerCheckCommands(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<VehicleCheckOptions>();
  CLI::App* command = app.add_subcommand("check", DESCRIPTION);
  command->footer(FOOTER);
  command->add_option("PATH", options->path, "the vehicle configuration: vehicle.json or its folder")->type_name("");
  command
      ->add_option("-c,--config", options->stack.configPath,
                   "the same as PATH (default: $OPENVCU_CONFIG, else the running stack's)")
      ->option_text("FILE");
  command->add_flag("-q,--quiet", options->quiet, "errors only, no warnings or notes");
  command->callback([options, &context] { context.exitCode = runCheck(*options, context.streams); });
}

}  // namespace openvcu::cli
