// makeReport() and summarize(): the logs that open, the first pass (statistics and checks),
// and the document; the signals' pass and the event lanes are in report_passes.cpp.
#include "openvcu/trace/report_job.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <system_error>
#include <utility>

#include "openvcu/can/log_reader.hpp"
#include "openvcu/trace/check.hpp"
#include "openvcu/trace/html_report.hpp"
#include "openvcu/trace/stats.hpp"
#include "report_passes.hpp"

namespace openvcu::trace {
namespace {

using detail::FrameBudget;

/// What the first pass found: everything of the report but the signals and the events.
struct FirstPass {
  std::vector<std::string> logs;        ///< opened
  std::vector<std::string> unreadable;  ///< left out
  std::vector<std::string> buses;
  std::vector<LogCounts> counts;
  std::int64_t startNs{};
  StatsReport stats;
  FindingList findings;
  std::vector<DtcInterval> dtcs;
  std::uint64_t dtcIntervalsSkipped{};
  bool truncated{};
};

/// The logs of `job` that open; an Error in `errors` for each one that does not.
std::vector<std::string> openableLogs(const ReportJob& job, std::vector<std::string>& unreadable,
                                      std::vector<Error>& errors, std::optional<Error>& firstError) {
  std::vector<std::string> logs;
  for (const std::string& path : job.logs) {
    Result<can::LogReader> readerResult = can::LogReader::open(path);
    if (readerResult) {
      logs.push_back(path);
      continue;
    }
    unreadable.push_back(path);
    errors.push_back(readerResult.error());
    if (!firstError) firstError = readerResult.error();
  }
  return logs;
}


Result<FirstPass> readFirstPass(const ReportJob& job, std::vector<Error>& errors) {
  FirstPass pass;
  std::optional<Error> firstError;
  pass.logs = openableLogs(job, pass.unreadable, errors, firstError);
  if (pass.logs.empty()) {
    if (job.logs.empty()) return Error{"no log given"};
    if (job.logs.size() == 1) return *firstError;
    return Error{
        "none of the " + std::to_string(job.logs.size()) + " logs can be opened; the first: " + firstError->message,
        firstError->location};
  }
  std::uint64_t logProblems = 0;
  Result<LogTimeline> timelineResult =
      LogTimeline::open(pass.logs, job.setup, [&errors, &logProblems](const Error& error) {
        if (logProblems < MAX_LISTED_LOG_ERRORS) errors.push_back(error);
        ++logProblems;
      });
  if (!timelineResult) return timelineResult.error();  // opened a moment ago: gone since
  LogTimeline& timeline = *timelineResult;

  TraceStats stats(job.setup, timeline.buses());
  TraceChecker checker(job.setup);
  ReportFindings findings;
  FrameBudget budget(job);
  TraceFrame frame;
  std::int64_t lastNs = 0;
  while (budget.allowsAnother() && timeline.next(frame)) {
    stats.add(frame);
    checker.add(frame, findings);
    lastNs = frame.timeNs;
  }
  if (budget.cancelled()) return detail::cancelledError();
  if (budget.limitReached() && timeline.next(frame)) {
    pass.truncated = true;
    char covered[32];
    std::snprintf(covered, sizeof covered, "%.3f", static_cast<double>(lastNs - timeline.startNs()) / 1e9);
    errors.push_back(Error{"stopped after " + std::to_string(job.maxFrames) +
                               " frames (the limit): the report covers the first " + covered + " s of the timeline",
                           Location{pass.logs[frame.log], static_cast<std::uint32_t>(frame.line), 0, {}},
                           openvcu::Severity::Warning});
  }
  checker.finish(lastNs, findings);
  for (Error& skipped : skippedLines(timeline.counts())) errors.push_back(std::move(skipped));
  if (logProblems > MAX_LISTED_LOG_ERRORS) {
    errors.push_back(Error{"only the first " + std::to_string(MAX_LISTED_LOG_ERRORS) + " of " +
                               std::to_string(logProblems) + " log problems were listed",
                           Location{}, openvcu::Severity::Note});
  }

  pass.buses = timeline.buses();
  pass.counts = timeline.counts();
  pass.startNs = timeline.startNs();
  pass.stats = stats.finish(timeline.buses());
  pass.findings = findings.list();
  pass.dtcs = checker.transport().dtcIntervals();
  pass.dtcIntervalsSkipped = checker.transport().counts().dtcIntervalsSkipped;
  return pass;
}

ReportSummary summaryOf(const FirstPass& pass) {
  ReportSummary summary;
  summary.frames = pass.stats.frames;
  summary.durationS = pass.stats.durationS;
  summary.startS = pass.stats.startS;
  summary.buses = pass.buses;
  for (const BusStats& bus : pass.stats.buses) {
    summary.busLoad.push_back(BusSummary{bus.bus, bus.frames, bus.loadMeanPct, bus.loadMaxPct});
    summary.errorFrames += bus.errorFrames;
  }
  summary.errors = pass.findings.bySeverity[static_cast<std::size_t>(Severity::Fault)];
  summary.warnings = pass.findings.bySeverity[static_cast<std::size_t>(Severity::Warning)];
  summary.infos = pass.findings.bySeverity[static_cast<std::size_t>(Severity::Info)];
  summary.messages = pass.stats.messages.size();
  for (const LogCounts& count : pass.counts) summary.malformedLines += count.malformedLines;
  summary.logs = pass.logs;
  summary.unreadableLogs = pass.unreadable;
  summary.truncated = pass.truncated;
  return summary;
}

std::string defaultTitle(const ReportJob& job) {
  if (!job.title.empty() || job.logs.empty()) return job.title;
  return std::filesystem::path(job.logs.front()).filename().string();
}

Result<ReportOutcome> makeReportUnguarded(const ReportJob& job) {
  ReportOutcome outcome;
  const std::vector<SignalRef> refs = detail::resolveSignals(job.setup.database, job.signals, outcome.inputErrors);
  Result<FirstPass> passResult = readFirstPass(job, outcome.inputErrors);
  if (!passResult) return passResult.error();
  FirstPass& pass = *passResult;

  outcome.summary = summaryOf(pass);
  ReportInput document;
  document.title = defaultTitle(job);
  document.source = job.setup.source + "; logs:";
  for (const std::string& path : pass.logs) document.source += " " + path;
  document.stats = std::move(pass.stats);
  document.buses = std::move(pass.buses);
  document.dtcs = std::move(pass.dtcs);
  document.dtcIntervalsSkipped = pass.dtcIntervalsSkipped;
  document.findings = std::move(pass.findings);
  Result<std::vector<SignalSeries>> seriesResult =
      detail::extractSignalSeries(job, pass.logs, refs, pass.startNs, document.stats.durationS);
  if (seriesResult) {
    document.signals = std::move(*seriesResult);
  } else if (job.cancel != nullptr && job.cancel->load(std::memory_order_relaxed)) {
    return seriesResult.error();
  } else {
    outcome.inputErrors.push_back(seriesResult.error());
  }
  if (!job.eventsLog.empty()) {
    document.eventLanes = detail::recordedEventLanes(job.eventsLog, pass.startNs, outcome.inputErrors);
  }

  outcome.html = renderHtmlReport(document);
  return outcome;
}

}  // namespace

Result<ReportOutcome> makeReport(const ReportJob& job) {
  try {
    return makeReportUnguarded(job);
  } catch (const std::exception& exception) {
    return Error{std::string("trace report: ") + exception.what()};
  }
}

Result<ReportSummary> summarize(const ReportJob& job, std::vector<Error>* inputErrors) {
  try {
    std::vector<Error> errors;
    Result<FirstPass> passResult = readFirstPass(job, errors);
    if (inputErrors != nullptr) inputErrors->insert(inputErrors->end(), errors.begin(), errors.end());
    if (!passResult) return passResult.error();
    return summaryOf(*passResult);
  } catch (const std::exception& exception) {
    return Error{std::string("trace summary: ") + exception.what()};
  }
}

std::vector<std::string> recordingLogs(const std::string& folder) {
  std::vector<std::string> logs;
  std::error_code error;
  for (std::filesystem::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    if (it->path().extension() == ".log" && it->is_regular_file(error)) logs.push_back(it->path().string());
  }
  std::sort(logs.begin(), logs.end());
  return logs;
}

std::string recordingEventsLog(const std::string& folder) {
  const std::filesystem::path events = std::filesystem::path(folder) / RECORDING_EVENTS_LOG;
  std::error_code error;
  return std::filesystem::exists(events, error) ? events.string() : std::string();
}

Result<ReportJob> jobForFolder(const std::string& folder, AnalysisSetup setup) {
  try {
    std::error_code error;
    if (!std::filesystem::is_directory(folder, error)) {
      return Error{error ? "cannot read: " + error.message() : std::string("not a folder"), Location{folder, 0, 0, {}}};
    }
    ReportJob job;
    job.logs = recordingLogs(folder);
    if (job.logs.empty()) return Error{"no *.log file in this folder", Location{folder, 0, 0, {}}};
    job.eventsLog = recordingEventsLog(folder);
    std::filesystem::path name = std::filesystem::path(folder);
    if (!name.has_filename()) name = name.parent_path();  // "drive1/" -> "drive1"
    job.title = name.filename().string();
    job.setup = std::move(setup);
    return job;
  } catch (const std::exception& exception) {
    return Error{std::string("cannot read: ") + exception.what(), Location{folder, 0, 0, {}}};
  }
}

std::vector<Error> skippedLines(const std::vector<LogCounts>& counts) {
  std::vector<Error> errors;
  for (const LogCounts& count : counts) {
    std::string text;
    const auto add = [&text](std::uint64_t n, const char* what) {
      if (n == 0) return;
      text += (text.empty() ? "" : ", ") + std::to_string(n) + what;
    };
    add(count.malformedLines, " malformed lines skipped");
    add(count.untimed, " lines without a time skipped");
    add(count.backwards, " frames earlier than the frame before them (the periods across them not measured)");
    if (text.empty()) continue;
    // malformed lines are errors of the input; the rest is what the analysis left out
    errors.push_back(Error{std::move(text), Location{count.path, 0, 0, {}},
                           count.malformedLines > 0 ? openvcu::Severity::Error : openvcu::Severity::Warning});
  }
  return errors;
}

}  // namespace openvcu::trace
