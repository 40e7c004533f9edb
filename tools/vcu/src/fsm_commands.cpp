// `vcu fsm ...`: check, graph, replay, reload. Each subcommand's description and footer
// are its manual (`vcu fsm check --help`).
#include "fsm_commands.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>

#include "check_commands.hpp"
#include "diagnostics.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/fsm/engine.hpp"
#include "openvcu/fsm/machine.hpp"

namespace openvcu::cli {
namespace {

using config::Json;

constexpr const char* CONFIG_NOTE =
    "The configuration: --config FILE or $OPENVCU_CONFIG (its DBC and internal signals\n"
    "are what the machine's keys are checked against).\n";

constexpr const char* CHECK_DESCRIPTION = "Check an FSM file against the configuration's signals";
constexpr const char* CHECK_FOOTER =
    "Reports, one per line as 'fsm.json: /states/2/transitions/0/nextState: error: ...':\n"
    "JSON syntax errors (line:column); unknown keys of the file and unknown signal keys\n"
    "(with a 'did you mean'); undefined initial or next states; an 'all' that needs one\n"
    "signal to take exclusive values; actions on signals this VCU does not transmit or on\n"
    "status signals; values outside the DBC range or not in its value table; bad durations.\n"
    "Warnings: empty conditions (always true) and empty actions, repeated conditions,\n"
    "unreachable states, transitions that can never be taken, self-transitions that do\n"
    "nothing. Diagnostics go to stderr, then a summary line to stdout. A schedule file that\n"
    "does not parse is reported as its own error (the machine's send groups come from it).\n"
    "\n"
    "Example:\n"
    "  vcu fsm check config/hhea/fsm.json --config config/hhea/vehicle.json\n"
    "Exit: 0 no errors (warnings allowed), 1 errors, 2 usage error.\n";

constexpr const char* GRAPH_DESCRIPTION = "Print the states and transitions as Graphviz DOT (or Mermaid)";
constexpr const char* GRAPH_FOOTER =
    "Needs no configuration: any file that parses as JSON is drawn, keys as written.\n"
    "Edges are labelled with the condition (and 'after', actions count); the initial\n"
    "state has an arrow from a point.\n"
    "\n"
    "Examples:\n"
    "  vcu fsm graph config/hhea/fsm.json | dot -Tsvg > fsm.svg\n"
    "  vcu fsm graph config/hhea/fsm.json --mermaid\n"
    "Exit: 0 drawn, 1 the file does not parse, 2 usage error.\n";

constexpr const char* REPLAY_DESCRIPTION = "Run the machine over a recorded CAN log and print its transitions";
constexpr const char* REPLAY_FOOTER =
    "The log (candump -L, candump console or Vector ASC) is decoded through the\n"
    "configuration's DBC into an in-memory table; the machine starts in its initial state\n"
    "at the first frame and is stepped after every frame and at its own deadlines ('for',\n"
    "'after', 'ageGt'), on the log's clock. One line per transition:\n"
    "  12.345000 s  Start -> Connect for Driving: VIC...HS_HiUBusCnctnSts eq 1 [... = 1]\n"
    "Faults and events the actions publish are printed as well. Signal quality 'stale' is\n"
    "not simulated (can-rx sets it live): use 'ageGt' for timeouts you want to replay.\n"
    "Operator switches are not in a CAN log: internal signals keep their initial values.\n"
    "The replay ends with the last frame: deadlines after it do not fire.\n"
    "\n"
    "Example:\n"
    "  vcu fsm replay config/hhea/fsm.json --config config/hhea/vehicle.json start.log\n"
    "Exit: 0 replayed, 1 the machine has errors or the log malformed lines, 2 usage error.\n";

constexpr const char* RELOAD_DESCRIPTION = "Make vcu-fsm load its FSM file again (or FILE), checked first";
constexpr const char* RELOAD_FOOTER =
    "vcu-fsm checks the file completely; with any error it refuses and keeps running its\n"
    "machine. Otherwise it switches between two evaluations, staying in the current state\n"
    "(which must exist in the new file) with its entry time; 'for' timers restart.\n"
    "FILE is read by vcu-fsm (a path on its machine); without FILE its configured file.\n"
    "A restart of vcu-fsm loads the configured file again.\n"
    "\n"
    "Example:\n"
    "  vcu fsm reload --config config/hhea/vehicle.json\n"
    "Exit: 0 accepted, 1 refused or no answer, 2 usage error.\n";

constexpr std::uint64_t MAX_REPORTED_LOG_ERRORS = 10;

using text::number;

std::string plural(std::size_t count, const std::string& word) {
  return std::to_string(count) + " " + word + (count == 1 ? "" : "s");
}

// ---- graph ----------------------------------------------------------------------------

std::string jsonValue(const Json& value) {
  if (value.is_string()) return value.get<std::string>();
  return value.dump();
}

/// A condition object as text, keys as written (graph works without a configuration).
std::string conditionText(const Json& condition) {
  if (!condition.is_object()) return condition.dump();
  std::string text;
  if (condition.empty()) return "always";
  for (const char* group : {"all", "any"}) {
    if (const auto it = condition.find(group); it != condition.end() && it->is_array()) {
      text = std::string(group) + "(";
      for (std::size_t c = 0; c < it->size(); ++c) text += (c > 0 ? ", " : "") + conditionText((*it)[c]);
      text += ")";
    }
  }
  if (const auto it = condition.find("not"); it != condition.end()) text = "not(" + conditionText(*it) + ")";
  if (text.empty() && condition.contains("key")) {
    text = jsonValue(condition["key"]);
    for (const auto& item : condition.items()) {
      if (item.key() == "key" || item.key() == "for" || item.key() == "comment") continue;
      text += " " + item.key() + " " + jsonValue(item.value());
    }
  } else if (text.empty()) {
    for (const auto& item : condition.items()) {
      if (item.key() == "for" || item.key() == "comment") continue;
      if (!text.empty()) text += ", ";
      text += item.key() + " eq " + jsonValue(item.value());
    }
    if (text.empty()) text = "always";
  }
  if (const auto it = condition.find("for"); it != condition.end()) text += " for " + jsonValue(*it);
  return text;
}

std::string escapeDot(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

std::string escapeMermaid(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '"') {
      out += "#quot;";
    } else if (c == '|') {
      out += "#124;";
    } else {
      out += c;
    }
  }
  return out;
}

struct Edge {
  std::string from;
  std::string to;
  std::string label;
};

std::string renderGraph(const Json& root, bool mermaid) {
  std::vector<std::string> states;
  std::vector<Edge> edges;
  if (const auto list = root.find("states"); list != root.end() && list->is_array()) {
    for (const Json& state : *list) {
      if (!state.is_object() || !state.contains("name") || !state["name"].is_string()) continue;
      const std::string name = state["name"].get<std::string>();
      states.push_back(name);
      const auto transitions = state.find("transitions");
      if (transitions == state.end() || !transitions->is_array()) continue;
      for (const Json& transition : *transitions) {
        if (!transition.is_object()) continue;
        Edge edge{name, transition.contains("nextState") ? jsonValue(transition["nextState"]) : "?", ""};
        if (transition.contains("condition")) edge.label = conditionText(transition["condition"]);
        if (transition.contains("after")) {
          edge.label += (edge.label.empty() ? "" : " and ") + std::string("after ") + jsonValue(transition["after"]);
        }
        if (const auto actions = transition.find("actions"); actions != transition.end() && actions->is_array()) {
          std::size_t count = 0;
          for (const Json& action : *actions) count += (action.is_object() && !action.empty()) ? 1 : 0;
          if (count > 0) edge.label += " / " + plural(count, "action");
        }
        edges.push_back(std::move(edge));
      }
    }
  }
  const std::string initial = root.contains("initialState") ? jsonValue(root["initialState"]) : "";
  std::string out;
  if (mermaid) {
    out = "stateDiagram-v2\n";
    const auto id = [&](const std::string& name) {
      for (std::size_t s = 0; s < states.size(); ++s) {
        if (states[s] == name) return "s" + std::to_string(s);
      }
      std::string safe = "undefined_";
      for (const char c : name) safe += std::isalnum(static_cast<unsigned char>(c)) != 0 ? c : '_';
      return safe;
    };
    for (const std::string& state : states) out += "  " + id(state) + " : " + escapeMermaid(state) + "\n";
    if (!initial.empty()) out += "  [*] --> " + id(initial) + "\n";
    for (const Edge& edge : edges) {
      out += "  " + id(edge.from) + " --> " + id(edge.to) + " : " + escapeMermaid(edge.label) + "\n";
    }
    return out;
  }
  out = "digraph fsm {\n  rankdir=LR;\n  node [shape=box, style=rounded];\n";
  if (!initial.empty()) out += "  __start [shape=point];\n  __start -> \"" + escapeDot(initial) + "\";\n";
  for (const std::string& state : states) out += "  \"" + escapeDot(state) + "\";\n";
  for (const Edge& edge : edges) {
    out += "  \"" + escapeDot(edge.from) + "\" -> \"" + escapeDot(edge.to) + "\" [label=\"" + escapeDot(edge.label) +
           "\"];\n";
  }
  return out + "}\n";
}

// ---- replay ---------------------------------------------------------------------------

/// Decodes frames into the in-memory table: per DBC message, the catalog index of each signal.
class FrameDecoder {
 public:
  FrameDecoder(const config::VehicleConfig& vehicle, const signals::Catalog& catalog)
      : m_matcher(vehicle.database, dbc::MatchMode::J1939), m_codecs(vehicle.database) {
    for (const dbc::Message& message : vehicle.database.messages) {
      std::vector<std::optional<signals::SignalIndex>> indices;
      for (const dbc::Signal& signal : message.signals) indices.push_back(catalog.indexOf(config::signalKey(message, signal)));
      m_indices.push_back(std::move(indices));
    }
  }

  void decode(const can::Frame& frame, std::int64_t nowNs, fsm::MemoryAccess& access) const {
    const std::int32_t message = m_matcher.match(frame.id, frame.extended());
    if (message == dbc::MessageMatcher::NO_MATCH || (frame.flags & can::FLAG_RTR) != 0) return;
    const auto& indices = m_indices[static_cast<std::size_t>(message)];
    m_codecs[static_cast<std::size_t>(message)].decode(
        frame.payload(), [&](std::uint32_t signal, const dbc::DecodedValue& value) {
          if (signal < indices.size() && indices[signal]) access.setBus(*indices[signal], value.physical, nowNs);
        });
  }

 private:
  dbc::MessageMatcher m_matcher;
  dbc::DatabaseCodec m_codecs;
  std::vector<std::vector<std::optional<signals::SignalIndex>>> m_indices;
};

void printOutputs(fsm::Outputs& outputs, double seconds, Sink& out) {
  char stamp[32];
  std::snprintf(stamp, sizeof stamp, "%.6f s  ", seconds);
  for (const ipc::FsmTransition& transition : outputs.transitions) {
    out.write(stamp + (transition.fromState.empty() ? std::string("(start)") : transition.fromState) + " -> " +
              transition.toState + ": " + transition.cause + "\n");
  }
  for (const ipc::FaultEvent& fault : outputs.faults) {
    out.write(stamp + std::string(fault.active ? "fault raised " : "fault cleared ") + fault.name +
              (fault.text.empty() ? "" : ": " + fault.text) + "\n");
  }
  for (const ipc::LogRecord& event : outputs.events) out.write(stamp + std::string("event: ") + event.text + "\n");
  outputs.transitions.clear();
  outputs.faults.clear();
  outputs.events.clear();
}

std::optional<fsm::Machine> loadCheckedMachine(const FsmFileOptions& options, const Stack& stack, Sink& err) {
  std::vector<Error> diagnostics;
  auto machineResult = fsm::loadMachine(options.file, stack.config, stack.catalog, &diagnostics);
  for (const Error& diagnostic : diagnostics) {
    if (diagnostic.severity == Severity::Error) report(err, diagnostic);
  }
  if (!machineResult) return std::nullopt;
  return std::move(*machineResult);
}

// ---- registration ---------------------------------------------------------------------

void addCheck(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<FsmFileOptions>();
  CLI::App* command = group.add_subcommand("check", CHECK_DESCRIPTION);
  command->footer(std::string(CHECK_FOOTER) + CONFIG_NOTE);
  command->add_option("FILE", options->file, "the FSM JSON file")->required()->type_name("");
  command->add_flag("-q,--quiet", options->quiet, "errors only, no warnings");
  addStackOptions(*command, options->stack);
  command->callback([options, &context] { context.exitCode = runFsmCheck(*options, context.streams); });
}

void addGraph(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<FsmFileOptions>();
  CLI::App* command = group.add_subcommand("graph", GRAPH_DESCRIPTION);
  command->footer(GRAPH_FOOTER);
  command->add_option("FILE", options->file, "the FSM JSON file")->required()->type_name("");
  command->add_flag("--mermaid", options->mermaid, "Mermaid stateDiagram-v2 instead of DOT");
  command->callback([options, &context] { context.exitCode = runFsmGraph(*options, context.streams); });
}

void addReplay(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<FsmFileOptions>();
  CLI::App* command = group.add_subcommand("replay", REPLAY_DESCRIPTION);
  command->footer(std::string(REPLAY_FOOTER) + CONFIG_NOTE);
  command->add_option("FILE", options->file, "the FSM JSON file")->required()->type_name("");
  command->add_option("LOG", options->log, "CAN log (candump -L, candump console, Vector ASC)")
      ->required()
      ->type_name("");
  addStackOptions(*command, options->stack);
  command->callback([options, &context] { context.exitCode = runFsmReplay(*options, context.streams); });
}

void addReload(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<FsmFileOptions>();
  CLI::App* command = group.add_subcommand("reload", RELOAD_DESCRIPTION);
  command->footer(RELOAD_FOOTER);
  command->add_option("FILE", options->file, "FSM file for vcu-fsm to load (default: its configured one)")
      ->type_name("");
  command->add_option("--timeout", options->timeoutSeconds, "seconds to wait for the answer (default 2)")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  addStackOptions(*command, options->stack);
  command->callback([options, &context] { context.exitCode = runFsmReload(*options, context.streams); });
}

}  // namespace

ExitCode runFsmCheck(const FsmFileOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const FileCounts counts = checkFsmFile(options.file, *maybeStack, options.quiet, streams.err);
  const std::size_t errors = counts.errors;
  const std::size_t warnings = counts.warnings;
  std::string summary = options.file + ": " + plural(errors, "error") + ", " + plural(warnings, "warning");
  if (errors == 0) {
    if (auto machine = fsm::loadMachine(options.file, maybeStack->config, maybeStack->catalog)) {
      std::size_t transitions = 0;
      for (const fsm::State& state : machine->states) transitions += state.transitions.size();
      summary += " (" + plural(machine->states.size(), "state") + ", " + plural(transitions, "transition") + ")";
    }
  }
  streams.out.write(summary + "\n");
  return errors == 0 ? ExitCode::Ok : ExitCode::Failure;
}

ExitCode runFsmGraph(const FsmFileOptions& options, Streams streams) {
  auto root = config::readJsonFile(options.file);
  if (!root) {
    report(streams.err, root.error());
    return ExitCode::Failure;
  }
  if (!root->is_object()) {
    report(streams.err, Error{"not an FSM file: the top level must be an object", Location{options.file, 0, 0, {}}});
    return ExitCode::Failure;
  }
  streams.out.write(renderGraph(*root, options.mermaid));
  return ExitCode::Ok;
}

ExitCode runFsmReplay(const FsmFileOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const Stack& stack = *maybeStack;
  auto machine = loadCheckedMachine(options, stack, streams.err);
  if (!machine) return ExitCode::Failure;
  auto slots = fsm::StatusSlots::find(stack.catalog);
  if (!slots) {
    reportError(streams.err, slots.error().message);
    return ExitCode::Failure;
  }
  auto readerResult = can::LogReader::open(options.log);
  if (!readerResult) {
    report(streams.err, readerResult.error());
    return ExitCode::Failure;
  }
  can::LogReader& reader = *readerResult;
  std::uint64_t reported = 0;
  reader.setErrorHandler([&](const Error& error) {
    if (reported++ < MAX_REPORTED_LOG_ERRORS) report(streams.err, error);
  });

  fsm::MemoryAccess access(stack.catalog.size());
  const FrameDecoder decoder(stack.config, stack.catalog);
  fsm::Engine engine(std::move(*machine), stack.catalog, access, std::move(*slots));
  // The log's clock, shifted so that it starts at 1 s (0 means "never" to the table).
  constexpr std::int64_t ORIGIN = 1'000'000'000;
  std::optional<std::int64_t> first;
  std::int64_t now = ORIGIN;
  const auto seconds = [&](std::int64_t ns) { return static_cast<double>(ns - ORIGIN) / 1e9; };
  std::uint64_t frames = 0;
  while (auto record = reader.next()) {
    const std::int64_t logNs = record->hasTime ? record->frame.timestampNs : (first ? now - ORIGIN + *first : 0);
    if (!first) {
      first = logNs;
      engine.start(ORIGIN, ORIGIN, fsm::StartMode::Fresh);
      printOutputs(engine.outputs(), 0, streams.out);
    }
    const std::int64_t frameNs = std::max(now, logNs - *first + ORIGIN);
    // Deadlines that fall before this frame fire at their own time.
    while (engine.nextDeadlineNs() <= frameNs) {
      now = std::max(now, engine.nextDeadlineNs());
      engine.step(now, now);
      printOutputs(engine.outputs(), seconds(now), streams.out);
    }
    now = frameNs;
    if ((record->frame.flags & can::FLAG_ERROR) == 0) decoder.decode(record->frame, now, access);
    engine.step(now, now);
    printOutputs(engine.outputs(), seconds(now), streams.out);
    ++frames;
  }
  const fsm::EngineCounters& counters = engine.counters();
  streams.err.write(options.log + ": " + plural(frames, "frame") + ", " + number(seconds(now)) + " s, " +
                    plural(counters.transitions, "transition") + ", final state '" +
                    (frames > 0 ? engine.stateName() : std::string("(none: empty log)")) + "'\n");
  if (reader.errorCount() > 0) {
    report(streams.err, Error{plural(reader.errorCount(), "malformed line") + " skipped", Location{options.log, 0, 0, {}}});
    return ExitCode::Failure;
  }
  return ExitCode::Ok;
}

ExitCode runFsmReload(const FsmFileOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::FsmReload;
  // vcu-fsm may run in another folder: send the file as an absolute path.
  request.key = options.file.empty() ? std::string() : std::filesystem::absolute(options.file).lexically_normal().string();
  return sendCommandRequest(maybeStack->config, std::move(request), options.timeoutSeconds, streams);
}

void registerFsmCommands(CLI::App& app, CommandContext& context) {
  CLI::App* group =
      app.add_subcommand("fsm", "the state machine file: check it, draw it, replay a log through it, reload vcu-fsm");
  addCheck(*group, context);
  addGraph(*group, context);
  addReplay(*group, context);
  addReload(*group, context);
}

}  // namespace openvcu::cli
