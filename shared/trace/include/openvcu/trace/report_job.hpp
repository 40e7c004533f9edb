#pragma once
// The trace report as one call (`vcu trace report`, vcu-web's report and summary of a
// recording or an uploaded log; design: docs/design/trace-report.md): the logs read as one
// timeline, statistics and protocol checks in one pass, the chosen signals in a second pass
// (their time range is known by then: each keeps a fixed number of min/max buckets), the
// FSM transitions and faults of a `vcu record` folder's events.lcmlog, and the HTML of
// renderHtmlReport(). summarize() is the first pass alone, without HTML.
//
//   auto setupResult = loadSetupFromConfig("config/hhea/vehicle.json");
//   auto jobResult = jobForFolder("recordings/drive1", std::move(*setupResult));
//   jobResult->signals = {"HVESSD1_PGN61584.HS_ULvl"};
//   auto reportResult = makeReport(*jobResult);
//   if (!reportResult) return reportResult.error();       // no log could be opened
//   for (const Error& e : reportResult->inputErrors) warn(e);   // what was left out, and why
//   write("drive1.html", reportResult->html);               // 4711 frames, 2 buses, ...
//
// Bad input: a log that cannot be opened is left out (an input error names it and the
// reason); the call fails only when no log can be opened. Malformed lines, unknown signal
// names, an unreadable events.lcmlog become input errors (severity Error); time going
// backwards and lines without a time become warnings. Never throws: an exception inside
// (out of memory) becomes the returned Error.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/trace/timeline.hpp"

namespace openvcu::trace {

/// Log problems listed one by one in ReportOutcome::inputErrors (as `vcu trace` prints
/// them); the rest are counted in the per-log lines that follow them.
inline constexpr std::size_t MAX_LISTED_LOG_ERRORS = 20;
/// Points per chosen signal: the min and max of each of this many equal slices of the
/// timeline's duration, whatever the number of samples.
inline constexpr std::size_t SIGNAL_BUCKETS = 2000;
/// The events log `vcu record` writes beside its <bus>.log files.
inline constexpr const char* RECORDING_EVENTS_LOG = "events.lcmlog";
/// How many frames pass between two looks at ReportJob::cancel.
inline constexpr std::uint64_t CANCEL_POLL_FRAMES = 4096;

/// What to report on.
struct ReportJob {
  AnalysisSetup setup;            ///< loadSetupFromConfig / loadSetupFromDbc / emptySetup
  std::vector<std::string> logs;  ///< candump -L, candump, ASC: read as one timeline
  std::string eventsLog;          ///< events.lcmlog of a `vcu record` folder; empty: none
  /// Signals to chart: "MESSAGE.SIGNAL" as in the DBC, or the table key
  /// "NODE.MESSAGE.SIGNAL" (config::signalKey). Empty: no signal chart.
  std::vector<std::string> signals;
  std::string title;  ///< the heading; empty: the first log's file name
  /// Frames read at most (each pass); 0: all. A log cut short says so in a warning and the
  /// report covers what was read.
  std::uint64_t maxFrames{};
  /// Set from another thread to stop: the call returns the Error "cancelled" within
  /// CANCEL_POLL_FRAMES frames. Null: not cancellable. Must outlive the call.
  const std::atomic<bool>* cancel{};
};

/// A bus of the summary.
struct BusSummary {
  std::string name;
  std::uint64_t frames{};
  double loadMeanPct{};
  double loadMaxPct{};  ///< the busiest 1 s window
};

/// The short answer: what was read and what the checks found.
struct ReportSummary {
  std::uint64_t frames{};
  double durationS{};               ///< first to last frame
  double startS{};                  ///< the first frame's log time, s (candump: since 1970)
  std::vector<std::string> buses;   ///< log channels as LogTimeline::buses() names them
  std::vector<BusSummary> busLoad;  ///< per bus with frames, in the order of `buses`
  std::uint64_t errors{};           ///< findings of severity Fault (protocol faults)
  std::uint64_t warnings{};         ///< findings of severity Warning
  std::uint64_t infos{};            ///< findings of severity Info
  std::uint64_t messages{};         ///< distinct (bus, identifier) streams
  std::uint64_t errorFrames{};
  std::uint64_t malformedLines{};           ///< all logs, skipped
  std::vector<std::string> logs;            ///< the logs read
  std::vector<std::string> unreadableLogs;  ///< the logs that could not be opened (left out)
  bool truncated{};                         ///< stopped at ReportJob::maxFrames
};

struct ReportOutcome {
  std::string html;  ///< the whole document (renderHtmlReport)
  ReportSummary summary;
  std::vector<Error> inputErrors;  ///< in the order found; severity Error, Warning or Note
};

/// The HTML report of `job` (the document `vcu trace report` writes). Fails only when no
/// log can be opened (the Error names it) or when cancelled.
/// @note allocates; reads every log twice when signals are chosen, once otherwise;
/// reentrant (no shared state): one job per thread.
[[nodiscard]] Result<ReportOutcome> makeReport(const ReportJob& job);

/// The statistics and checks of `job` without HTML, signals or events: one pass. Input
/// errors are appended to `inputErrors` when given.
/// @note as makeReport.
[[nodiscard]] Result<ReportSummary> summarize(const ReportJob& job, std::vector<Error>* inputErrors = nullptr);

/// The *.log files of a folder written by `vcu record` (one per bus), sorted by name;
/// empty when there is none or the folder cannot be read.
[[nodiscard]] std::vector<std::string> recordingLogs(const std::string& folder);

/// The events.lcmlog of a `vcu record` folder; empty when the folder has none.
[[nodiscard]] std::string recordingEventsLog(const std::string& folder);

/// The job of a `vcu record` folder as `vcu trace report` finds it: its *.log files, its
/// events.lcmlog when there is one, the folder's name as the title. Fails when `folder` is
/// not a folder or holds no *.log file.
[[nodiscard]] Result<ReportJob> jobForFolder(const std::string& folder, AnalysisSetup setup);

/// One Error per log with what was skipped (as `vcu trace` prints it): malformed lines are
/// errors of the input (severity Error), lines without a time and frames earlier than the one
/// before them are what the analysis left out (Warning). Logs with nothing skipped give none.
[[nodiscard]] std::vector<Error> skippedLines(const std::vector<LogCounts>& counts);

}  // namespace openvcu::trace
