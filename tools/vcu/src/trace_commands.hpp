#pragma once
// The `vcu trace` command group: stats, check, report over one or more CAN logs read as one
// timeline (shared/trace: LogTimeline, TraceStats, TraceChecker, the HTML report). This file
// holds what the three commands share: the input options (--config | --dbc, LOG...), opening
// the setup and the timeline with every problem reported, and the closing summary of what was
// skipped. Each command lives in its own file (trace_stats.cpp, trace_check.cpp,
// trace_report.cpp) and is added to the group by registerTraceCommands().
//
//   vcu trace stats --config config/hhea/vehicle.json drive1/vehicle.log
//   vcu trace check --dbc j1939.dbc truck.log --format json
//   vcu trace report --config config/hhea/vehicle.json drive1 -o drive1.html

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/trace/timeline.hpp"

namespace CLI {
class App;
}

namespace openvcu::cli {

/// The options every `vcu trace` command takes.
struct TraceInputOptions {
  std::string configFile;               ///< vehicle.json or its folder; excludes dbcFiles
  std::vector<std::string> dbcFiles;    ///< merged in order
  std::vector<std::string> logs;        ///< candump -L, candump, ASC; a folder = its *.log files (vcu record)
  std::optional<dbc::MatchMode> match;  ///< default: the setup's (J1939)
};

/// An opened input: the setup and the merged timeline (`vcu trace report` hands the setup and
/// the log paths to trace::makeReport instead). `failed` is set when something could
/// not be read (a DBC, a malformed line): the command goes on and exits with 1.
struct TraceInput {
  std::unique_ptr<trace::AnalysisSetup> setup;
  std::optional<trace::LogTimeline> timeline;
  std::vector<std::string> logPaths;  ///< the files read (folders expanded)
  std::string recordFolder;           ///< the first folder given (vcu record), for its events.lcmlog
  bool failed{};
  std::shared_ptr<std::uint64_t> reportedErrors;  ///< malformed lines printed so far
};

/// Adds --config, --dbc, --match and LOG... to `command`.
void addTraceInputOptions(CLI::App& command, TraceInputOptions& options);

/// Loads the setup (a DBC or configuration that cannot be read is reported and the analysis
/// goes on without it, `failed` set) and lists the logs (a folder: its *.log files); opens
/// no log (`timeline` stays empty). Empty after reporting when there is no log to read.
[[nodiscard]] std::optional<TraceInput> prepareTraceInput(const TraceInputOptions& options, Sink& err);

/// prepareTraceInput(), then opens the logs as one timeline. Empty after reporting when a
/// log cannot be opened.
[[nodiscard]] std::optional<TraceInput> openTraceInput(const TraceInputOptions& options, Sink& err);

/// After the timeline is read: one line on `err` per log with what was skipped (malformed
/// lines, lines without time, backward steps); sets input.failed for malformed lines.
void reportSkipped(TraceInput& input, Sink& err);

/// `vcu trace stats` (trace_stats.cpp).
void addTraceStats(CLI::App& trace, CommandContext& context);
/// Adds `vcu trace check` (trace_check.cpp) to the `trace` group.
void addTraceCheck(CLI::App& trace, CommandContext& context);
/// Adds `vcu trace report` (trace_report.cpp) to the `trace` group.
void addTraceReport(CLI::App& trace, CommandContext& context);

/// Adds `trace` and its subcommands to `app`.
void registerTraceCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
