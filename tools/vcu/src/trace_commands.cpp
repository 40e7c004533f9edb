// `vcu trace`: the group, and the input every trace command shares.
#include "trace_commands.hpp"

#include <CLI/CLI.hpp>
#include <filesystem>
#include <system_error>

#include "cli_checks.hpp"
#include "dbc_commands.hpp"
#include "diagnostics.hpp"
#include "openvcu/trace/report_job.hpp"

namespace openvcu::cli {
void addTraceInputOptions(CLI::App& command, TraceInputOptions& options) {
  auto* config = command
                     .add_option("-c,--config", options.configFile,
                                 "vehicle configuration (vehicle.json or its folder): its DBC files, bit rates, "
                                 "schedule cycles and J1939-76 pairs")
                     ->option_text("FILE");
  auto* dbcOption =
      command.add_option("-d,--dbc", options.dbcFiles, "DBC file (repeat for several; merged in order)")
          ->option_text("FILE")
          ->take_all()
          ->allow_extra_args(false);  // one file per --dbc: "--dbc a.dbc drive.log -f json" leaves the log a LOG
  config->excludes(dbcOption);
  command
      .add_option_function<std::string>(
          "--match",
          [&options](const std::string& mode) {
            options.match = mode == "exact"          ? dbc::MatchMode::Exact
                            : mode == "j1939-tagged" ? dbc::MatchMode::J1939Tagged
                                                     : dbc::MatchMode::J1939;
          },
          "how frames find their DBC message (default j1939)")
      ->check(CLI::IsMember({"exact", "j1939", "j1939-tagged"}))
      ->option_text("exact|j1939|j1939-tagged");
  command
      .add_option("LOG", options.logs,
                  "CAN logs (candump -L, candump, ASC) or a folder written by vcu record; several = one timeline")
      ->required()
      ->type_name("");
}

std::optional<TraceInput> prepareTraceInput(const TraceInputOptions& options, Sink& err) {
  TraceInput input;
  input.reportedErrors = std::make_shared<std::uint64_t>(0);
  Result<trace::AnalysisSetup> setupResult = trace::emptySetup();
  if (!options.configFile.empty()) {
    const Result<std::string> vehicleFile = vehicleFileOf(options.configFile);
    setupResult =
        vehicleFile ? trace::loadSetupFromConfig(*vehicleFile) : Result<trace::AnalysisSetup>(vehicleFile.error());
  } else if (!options.dbcFiles.empty()) {
    setupResult = trace::loadSetupFromDbc(options.dbcFiles);
  }
  if (!setupResult) {
    report(err, setupResult.error());
    reportError(err, "going on without a DBC: messages are shown by identifier, expected cycles are unknown");
    input.failed = true;
    setupResult = trace::emptySetup();
  }
  input.setup = std::make_unique<trace::AnalysisSetup>(std::move(*setupResult));
  if (options.match) input.setup->match = *options.match;

  for (const std::string& log : options.logs) {
    std::error_code error;
    if (std::filesystem::is_directory(log, error)) {
      if (input.recordFolder.empty()) input.recordFolder = log;
      std::vector<std::string> logs = trace::recordingLogs(log);
      if (logs.empty()) {
        report(err, Error{"no *.log file in this folder", Location{log, 0, 0, {}}});
        input.failed = true;
      }
      input.logPaths.insert(input.logPaths.end(), logs.begin(), logs.end());
    } else {
      input.logPaths.push_back(log);
    }
  }
  if (input.logPaths.empty()) return std::nullopt;
  return input;
}

std::optional<TraceInput> openTraceInput(const TraceInputOptions& options, Sink& err) {
  std::optional<TraceInput> maybeInput = prepareTraceInput(options, err);
  if (!maybeInput) return std::nullopt;
  TraceInput& input = *maybeInput;
  auto reported = input.reportedErrors;
  Result<trace::LogTimeline> timelineResult =
      trace::LogTimeline::open(input.logPaths, *input.setup, [&err, reported](const Error& error) {
        if (*reported < MAX_REPORTED_LOG_ERRORS) report(err, error);
        ++*reported;
      });
  if (!timelineResult) {
    report(err, timelineResult.error());
    return std::nullopt;
  }
  input.timeline.emplace(std::move(*timelineResult));
  return maybeInput;
}

void reportSkipped(TraceInput& input, Sink& err) {
  for (const Error& skipped : trace::skippedLines(input.timeline->counts())) {
    report(err, skipped);
    if (skipped.severity == Severity::Error) input.failed = true;  // malformed lines
  }
  if (*input.reportedErrors > MAX_REPORTED_LOG_ERRORS) {
    reportError(err, "only the first " + std::to_string(MAX_REPORTED_LOG_ERRORS) + " of " +
                         std::to_string(*input.reportedErrors) + " log problems were shown");
  }
}

void registerTraceCommands(CLI::App& app, CommandContext& context) {
  CLI::App* traceGroup = app.add_subcommand(
      "trace", "CAN log analysis: traffic statistics, protocol checks (J1939-21/73/76), an HTML report");
  addTraceStats(*traceGroup, context);
  addTraceCheck(*traceGroup, context);
  addTraceReport(*traceGroup, context);
}

}  // namespace openvcu::cli
