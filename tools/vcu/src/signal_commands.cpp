// `vcu signal ...`: list, get, set, watch. Each subcommand's description and footer are its
// manual (`vcu signal set --help`).
#include "signal_commands.hpp"

#include <signal.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>

#include "command_request.hpp"
#include "diagnostics.hpp"
#include "stop_signal.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/signals/table.hpp"
#include "text_table.hpp"

namespace openvcu::cli {
namespace {

using namespace std::chrono_literals;

/// The longest `vcu signal watch` sleeps between looks at its stop conditions.
constexpr auto WATCH_TICK = 200ms;
/// Retry delay when a plane could not be read (all of its newest writes were unfinished).
constexpr auto WATCH_RETRY = 10ms;

constexpr const char* CONFIG_NOTE =
    "The stack: --config FILE or $OPENVCU_CONFIG (required: there is no default), and\n"
    "--instance to talk to a stack started with another instance name.\n";

constexpr const char* LIST_DESCRIPTION = "List the signals of the configuration (key, unit, range, kind, bus)";
constexpr const char* LIST_FOOTER =
    "PATTERN is a glob over the keys ('*' any text, '?' one character), e.g.\n"
    "'internal.*' or '*SOC*'; without it every signal is listed. Reads only the\n"
    "configuration: works without a running stack.\n"
    "\n"
    "Example:\n"
    "  vcu signal list --config config/hhea/vehicle.json 'VIC.*'\n"
    "Exit: 0 listed, 1 configuration error or nothing matches (a key without wildcards\n"
    "that does not exist gets a 'did you mean'), 2 usage error.\n";

constexpr const char* GET_DESCRIPTION = "Show the bus, command and override planes of signals";
constexpr const char* GET_FOOTER =
    "For each KEY: the bus plane (value seen on the bus, quality, source address), the\n"
    "command plane (commanded value, writer: the service and its id, 'fsm (3)'), the\n"
    "override plane (active or not, writer) and the effective command (override if\n"
    "active, else the command). Each\n"
    "written plane shows its time as UTC and its age, and its update count. Values with\n"
    "a value table show their text: 1 \"Start\". Needs the running stack's table.\n"
    "\n"
    "Example:\n"
    "  vcu signal get internal.operator.Start VIC.HVESSD2_PGN61585.HS_FastUpdSOC\n"
    "Exit: 0 shown, 1 unknown key (with 'did you mean'), no table yet, configuration\n"
    "error, 2 usage error.\n";

constexpr const char* SET_DESCRIPTION = "Command a signal through the service that owns it, and wait for its answer";
constexpr const char* SET_FOOTER =
    "Publishes one command request (LCM, channel OPENVCU_<INSTANCE>_COMMAND) with a\n"
    "unique request id and waits for the acknowledgement carrying that id:\n"
    "  accepted            the owning service checked and applied it\n"
    "  refused: REASON     nothing changed (value outside the signal's range, not\n"
    "                      permitted, ...)\n"
    "VALUE is a number or a text of the signal's value table ('Start').\n"
    "Default: set the commanded value (SetSignal). --override sets an operator\n"
    "override (wins over the command until cleared; always visible in the log);\n"
    "--clear-override removes it (no VALUE).\n"
    "An unknown key is refused here, before anything is sent, with a 'did you mean';\n"
    "range and permission are checked by the service.\n"
    "\n"
    "Examples:\n"
    "  vcu signal set internal.operator.Start Start\n"
    "  vcu signal set --override Vehicle_Control_Unit.VCU2BMS.HS_Enable 0 --note 'bench test'\n"
    "  vcu signal set --clear-override Vehicle_Control_Unit.VCU2BMS.HS_Enable\n"
    "Exit: 0 accepted, 1 refused, unknown key, bad value, or no service answered within\n"
    "the timeout (default 2 s), 2 usage error.\n";

constexpr const char* WATCH_DESCRIPTION = "Print changes of matching signals as they happen";
constexpr const char* WATCH_FOOTER =
    "One line per change of a plane of a matching signal:\n"
    "  2026-11-21T06:00:01.234Z  internal.operator.Start  command  1 \"Start\"  writer 240\n"
    "  2026-11-21T06:00:01.250Z  BMS.Status.SOC  bus  87.5 %  Valid  source 0xF3\n"
    "  2026-11-21T06:00:02.000Z  X.Y.Z  override  cleared  writer 240\n"
    "The time is when the value was written. Wakes on the table's change notification\n"
    "(no polling). Runs until Ctrl-C (SIGINT) or SIGTERM, --count N changes or --for\n"
    "SECONDS; a line 'watching N signals ...' on stderr says it has started.\n"
    "\n"
    "Example:\n"
    "  vcu signal watch 'internal.operator.*' --for 60\n"
    "Exit: 0 stopped as asked, 1 nothing matches, no table, configuration error,\n"
    "2 usage error.\n";

bool hasWildcard(std::string_view pattern) {
  return pattern.find_first_of("*?") != std::string_view::npos;
}

/// The indices matching `pattern`; reports on err and returns empty when nothing does.
std::vector<signals::SignalIndex> matchSignals(const signals::Catalog& catalog, const std::string& pattern, Sink& err) {
  std::vector<signals::SignalIndex> matches;
  for (signals::SignalIndex i = 0; i < catalog.size(); ++i) {
    if (pattern.empty() || text::globMatch(pattern, catalog[i].key)) matches.push_back(i);
  }
  if (matches.empty()) {
    if (!hasWildcard(pattern)) {
      const auto found = catalog.find(pattern);
      reportError(err, found ? "no signal matches '" + pattern + "'" : found.error().message);
    } else {
      reportError(err, "no signal matches '" + pattern + "'");
    }
  }
  return matches;
}

std::string rangeText(const signals::SignalInfo& signal) {
  if (!(signal.minimum < signal.maximum)) return "-";
  return formatNumber(signal.minimum) + ".." + formatNumber(signal.maximum);
}

/// "at 2026-11-21T06:00:01.234Z (0.52 s ago)"
std::string whenText(std::int64_t monotonicNs) {
  const std::int64_t age = clock::monotonicNs() - monotonicNs;
  return "at " + formatUtc(monotonicToRealtimeNs(monotonicNs)) + " (" + formatDuration(age) + " ago)";
}

std::string sourceText(std::uint16_t source) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "0x%02X", static_cast<unsigned>(source));
  return text.data();
}

/// "fsm (3)" for a service's writer id (config::SERVICES), the bare id for another writer.
std::string writerText(signals::WriterId writer) {
  if (const auto service = config::serviceOfWriter(writer)) return std::string(*service) + " (" + std::to_string(writer) + ")";
  return std::to_string(writer);
}

/// The owning service by name ("can-tx"), "-" when no service owns the signal.
std::string ownerText(const signals::SignalInfo& signal) {
  if (const auto service = config::serviceOfWriter(signal.owner)) return std::string(*service);
  return "-";
}

std::optional<signals::SignalTable> openTable(const Stack& stack, Sink& err) {
  auto tableResult = signals::SignalTable::open(stack.catalog, stack.config.instance, signals::OpenMode::AttachOnly);
  if (!tableResult) {
    reportError(err, tableResult.error().message);
    return std::nullopt;
  }
  return std::move(*tableResult);
}

void appendPlanes(std::string& out, const signals::SignalInfo& signal, const signals::SlotSnapshot& slot) {
  const signals::BusValue& bus = slot.bus;
  out += "  bus        ";
  if (bus.updates == 0) {
    out += "never received\n";
  } else {
    out += formatValue(signal, bus.value) + "  " + std::string(signals::qualityName(bus.quality)) + "  " +
           whenText(bus.timestampNs) + "  source " + sourceText(bus.source) + "  update " +
           std::to_string(bus.updates) + "\n";
  }
  const signals::CommandValue& command = slot.command;
  out += "  command    ";
  if (command.updates == 0) {
    out += "never commanded\n";
  } else {
    out += formatValue(signal, command.value) + "  " + whenText(command.timestampNs) + "  writer " +
           writerText(command.writer) + "  update " + std::to_string(command.updates) + "\n";
  }
  const signals::OverrideValue& override = slot.override;
  out += "  override   ";
  if (override.updates == 0) {
    out += "never set\n";
  } else if (override.active) {
    out += formatValue(signal, override.value) + "  ACTIVE  " + whenText(override.timestampNs) + "  writer " +
           writerText(override.writer) + "  update " + std::to_string(override.updates) + "\n";
  } else {
    out += "cleared  " + whenText(override.timestampNs) + "  by writer " + writerText(override.writer) +
           "  update " + std::to_string(override.updates) + "\n";
  }
  out += "  effective  ";
  if (const auto maybeEffective = signals::effectiveCommand(slot)) {
    out +=
        formatValue(signal, maybeEffective->value) + (maybeEffective->overridden ? "  (override)\n" : "  (command)\n");
  } else {
    out += "none\n";
  }
}

// ---- watch -------------------------------------------------------------------------------

/// What a watcher last saw of one signal's planes.
struct SeenPlanes {
  signals::SignalIndex index{};
  std::uint64_t busUpdates{};
  signals::Quality busQuality{signals::Quality::NeverReceived};
  std::uint64_t commandUpdates{};
  std::uint64_t overrideUpdates{};
};

/// Compares every watched signal with what was seen; appends one line per changed plane.
/// Returns false when a plane could not be read (retry soon).
bool scanChanges(const signals::SignalTable& table, const signals::Catalog& catalog, std::vector<SeenPlanes>& seen,
                 std::vector<std::pair<std::int64_t, std::string>>* changes) {
  bool complete = true;
  for (SeenPlanes& planes : seen) {
    const auto maybeSlot = table.read(planes.index);
    if (!maybeSlot) {
      complete = false;
      continue;
    }
    const signals::SignalInfo& signal = catalog[planes.index];
    const signals::SlotSnapshot& slot = *maybeSlot;
    if (changes != nullptr) {
      if (slot.bus.updates != planes.busUpdates || (slot.bus.updates > 0 && slot.bus.quality != planes.busQuality)) {
        changes->emplace_back(slot.bus.timestampNs, signal.key + "  bus  " + formatValue(signal, slot.bus.value) +
                                                        "  " + std::string(signals::qualityName(slot.bus.quality)) +
                                                        "  source " + sourceText(slot.bus.source));
      }
      if (slot.command.updates != planes.commandUpdates) {
        changes->emplace_back(slot.command.timestampNs, signal.key + "  command  " +
                                                            formatValue(signal, slot.command.value) + "  writer " +
                                                            writerText(slot.command.writer));
      }
      if (slot.override.updates != planes.overrideUpdates) {
        changes->emplace_back(slot.override.timestampNs,
                              signal.key + "  override  " +
                                  (slot.override.active ? formatValue(signal, slot.override.value) + "  active"
                                                        : std::string("cleared")) +
                                  "  writer " + writerText(slot.override.writer));
      }
    }
    planes.busUpdates = slot.bus.updates;
    planes.busQuality = slot.bus.quality;
    planes.commandUpdates = slot.command.updates;
    planes.overrideUpdates = slot.override.updates;
  }
  return complete;
}

// ---- registration --------------------------------------------------------------------------

void addList(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<SignalListOptions>();
  CLI::App* list = group.add_subcommand("list", LIST_DESCRIPTION);
  list->footer(std::string(LIST_FOOTER) + CONFIG_NOTE);
  list->add_option("PATTERN", options->pattern, "glob over the keys, e.g. 'internal.*'")->type_name("");
  addStackOptions(*list, options->stack);
  list->callback([options, &context] { context.exitCode = runSignalList(*options, context.streams); });
}

void addGet(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<SignalGetOptions>();
  CLI::App* get = group.add_subcommand("get", GET_DESCRIPTION);
  get->footer(std::string(GET_FOOTER) + CONFIG_NOTE);
  get->add_option("KEY", options->keys, "signal keys")->required()->type_name("");
  addStackOptions(*get, options->stack);
  get->callback([options, &context] { context.exitCode = runSignalGet(*options, context.streams); });
}

void addSet(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<SignalSetOptions>();
  struct Flags {
    bool override{};
    bool clearOverride{};
  };
  auto flags = std::make_shared<Flags>();
  CLI::App* set = group.add_subcommand("set", SET_DESCRIPTION);
  set->footer(std::string(SET_FOOTER) + CONFIG_NOTE);
  set->add_option("KEY", options->key, "signal key")->required()->type_name("");
  set->add_option("VALUE", options->value, "a number or a value text (not with --clear-override)")->type_name("");
  CLI::Option* overrideFlag =
      set->add_flag("--override", flags->override, "set an operator override instead of the command");
  CLI::Option* clearFlag = set->add_flag("--clear-override", flags->clearOverride, "remove the operator override");
  overrideFlag->excludes(clearFlag);
  set->add_option("--timeout", options->timeoutSeconds, "seconds to wait for the answer (default 2)")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  set->add_option("--note", options->note, "free text carried with the request (why)")->option_text("TEXT");
  addStackOptions(*set, options->stack);
  set->callback([options, flags, &context] {
    options->mode = flags->override        ? SetMode::Override
                    : flags->clearOverride ? SetMode::ClearOverride
                                           : SetMode::Command;
    context.exitCode = runSignalSet(*options, context.streams);
  });
}

void addWatch(CLI::App& group, CommandContext& context) {
  auto options = std::make_shared<SignalWatchOptions>();
  CLI::App* watch = group.add_subcommand("watch", WATCH_DESCRIPTION);
  watch->footer(std::string(WATCH_FOOTER) + CONFIG_NOTE);
  watch->add_option("PATTERN", options->pattern, "glob over the keys, e.g. 'internal.*'")->required()->type_name("");
  watch->add_option("-n,--count", options->count, "stop after N changes")->option_text("N");
  watch->add_option("--for", options->forSeconds, "stop after this many seconds")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  addStackOptions(*watch, options->stack);
  watch->callback([options, &context] { context.exitCode = runSignalWatch(*options, context.streams); });
}

}  // namespace

ExitCode runSignalList(const SignalListOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const signals::Catalog& catalog = maybeStack->catalog;
  const auto matches = matchSignals(catalog, options.pattern, streams.err);
  if (matches.empty()) return ExitCode::Failure;
  TextTable table({"KEY", "UNIT", "RANGE", "KIND", "BUS", "DIRECTION", "OWNER"});
  for (const signals::SignalIndex index : matches) {
    const signals::SignalInfo& signal = catalog[index];
    table.addRow({signal.key, signal.unit.empty() ? "-" : signal.unit, rangeText(signal),
                  std::string(signals::signalKindName(signal.kind)), signal.bus.empty() ? "-" : signal.bus,
                  std::string(signals::signalDirectionName(signal.direction)) + (signal.reported ? " status" : ""),
                  ownerText(signal)});
  }
  std::string out;
  table.appendTo(out);
  streams.out.write(out);
  return ExitCode::Ok;
}

ExitCode runSignalGet(const SignalGetOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const signals::Catalog& catalog = maybeStack->catalog;
  std::vector<signals::SignalIndex> indices;
  bool allKnown = true;
  for (const std::string& key : options.keys) {
    const auto found = catalog.find(key);
    if (!found) {
      reportError(streams.err, found.error().message);
      allKnown = false;
      continue;
    }
    indices.push_back(*found);
  }
  if (!allKnown) return ExitCode::Failure;
  const auto maybeTable = openTable(*maybeStack, streams.err);
  if (!maybeTable) return ExitCode::Failure;
  std::string out;
  for (const signals::SignalIndex index : indices) {
    const signals::SignalInfo& signal = catalog[index];
    out += signal.key + "  [" + rangeText(signal) + (signal.unit.empty() ? "" : " " + signal.unit) + "]  " +
           std::string(signals::signalKindName(signal.kind)) + (signal.bus.empty() ? "" : " on " + signal.bus) + ", " +
           std::string(signals::signalDirectionName(signal.direction)) + (signal.reported ? " status" : "") +
           ", owner " + ownerText(signal) + "\n";
    if (const auto maybeSlot = maybeTable->read(index)) {
      appendPlanes(out, signal, *maybeSlot);
    } else {
      out += "  unreadable: every recent write of a plane was unfinished; try again\n";
    }
  }
  streams.out.write(out);
  return ExitCode::Ok;
}

namespace {

/// Why no service may answer for `signal` (a received signal or a status), empty otherwise.
std::string notCommandableHint(const config::VehicleConfig& config, const signals::SignalInfo& signal) {
  if (signal.direction == signals::SignalDirection::Received) {
    std::string sender;
    for (const dbc::Message& message : config.database.messages) {
      if (message.name == signal.message) sender = message.transmitter;
    }
    return "'" + signal.key + "' is received from the bus (sent by " + sender + " in " + signal.message +
           "): only signals of messages this VCU sends can be commanded (`vcu schedule add " + signal.message +
           " MS` makes this bench send it)";
  }
  if (signal.reported) {
    return "'" + signal.key + "' is a status " + (signal.owner == signals::NO_OWNER ? "" : ownerText(signal) + " ") +
           "reports; it cannot be commanded";
  }
  return {};
}

}  // namespace

ExitCode runSignalSet(const SignalSetOptions& options, Streams streams) {
  if (options.mode == SetMode::ClearOverride && !options.value.empty()) {
    reportError(streams.err, "--clear-override takes no VALUE (see --help)");
    return ExitCode::Usage;
  }
  if (options.mode != SetMode::ClearOverride && options.value.empty()) {
    reportError(streams.err, "no VALUE given (see --help)");
    return ExitCode::Usage;
  }
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const Stack& stack = *maybeStack;
  const auto found = stack.catalog.find(options.key);
  if (!found) {
    reportError(streams.err, found.error().message);  // answered here: nothing is sent
    return ExitCode::Failure;
  }
  double value = 0.0;
  if (options.mode != SetMode::ClearOverride) {
    const auto valueResult = parseValue(stack.catalog[*found], options.value);
    if (!valueResult) {
      reportError(streams.err, valueResult.error().message);
      return ExitCode::Failure;
    }
    value = *valueResult;
  }

  ipc::CommandRequest request;
  request.kind = options.mode == SetMode::Override        ? ipc::CommandKind::SetOverride
                 : options.mode == SetMode::ClearOverride ? ipc::CommandKind::ClearOverride
                                                          : ipc::CommandKind::SetSignal;
  request.key = options.key;
  request.value = value;
  request.text = options.note;
  return sendCommandRequest(stack.config, std::move(request), options.timeoutSeconds, streams,
                            notCommandableHint(stack.config, stack.catalog[*found]));
}

ExitCode runSignalWatch(const SignalWatchOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const signals::Catalog& catalog = maybeStack->catalog;
  const auto matches = matchSignals(catalog, options.pattern, streams.err);
  if (matches.empty()) return ExitCode::Failure;
  const auto maybeTable = openTable(*maybeStack, streams.err);
  if (!maybeTable) return ExitCode::Failure;
  const signals::SignalTable& table = *maybeTable;

  std::vector<SeenPlanes> seen;
  seen.reserve(matches.size());
  for (const signals::SignalIndex index : matches) seen.push_back(SeenPlanes{index});
  const StopSignalScope stopSignals;
  std::uint32_t epoch = table.changeEpoch();  // before the first look: no change slips between
  bool complete = scanChanges(table, catalog, seen, nullptr);
  streams.err.write("watching " + std::to_string(matches.size()) + " signal" + (matches.size() == 1 ? "" : "s") +
                    " matching '" + options.pattern + "' in table '" + table.info().name + "' (Ctrl-C to stop)\n");
  streams.err.flush();

  const auto start = std::chrono::steady_clock::now();
  const auto forDuration =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(options.forSeconds));
  std::uint64_t printed = 0;
  std::vector<std::pair<std::int64_t, std::string>> changes;
  while (!stopRequested()) {
    std::chrono::nanoseconds wait =
        complete ? std::chrono::nanoseconds{WATCH_TICK} : std::chrono::nanoseconds{WATCH_RETRY};
    if (options.forSeconds > 0) {
      const auto left = start + forDuration - std::chrono::steady_clock::now();
      if (left <= std::chrono::nanoseconds::zero()) break;
      wait = std::min(wait, std::chrono::duration_cast<std::chrono::nanoseconds>(left));
    }
    const std::uint32_t newEpoch = table.waitForChange(epoch, wait);
    if (newEpoch == epoch && complete) continue;
    epoch = newEpoch;
    changes.clear();
    complete = scanChanges(table, catalog, seen, &changes);
    std::sort(changes.begin(), changes.end());
    std::string out;
    for (const auto& [timestampNs, line] : changes) {
      if (options.count > 0 && printed >= options.count) break;
      out += formatUtc(monotonicToRealtimeNs(timestampNs)) + "  " + line + "\n";
      ++printed;
    }
    if (!out.empty()) {
      streams.out.write(out);
      if (!streams.out.flush()) return ExitCode::Failure;  // e.g. the reader of a pipe went away
    }
    if (options.count > 0 && printed >= options.count) break;
  }
  return ExitCode::Ok;
}

void registerSignalCommands(CLI::App& app, CommandContext& context) {
  CLI::App* group =
      app.add_subcommand("signal", "Signals of a running stack: list, get, set (checked commands), watch");
  addList(*group, context);
  addGet(*group, context);
  addSet(*group, context);
  addWatch(*group, context);
}

}  // namespace openvcu::cli
