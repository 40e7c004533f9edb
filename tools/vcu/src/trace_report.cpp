// vcu trace report: one self-contained HTML file of a timeline. The pipeline (statistics and
// checks in one pass over the logs, the chosen signals in a second pass, the FSM transitions
// and faults of a `vcu record` folder's events.lcmlog, the document) is trace::makeReport
// (shared/trace report_job.hpp), which vcu-web calls as well; this file turns the options
// into a trace::ReportJob, prints the input errors and writes the file.
//
//   vcu trace report --config config/hhea/vehicle.json drive1 -o drive1.html
//       --signals HVESSD1_PGN61584.HS_ULvl,ST_MOT_1.st_mot_n
#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <memory>

#include "diagnostics.hpp"
#include "openvcu/trace/report_job.hpp"
#include "trace_commands.hpp"

namespace openvcu::cli {
namespace {

constexpr const char* REPORT_DESCRIPTION = "One self-contained HTML report of CAN logs: the thesis' chapter 7 figures and more";
constexpr const char* REPORT_FOOTER =
    "Writes ONE HTML file (no external file, no network: it opens offline in any browser and\n"
    "can be mailed) with:\n"
    "  - bus load over time, per bus (exact wire bits, 1 s windows);\n"
    "  - data rate per node (J1939 source address), thesis Figure 7.1;\n"
    "  - expected vs measured cycle per message, Figure 7.2, and their difference, Figure 7.3;\n"
    "  - the signals of --signals on a zoomable time axis (min/max per pixel column);\n"
    "  - the DTC timeline (DM1/DM2 of every ECU, also by BAM/RTS-CTS);\n"
    "  - for a folder written by `vcu record`: the FSM transitions and faults of its\n"
    "    events.lcmlog on the same time axis;\n"
    "  - the findings of `vcu trace check` and the tables of `vcu trace stats`.\n"
    "Time charts zoom with the mouse wheel, pan by dragging, reset with a double click.\n"
    "\n"
    "Examples:\n"
    "  vcu trace report --config config/hhea/vehicle.json drive1 -o drive1.html\n"
    "  vcu trace report --dbc j1939.dbc truck.log -o truck.html --signals EEC1.EngineSpeed\n"
    "Exit: 0 written; 1 input errors (unreadable log, DBC or event log, malformed lines; the\n"
    "report is still written with what could be read) or the file cannot be written; 2 usage.\n";

struct ReportArguments {
  TraceInputOptions input;
  std::string output;
  std::vector<std::string> signals;
  std::string title;
};

/// The heading: --title, else the name of the first LOG argument ("drive1/" -> "drive1").
std::string reportTitle(const ReportArguments& arguments) {
  if (!arguments.title.empty()) return arguments.title;
  std::filesystem::path first(arguments.input.logs.front());
  if (!first.has_filename()) first = first.parent_path();
  return first.filename().string();
}

ExitCode runReport(const ReportArguments& arguments, Streams streams) {
  std::optional<TraceInput> maybeInput = prepareTraceInput(arguments.input, streams.err);
  if (!maybeInput) return ExitCode::Failure;
  TraceInput& input = *maybeInput;

  trace::ReportJob job;
  job.setup = std::move(*input.setup);
  job.logs = input.logPaths;
  if (!input.recordFolder.empty()) job.eventsLog = trace::recordingEventsLog(input.recordFolder);
  job.signals = arguments.signals;
  job.title = reportTitle(arguments);
  Result<trace::ReportOutcome> reportResult = trace::makeReport(job);
  if (!reportResult) {
    report(streams.err, reportResult.error());
    return ExitCode::Failure;
  }
  const trace::ReportOutcome& outcome = *reportResult;
  for (const Error& error : outcome.inputErrors) {
    report(streams.err, error);
    if (error.severity == Severity::Error) input.failed = true;
  }

  std::ofstream file(arguments.output, std::ios::binary | std::ios::trunc);
  file.write(outcome.html.data(), static_cast<std::streamsize>(outcome.html.size()));
  file.close();
  if (!file) {
    report(streams.err, Error{"cannot write the report", Location{arguments.output, 0, 0, {}}});
    return ExitCode::Failure;
  }
  const trace::ReportSummary& summary = outcome.summary;
  streams.out.write(arguments.output + ": " + std::to_string(outcome.html.size() / 1024) + " KiB, " +
                    std::to_string(summary.frames) + " frames over " +
                    std::to_string(static_cast<long long>(summary.durationS)) + " s, " +
                    std::to_string(summary.errors + summary.warnings + summary.infos) + " findings\n");
  return input.failed ? ExitCode::Failure : ExitCode::Ok;
}

}  // namespace

void addTraceReport(CLI::App& traceGroup, CommandContext& context) {
  auto arguments = std::make_shared<ReportArguments>();
  CLI::App* command = traceGroup.add_subcommand("report", REPORT_DESCRIPTION);
  command->footer(REPORT_FOOTER);
  addTraceInputOptions(*command, arguments->input);
  command->add_option("-o,--output", arguments->output, "the HTML file to write")->required()->option_text("FILE");
  command->add_option("--signals", arguments->signals,
                      "signals to draw: MESSAGE.SIGNAL (as in the DBC) or NODE.MESSAGE.SIGNAL (the table key), comma-separated")
      ->delimiter(',')
      ->option_text("KEY,...");
  command->add_option("--title", arguments->title, "the report's heading (default: the first log's name)")
      ->option_text("TEXT");
  command->callback([arguments, &context] { context.exitCode = runReport(*arguments, context.streams); });
}

}  // namespace openvcu::cli
