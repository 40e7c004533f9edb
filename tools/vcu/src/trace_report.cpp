// vcu trace report: one self-contained HTML file of a timeline (trace::renderHtmlReport):
// statistics and checks in one pass over the logs, the chosen signals in a second pass
// (their time range is known by then, so each keeps a fixed number of min/max buckets), and
// for a folder written by `vcu record` the FSM transitions and faults of its events.lcmlog.
//
//   vcu trace report --config config/hhea/vehicle.json drive1 -o drive1.html
//       --signals HVESSD1_PGN61584.HS_ULvl,ST_MOT_1.st_mot_n
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include "diagnostics.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/ipc/event_log.hpp"
#include "openvcu/trace/check.hpp"
#include "openvcu/trace/frame_decoder.hpp"
#include "openvcu/trace/html_report.hpp"
#include "openvcu/trace/log.hpp"
#include "openvcu/trace/stats.hpp"
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

/// Points per signal: min and max of this many buckets over the timeline's duration.
constexpr std::size_t SIGNAL_BUCKETS = 2000;

struct ReportArguments {
  TraceInputOptions input;
  std::string output;
  std::vector<std::string> signals;
  std::string title;
};

/// Min and max of each of SIGNAL_BUCKETS equal slices of [0, durationS]: the points a chart
/// needs whatever the number of samples.
class BucketedSeries {
 public:
  explicit BucketedSeries(double durationS)
      : m_durationS(durationS > 0 ? durationS : 1.0), m_buckets(SIGNAL_BUCKETS) {}

  void add(double s, double value) {
    if (!(value == value)) return;  // NaN: not drawn
    const auto index = std::min(SIGNAL_BUCKETS - 1, static_cast<std::size_t>(std::max(0.0, s) / m_durationS *
                                                                                 static_cast<double>(SIGNAL_BUCKETS)));
    Bucket& bucket = m_buckets[index];
    if (bucket.count == 0 || value < bucket.min.second) bucket.min = {s, value};
    if (bucket.count == 0 || value > bucket.max.second) bucket.max = {s, value};
    ++bucket.count;
  }

  [[nodiscard]] std::vector<std::pair<double, double>> points() const {
    std::vector<std::pair<double, double>> out;
    for (const Bucket& bucket : m_buckets) {
      if (bucket.count == 0) continue;
      if (bucket.count == 1 || bucket.min == bucket.max) {
        out.push_back(bucket.min);
      } else if (bucket.min.first <= bucket.max.first) {
        out.push_back(bucket.min);
        out.push_back(bucket.max);
      } else {
        out.push_back(bucket.max);
        out.push_back(bucket.min);
      }
    }
    return out;
  }

 private:
  struct Bucket {
    std::pair<double, double> min{}, max{};
    std::uint64_t count{};
  };
  double m_durationS;
  std::vector<Bucket> m_buckets;
};

/// MESSAGE.SIGNAL, or the signal table's key of a bus signal (config::signalKey:
/// TRANSMITTER.MESSAGE.SIGNAL, as `vcu signal list` shows it).
std::optional<trace::SignalRef> findSignalByName(const dbc::Database& database, const std::string& name) {
  if (std::optional<trace::SignalRef> ref = trace::findSignal(database, name)) return ref;
  const std::size_t dot = name.find('.');
  if (dot == std::string::npos) return std::nullopt;
  std::optional<trace::SignalRef> ref = trace::findSignal(database, std::string_view(name).substr(dot + 1));
  if (!ref) return std::nullopt;
  const dbc::Message& message = database.messages[static_cast<std::size_t>(ref->message)];
  if (config::signalKey(message, message.signals[ref->signal]) != name) return std::nullopt;
  return ref;
}

std::string seriesName(const dbc::Database& database, trace::SignalRef ref) {
  const dbc::Message& message = database.messages[static_cast<std::size_t>(ref.message)];
  return message.name + "." + message.signals[ref.signal].name;
}

/// The second pass: every chosen signal as min/max buckets over the timeline.
std::vector<trace::SignalSeries> extractSignals(const TraceInput& input, const std::vector<trace::SignalRef>& refs,
                                                std::int64_t startNs, double durationS, Sink& err) {
  std::vector<trace::SignalSeries> series;
  if (refs.empty()) return series;
  auto timelineResult = trace::LogTimeline::open(input.logPaths, *input.setup);  // errors were reported in pass 1
  if (!timelineResult) {
    report(err, timelineResult.error());
    return series;
  }
  const dbc::Database& database = input.setup->database;
  trace::FrameDecoder decoder(database, input.setup->match);
  std::vector<BucketedSeries> buckets(refs.size(), BucketedSeries(durationS));
  trace::TraceFrame frame;
  while (timelineResult->next(frame)) {
    if (frame.message < 0) continue;
    bool decoded = false;
    std::span<const trace::SignalValue> values;
    for (std::size_t i = 0; i < refs.size(); ++i) {
      if (refs[i].message != frame.message) continue;
      if (!decoded) {
        values = decoder.decode(frame.frame, frame.message);
        decoded = true;
      }
      for (const trace::SignalValue& value : values) {
        if (value.signalIndex == refs[i].signal) {
          buckets[i].add(static_cast<double>(frame.timeNs - startNs) / 1e9, value.value.physical);
        }
      }
    }
  }
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const dbc::Message& message = database.messages[static_cast<std::size_t>(refs[i].message)];
    series.push_back(trace::SignalSeries{seriesName(database, refs[i]), message.signals[refs[i].signal].unit,
                                         buckets[i].points()});
  }
  return series;
}

trace::Severity faultSeverity(ipc::FaultSeverity severity) {
  switch (severity) {
    case ipc::FaultSeverity::Info: return trace::Severity::Info;
    case ipc::FaultSeverity::Warning: return trace::Severity::Warning;
    default: return trace::Severity::Fault;
  }
}

/// The FSM and fault lanes of a `vcu record` folder's events.lcmlog.
std::vector<trace::EventLane> recordedEvents(const std::string& folder, std::int64_t startNs, Sink& err, bool& failed) {
  std::vector<trace::EventLane> lanes;
  const std::string path = (std::filesystem::path(folder) / "events.lcmlog").string();
  std::error_code error;
  if (!std::filesystem::exists(path, error)) return lanes;
  auto eventsResult = ipc::readEventLog(path);
  if (!eventsResult) {
    report(err, eventsResult.error());
    failed = true;
    return lanes;
  }
  const auto seconds = [startNs](std::int64_t ns) { return static_cast<double>(ns - startNs) / 1e9; };
  trace::EventLane states{"FSM state", {}};
  for (const ipc::FsmTransition& transition : eventsResult->transitions) {
    states.events.push_back(trace::ReportEvent{seconds(transition.timestampNs), transition.toState, trace::Severity::Info});
  }
  trace::EventLane faults{"Faults", {}};
  for (const ipc::FaultEvent& fault : eventsResult->faults) {
    faults.events.push_back(trace::ReportEvent{seconds(fault.timestampNs),
                                               (fault.active ? "raised " : "cleared ") + fault.name,
                                               fault.active ? faultSeverity(fault.severity) : trace::Severity::Info});
  }
  lanes.push_back(std::move(states));
  lanes.push_back(std::move(faults));
  if (eventsResult->undecodable > 0 || eventsResult->dropped > 0) {
    report(err, Error{std::to_string(eventsResult->undecodable) + " events did not decode, " +
                          std::to_string(eventsResult->dropped) + " beyond the limit were left out",
                      Location{path, 0, 0, {}}});
  }
  return lanes;
}

ExitCode runReport(const ReportArguments& arguments, Streams streams) {
  std::optional<TraceInput> maybeInput = openTraceInput(arguments.input, streams.err);
  if (!maybeInput) return ExitCode::Failure;
  TraceInput& input = *maybeInput;
  const dbc::Database& database = input.setup->database;

  std::vector<trace::SignalRef> refs;
  for (const std::string& name : arguments.signals) {
    std::optional<trace::SignalRef> ref = findSignalByName(database, name);
    if (!ref) {
      reportError(streams.err, "--signals " + name +
                                   ": no such signal in the DBC (MESSAGE.SIGNAL as `vcu dbc info` lists them, or the "
                                   "table key NODE.MESSAGE.SIGNAL as `vcu signal list` does)");
      input.failed = true;
      continue;
    }
    refs.push_back(*ref);
  }

  trace::TraceStats stats(*input.setup, input.timeline->buses());
  trace::TraceChecker checker(*input.setup);
  trace::ReportFindings findings;
  trace::TraceFrame frame;
  std::int64_t lastNs = 0;
  while (input.timeline->next(frame)) {
    stats.add(frame);
    checker.add(frame, findings);
    lastNs = frame.timeNs;
  }
  checker.finish(lastNs, findings);
  reportSkipped(input, streams.err);

  trace::ReportInput document;
  document.title = arguments.title.empty() ? std::filesystem::path(arguments.input.logs.front()).filename().string()
                                         : arguments.title;
  document.source = input.setup->source + "; logs:";
  for (const std::string& path : input.logPaths) document.source += " " + path;
  document.stats = stats.finish(input.timeline->buses());
  document.buses = input.timeline->buses();
  document.dtcs = checker.transport().dtcIntervals();
  document.dtcIntervalsSkipped = checker.transport().counts().dtcIntervalsSkipped;
  document.findings = findings.list();
  const std::int64_t startNs = input.timeline->startNs();
  document.signals = extractSignals(input, refs, startNs, document.stats.durationS, streams.err);
  if (!input.recordFolder.empty()) {
    document.eventLanes = recordedEvents(input.recordFolder, startNs, streams.err, input.failed);
  }

  const std::string html = trace::renderHtmlReport(document);
  std::ofstream file(arguments.output, std::ios::binary | std::ios::trunc);
  file.write(html.data(), static_cast<std::streamsize>(html.size()));
  file.close();
  if (!file) {
    report(streams.err, Error{"cannot write the report", Location{arguments.output, 0, 0, {}}});
    return ExitCode::Failure;
  }
  streams.out.write(arguments.output + ": " + std::to_string(html.size() / 1024) + " KiB, " +
                    std::to_string(document.stats.frames) + " frames over " +
                    std::to_string(static_cast<long long>(document.stats.durationS)) + " s, " +
                    std::to_string(document.findings.total) + " findings\n");
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
