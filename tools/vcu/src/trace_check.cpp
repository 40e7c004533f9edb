// vcu trace check: the protocol checks of trace::TraceChecker over one timeline, a line per
// finding as it is made, a summary at the end, exit 1 on a protocol fault.
//
//   $ vcu trace check --config config/hhea/vehicle.json drive.log
//   1700000000.040292 fault j1939-76 vehicle: S1_ES_PGN61427 (0x0CEFF321): CrcMismatch: SHM CRC 0x8100EFA3, SDM
//   data CRC 0x3C1D2B0E
// The time is the log's own, as its lines stamp it (grep finds the frame); --time relative
// gives seconds from the first frame instead, --time both the two.
//   ...
//   checked 5 J1939-76 pairs (2500 SDMs, 1 fault), 2 requests (0 unanswered), 0 TP sessions
#include <CLI/CLI.hpp>
#include <array>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>

#include "diagnostics.hpp"
#include "openvcu/trace/check.hpp"
#include "openvcu/trace/frame_writer.hpp"
#include "trace_commands.hpp"

namespace openvcu::cli {
namespace {

constexpr const char* CHECK_DESCRIPTION =
    "Protocol checks of CAN logs: J1939-76 pairs, transport sessions, DTCs, requests";
constexpr const char* CHECK_FOOTER =
    "Reads the logs as one timeline (merged by time) and checks:\n"
    "  j1939-76  every SHM/SDM pair: SHM before its SDM, inverted header fields, CRC-32,\n"
    "            sequence, SRVT and SCT (a fault per bad SDM, with the numbers), the\n"
    "            SHM -> SDM delta against the schedule's deltaUs (a warning beyond\n"
    "            max(200 us, 50 %)) and senders whose SHMs stopped (no SHM for an SCT).\n"
    "            --config: the schedule's and receive.json's pairs; --dbc or nothing: the\n"
    "            pairs the SHMs (PGN 0x0E00) name, SRVT 10 ms, SCT 3 x the SDM's DBC cycle\n"
    "            (3 s when unknown), at most 256 pairs.\n"
    "  tp, dtc   J1939-21 BAM and RTS/CTS sessions (completed, aborted, timed out) and\n"
    "            DM1/DM2 DTCs raised and cleared.\n"
    "  request   every Request (PGN 59904) needs, within 1.25 s, the PGN from the\n"
    "            addressee (anyone for a global request), an ACK/NACK for it or a TP.CM\n"
    "            BAM/RTS announcing it; a NACK is listed as info.\n"
    "Each kind of fault is listed at most 20 times per pair; the rest are counted in a\n"
    "closing line.\n"
    "--format text (default): 'TIME SEVERITY CHECK BUS: TEXT' per finding, then a summary\n"
    "  with the delta statistics of each pair. TIME by --time: log (default) the log's own\n"
    "  time in seconds as its lines stamp it (candump -L: 1700000005.007300, so grep finds\n"
    "  the frame), relative the seconds from the first frame (5.007300), both the two\n"
    "  ('1700000005.007300 +5.007300').\n"
    "--format json: {\"source\",\"findings\":[{\"t\" (the log's time),\"t_rel\" (from the\n"
    "  first "
    "frame),\"severity\",\"check\",\"bus\",\"text\"}],\"pairs\":[{\"bus\",\"id\",\"name\",\"sdms\",\"ok\",\"faults\","
    "\"delta_us\",\n"
    "  \"delta_min_us\",\"delta_mean_us\",\"delta_max_us\",\"delta_warnings\"}],\"summary\":{...}}\n"
    "--quiet hides info findings (they are still counted).\n"
    "\n"
    "Examples:\n"
    "  vcu trace check --config config/hhea/vehicle.json drive1/vehicle.log\n"
    "  vcu trace check --dbc j1939.dbc truck.log --format json --quiet\n"
    "Exit: 0 no protocol fault; 1 a protocol fault (severity 'fault') was found, or the\n"
    "input had errors (unreadable log or DBC, malformed lines); 2 usage error.\n";

/// Which time a text finding line starts with.
enum class TimeColumn : std::uint8_t {
  Log,       ///< the log's own: "1700000005.007300"
  Relative,  ///< seconds from the timeline's first frame: "5.007300"
  Both,      ///< "1700000005.007300 +5.007300"
};

struct CheckArguments {
  TraceInputOptions input;
  std::string format{"text"};
  TimeColumn time{TimeColumn::Log};
  bool quiet{};
};

constexpr std::size_t CHECK_KINDS = 5;  // trace::Check values

std::string busName(const std::vector<std::string>& buses, std::uint16_t bus) {
  return bus < buses.size() ? buses[bus] : std::to_string(bus);
}

std::string micros(double ns) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f", ns / 1000.0);
  return text;
}

/// Prints findings as they come and counts faults per check.
class PrintingSink final : public trace::FindingSink {
 public:
  PrintingSink(Sink& out, const trace::LogTimeline& timeline, bool json, TimeColumn time, bool quiet)
      : m_out(out), m_timeline(timeline), m_json(json), m_time(time), m_quiet(quiet) {}

  void finding(const trace::Finding& finding) override {
    if (finding.severity == trace::Severity::Fault) ++faultsByCheck[static_cast<std::size_t>(finding.check)];
    if (m_quiet && finding.severity == trace::Severity::Info) return;
    const std::string bus = busName(m_timeline.buses(), finding.bus);
    const std::int64_t relativeNs = finding.timeNs - m_timeline.startNs();
    m_line.clear();
    if (m_json) {
      m_line += m_first ? "\n  " : ",\n  ";
      m_line += "{\"t\":";
      trace::appendSeconds(m_line, finding.timeNs);
      m_line += ",\"t_rel\":";
      trace::appendSeconds(m_line, relativeNs);
      m_line += ",\"severity\":\"" + std::string(trace::severityName(finding.severity)) + "\",\"check\":\"" +
                std::string(trace::checkName(finding.check)) + "\",\"bus\":";
      trace::appendJsonString(m_line, bus);
      m_line += ",\"text\":";
      trace::appendJsonString(m_line, finding.text);
      m_line += '}';
    } else {
      if (m_time != TimeColumn::Relative) trace::appendSeconds(m_line, finding.timeNs);
      if (m_time == TimeColumn::Both) m_line += " +";
      if (m_time != TimeColumn::Log) trace::appendSeconds(m_line, relativeNs);
      m_line += ' ' + std::string(trace::severityName(finding.severity)) + ' ' +
                std::string(trace::checkName(finding.check)) + ' ' + bus + ": " + finding.text + '\n';
    }
    m_first = false;
    m_out.write(m_line);
  }

  std::array<std::uint64_t, CHECK_KINDS> faultsByCheck{};

 private:
  Sink& m_out;
  const trace::LogTimeline& m_timeline;
  bool m_json;
  TimeColumn m_time;
  bool m_quiet;
  bool m_first{true};
  std::string m_line;
};

std::string pairName(const trace::AnalysisSetup& setup, const trace::SafetyPairStats& pair) {
  char id[16];
  std::snprintf(id, sizeof id, "0x%08X", pair.dataCanId);
  const bool named = pair.message >= 0 && static_cast<std::size_t>(pair.message) < setup.database.messages.size();
  return named ? setup.database.messages[static_cast<std::size_t>(pair.message)].name + " (" + id + ")"
               : std::string("SDM ") + id;
}

void writeTextSummary(Sink& out, const trace::AnalysisSetup& setup, const std::vector<std::string>& buses,
                      const trace::TraceChecker& checker, const PrintingSink& printed) {
  const trace::CheckCounts& counts = checker.counts();
  const trace::TransportCounts& tp = checker.transport().counts();
  const std::vector<trace::SafetyPairStats> pairs = checker.safetyPairs();
  std::string text = "checked " + std::to_string(pairs.size()) + " J1939-76 pairs (" +
                     std::to_string(counts.safetyPairs) + " SDMs, " + std::to_string(counts.safetyFaults) +
                     " faulty), " + std::to_string(counts.requests) + " requests (" +
                     std::to_string(counts.unanswered) + " unanswered), " + std::to_string(tp.sessions) +
                     " TP sessions (" + std::to_string(tp.completed) + " completed, " + std::to_string(tp.aborted) +
                     " aborted, " + std::to_string(tp.timedOut) + " timed out)\n";
  for (const trace::SafetyPairStats& pair : pairs) {
    text += "  " + pairName(setup, pair) + " on " + busName(buses, pair.bus) + ": " + std::to_string(pair.pairs) +
            " SDMs, " + std::to_string(pair.faults) + " faulty";
    if (pair.deltaCount > 0) {
      text += ", SHM -> SDM delta min/mean/max " + micros(static_cast<double>(pair.deltaMinNs)) + "/" +
              micros(pair.deltaMeanNs()) + "/" + micros(static_cast<double>(pair.deltaMaxNs)) + " us";
    }
    if (pair.deltaNs > 0) text += " (configured " + micros(static_cast<double>(pair.deltaNs)) + " us)";
    if (pair.discovered) text += " (found on the bus)";
    text += '\n';
  }
  text += "findings: " + std::to_string(counts.faults) + " faults, " + std::to_string(counts.warnings) + " warnings, " +
          std::to_string(counts.infos) + " infos";
  if (counts.faults > 0) {
    text += "; faults by check:";
    for (std::size_t i = 0; i < CHECK_KINDS; ++i) {
      if (printed.faultsByCheck[i] == 0) continue;
      text += ' ' + std::string(trace::checkName(static_cast<trace::Check>(i))) + ' ' +
              std::to_string(printed.faultsByCheck[i]);
    }
  }
  text += '\n';
  out.write(text);
}

void writeJsonSummary(Sink& out, const trace::AnalysisSetup& setup, const std::vector<std::string>& buses,
                      const trace::TraceChecker& checker, const PrintingSink& printed) {
  const trace::CheckCounts& counts = checker.counts();
  const trace::TransportCounts& tp = checker.transport().counts();
  std::string text = "\n],\n\"pairs\": [";
  bool first = true;
  for (const trace::SafetyPairStats& pair : checker.safetyPairs()) {
    text += first ? "\n  {\"bus\":" : ",\n  {\"bus\":";
    first = false;
    trace::appendJsonString(text, busName(buses, pair.bus));
    text += ",\"id\":" + std::to_string(pair.dataCanId) + ",\"name\":";
    trace::appendJsonString(text, pairName(setup, pair));
    text += ",\"discovered\":" + std::string(pair.discovered ? "true" : "false") +
            ",\"sdms\":" + std::to_string(pair.pairs) + ",\"ok\":" + std::to_string(pair.ok) +
            ",\"faults\":" + std::to_string(pair.faults) +
            ",\"delta_us\":" + micros(static_cast<double>(pair.deltaNs)) +
            ",\"delta_count\":" + std::to_string(pair.deltaCount);
    if (pair.deltaCount > 0) {
      text += ",\"delta_min_us\":" + micros(static_cast<double>(pair.deltaMinNs)) +
              ",\"delta_mean_us\":" + micros(pair.deltaMeanNs()) +
              ",\"delta_max_us\":" + micros(static_cast<double>(pair.deltaMaxNs));
    }
    text += ",\"delta_warnings\":" + std::to_string(pair.deltaWarnings) + '}';
  }
  text += "\n],\n\"summary\": {\"sdms\":" + std::to_string(counts.safetyPairs) +
          ",\"sdm_faults\":" + std::to_string(counts.safetyFaults) +
          ",\"requests\":" + std::to_string(counts.requests) + ",\"unanswered\":" + std::to_string(counts.unanswered) +
          ",\"tp_sessions\":" + std::to_string(tp.sessions) + ",\"faults\":" + std::to_string(counts.faults) +
          ",\"warnings\":" + std::to_string(counts.warnings) + ",\"infos\":" + std::to_string(counts.infos) +
          ",\"faults_by_check\":{";
  for (std::size_t i = 0; i < CHECK_KINDS; ++i) {
    if (i > 0) text += ',';
    text += '"' + std::string(trace::checkName(static_cast<trace::Check>(i))) +
            "\":" + std::to_string(printed.faultsByCheck[i]);
  }
  text += "}}\n}\n";
  out.write(text);
}

ExitCode runTraceCheck(const CheckArguments& arguments, Streams streams) {
  std::optional<TraceInput> input = openTraceInput(arguments.input, streams.err);
  if (!input) return ExitCode::Failure;
  const bool json = arguments.format == "json";
  trace::LogTimeline& timeline = *input->timeline;
  trace::TraceChecker checker(*input->setup);
  PrintingSink printer(streams.out, timeline, json, arguments.time, arguments.quiet);
  if (json) {
    std::string head = "{\n\"source\": ";
    trace::appendJsonString(head, input->setup->source);
    head += ",\n\"findings\": [";
    streams.out.write(head);
  }
  trace::TraceFrame frame;
  std::int64_t endNs = std::numeric_limits<std::int64_t>::min();
  while (timeline.next(frame)) {
    checker.add(frame, printer);
    endNs = std::max(endNs, frame.timeNs);
  }
  if (endNs == std::numeric_limits<std::int64_t>::min()) endNs = timeline.startNs();
  checker.finish(endNs, printer);
  if (json) {
    writeJsonSummary(streams.out, *input->setup, timeline.buses(), checker, printer);
  } else {
    writeTextSummary(streams.out, *input->setup, timeline.buses(), checker, printer);
  }
  reportSkipped(*input, streams.err);
  if (!streams.out.flush()) {
    reportError(streams.err, "writing the output failed");
    return ExitCode::Failure;
  }
  return checker.counts().faults > 0 || input->failed ? ExitCode::Failure : ExitCode::Ok;
}

}  // namespace

void addTraceCheck(CLI::App& trace, CommandContext& context) {
  auto arguments = std::make_shared<CheckArguments>();
  CLI::App* check = trace.add_subcommand("check", CHECK_DESCRIPTION);
  check->footer(CHECK_FOOTER);
  addTraceInputOptions(*check, arguments->input);
  check->add_option("-f,--format", arguments->format, "output format (default text)")
      ->check(CLI::IsMember({"text", "json"}))
      ->option_text("text|json");
  check->add_option("--time", arguments->time, "time of a text finding: the log's, from the first frame, or both")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, TimeColumn>{
              {"log", TimeColumn::Log}, {"relative", TimeColumn::Relative}, {"both", TimeColumn::Both}},
          CLI::ignore_case))
      ->option_text("log|relative|both");
  check->add_flag("-q,--quiet", arguments->quiet, "hide info findings (still counted)");
  check->callback([arguments, &context] { context.exitCode = runTraceCheck(*arguments, context.streams); });
}

}  // namespace openvcu::cli
