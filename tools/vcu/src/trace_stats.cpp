// `vcu trace stats`: bus load, per-node traffic and per-message cycle times of one or more
// CAN logs (shared/trace TraceStats), streamed once, as aligned tables or JSON.
//
//   vcu trace stats --dbc truck.dbc truck.log --format json > stats.json
#include <CLI/CLI.hpp>
#include <memory>

#include "diagnostics.hpp"
#include "openvcu/trace/stats.hpp"
#include "trace_commands.hpp"

namespace openvcu::cli {
namespace {

constexpr const char* STATS_DESCRIPTION = "Bus load, traffic per node and cycle times per message of CAN logs";

constexpr const char* STATS_FOOTER =
    "Reads the logs once, in time order (several logs = one timeline; a folder = its *.log\n"
    "files as vcu record writes them), in constant memory whatever their size.\n"
    "--config gives the DBC files, bus bit rates and the schedule's cycles of what the VCU\n"
    "sends; --dbc gives GenMsgCycleTime cycles; without either every frame is unknown\n"
    "(bus load and nodes still work). Buses not configured count at 500 kbit/s (CAN FD data\n"
    "phase 2 Mbit/s).\n"
    "\n"
    "Buses: FRAMES (error frames included, counted as 17 bits), DURATION first to last frame,\n"
    "  LOAD MEAN = wire time of all frames / DURATION; LOAD PEAK = the highest load of any\n"
    "  1 s window (windows step by 10 ms from the bus' first frame; the mean when the bus\n"
    "  lasted less than 1 s). Wire time = exact bits incl. stuff bits and intermission,\n"
    "  as can-rx counts them, at the bus' bit rates.\n"
    "Nodes: per J1939 source address (the low byte of 29-bit ids); all 11-bit frames are\n"
    "  one node '11-bit'. NAME: the DBC node transmitting a message with that address.\n"
    "  BIT/S = the node's wire bits / bus DURATION; SHARE = its bits / all bits of the bus.\n"
    "Messages: per bus and identifier (the first 4096; frames of further ones are counted\n"
    "  as skipped). EXPECTED: the schedule's cycle (--config) or GenMsgCycleTime. MEAN, P50,\n"
    "  P99, MAX: measured periods between consecutive frames in ms. MEAN and MAX are exact;\n"
    "  P50/P99 come from a histogram: rounded to 0.1 ms up to 200 ms (within 0.05 ms), 128\n"
    "  bins per octave from 200 ms to 12.8 s (within 0.4 %), above that the max. P50/P99 are\n"
    "  nearest-rank percentiles, kept within the exact min and max. DEVIATION = MEAN -\n"
    "  EXPECTED. GAPS: periods over 1.5 x EXPECTED; MISSING: cycles lost in them, the sum\n"
    "  of round(period / EXPECTED) - 1. A frame older than the previous one of its stream\n"
    "  (time went back) starts over: that interval is not measured.\n"
    "--format json: {\"duration_s\",\"frames\",\"skipped_frames\",\"backward_steps\",\n"
    "  \"period_resolution\",\"buses\":[{bus,bitrate,frames,error_frames,duration_s,\n"
    "  load_mean_pct,load_max_pct}],\"nodes\":[{bus,sa,standard,name,frames,bits_per_s,\n"
    "  share_pct}],\"messages\":[{bus,id,extended,name,sa,count,periods,expected_ms,\n"
    "  cycle_source,mean_ms,p50_ms,p99_ms,max_ms,min_ms,deviation_ms,gaps,missing}]}; id as\n"
    "  \"0x18FEF121\"; null where a figure does not exist (no expectation, < 2 frames, sa of\n"
    "  11-bit frames).\n"
    "Bad input: malformed lines are reported as 'file:line:col: error: reason' (the first\n"
    "20) and skipped; a DBC or configuration that cannot be read is reported and the\n"
    "statistics are made without it; both make the exit status 1.\n"
    "\n"
    "Examples:\n"
    "  vcu trace stats --config config/hhea/vehicle.json drive1/\n"
    "  vcu trace stats --dbc j1939.dbc truck.log truck2.log --format json\n"
    "Exit: 0 done, 1 a log, DBC or configuration could not be read or had malformed lines,\n"
    "2 usage error.\n";

struct StatsOptions {
  TraceInputOptions input;
  std::string format{"text"};
};

ExitCode runStats(const StatsOptions& options, Streams streams) {
  std::optional<TraceInput> maybeInput = openTraceInput(options.input, streams.err);
  if (!maybeInput) return ExitCode::Failure;
  TraceInput& input = *maybeInput;
  trace::LogTimeline& timeline = *input.timeline;

  trace::TraceStats stats(*input.setup, timeline.buses());
  trace::TraceFrame frame;
  while (timeline.next(frame)) stats.add(frame);
  const trace::StatsReport report = stats.finish(timeline.buses());

  std::string text;
  if (options.format == "json") {
    trace::appendStatsJson(text, report);
  } else {
    text += "Setup: " + input.setup->source + "\n";
    trace::appendStatsText(text, report);
  }
  streams.out.write(text);
  reportSkipped(input, streams.err);

  ExitCode exitCode = input.failed ? ExitCode::Failure : ExitCode::Ok;
  if (!streams.out.flush()) {
    reportError(streams.err, "cannot write the output: " + streams.out.errorMessage());
    exitCode = ExitCode::Failure;
  }
  return exitCode;
}

}  // namespace

void addTraceStats(CLI::App& trace, CommandContext& context) {
  auto options = std::make_shared<StatsOptions>();
  CLI::App* command = trace.add_subcommand("stats", STATS_DESCRIPTION);
  command->footer(STATS_FOOTER);
  addTraceInputOptions(*command, options->input);
  command->add_option("-f,--format", options->format, "output format (default text)")
      ->check(CLI::IsMember({"text", "json"}))
      ->option_text("text|json");
  command->callback([options, &context] { context.exitCode = runStats(*options, context.streams); });
}

}  // namespace openvcu::cli
