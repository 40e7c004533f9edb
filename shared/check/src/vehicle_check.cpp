// The whole-vehicle checks (vehicle_check.hpp): loading the files, unused signals, FSM
// conditions on signals nobody writes, the simulation's J1939-76 checks, diagnostics.json
// against the FSM and the catalog; the bus checks are in bus_checks.cpp.
#include "openvcu/check/vehicle_check.hpp"

#include <algorithm>
#include <iomanip>
#include <map>
#include <sstream>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/diagnostics.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/j1939/address_claim.hpp"
#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/j1939/transport.hpp"
#include "j1939_checks.hpp"
#include "vehicle_files.hpp"

namespace openvcu::check {

std::string percent(double share) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(1) << share * 100 << " %";
  return text.str();
}

std::string hexId(std::uint32_t id, bool extended) {
  std::ostringstream text;
  text << "0x" << std::uppercase << std::hex << std::setw(extended ? 8 : 3) << std::setfill('0') << id;
  return text.str();
}

Location messageLocation(const config::VehicleConfig& vehicle, const dbc::Message& message) {
  if (vehicle.dbcFiles.size() == 1) return Location{vehicle.dbcFiles.front(), message.source.line, 0, {}};
  return Location::json(vehicle.path, "/dbc");
}

std::string listNames(const std::vector<std::string>& names) {
  std::string text;
  const std::size_t shown = std::min(names.size(), NAMES_SHOWN);
  for (std::size_t i = 0; i < shown; ++i) text += (i == 0 ? "" : ", ") + names[i];
  if (names.size() > shown) text += " and " + std::to_string(names.size() - shown) + " more";
  return text;
}

namespace {


/// A received message vcu-can-rx handles itself (transport, requests, acknowledgements,
/// address claims, J1939-76 headers, DM1 when its decoding is on): not "unused".
bool protocolMessage(const dbc::Message& message, const VehicleFiles& files) {
  if (!message.extended) return false;
  const std::uint32_t pgn = j1939::Id::fromCanId(message.id).pgn();
  if (pgn == j1939::PGN_DM1) return files.receive && files.receive->dm1;
  return pgn == j1939::PGN_TP_CM || pgn == j1939::PGN_TP_DT || pgn == j1939::PGN_REQUEST ||
         pgn == j1939::PGN_ACKNOWLEDGEMENT || pgn == j1939::PGN_ADDRESS_CLAIMED || pgn == j1939::PGN_SAFETY_HEADER;
}

/// Loads every file the checks read; a note per file that does not load.
VehicleFiles loadFiles(const config::VehicleConfig& vehicle, const signals::Catalog& catalog, std::vector<Error>& out) {
  VehicleFiles files;
  const auto skipped = [&](const std::string& file) {
    out.push_back(Error{"not cross-checked with the other files: it does not load (its own check says why)",
                        Location{file, 0, 0, {}}, Severity::Note});
  };
  if (auto loaded = schedule::loadSchedule(vehicle, catalog)) {
    files.schedule = std::move(*loaded);
  } else {
    skipped(vehicle.scheduleFile.empty() ? vehicle.path : vehicle.scheduleFile);
  }
  if (!vehicle.fsmFile.empty()) {
    if (auto loaded = fsm::loadMachine(vehicle.fsmFile, vehicle, catalog)) {
      files.machine = std::move(*loaded);
    } else {
      skipped(vehicle.fsmFile);
    }
  }
  if (auto loaded = config::loadReceiveConfig(vehicle)) {
    files.receive = std::move(*loaded);
  } else {
    skipped(vehicle.receiveFile.empty() ? vehicle.path : vehicle.receiveFile);
  }
  if (!vehicle.simulationFile.empty()) {
    if (auto loaded = config::loadSimConfig(vehicle.simulationFile, vehicle)) {
      files.simulation = std::move(*loaded);
    } else {
      skipped(vehicle.simulationFile);
    }
  }
  if (!vehicle.diagnosticsFile.empty()) {
    std::vector<std::string> states;
    if (files.machine) {
      for (const fsm::State& state : files.machine->states) states.push_back(state.name);
    }
    if (auto loaded = config::loadDiagnosticsConfig(vehicle, catalog, files.machine ? &states : nullptr, &out)) {
      files.diagnostics = std::move(*loaded);
    }
  }
  if (const std::string dashboard = config::dashboardBeside(vehicle.path); !dashboard.empty()) {
    if (auto loaded = config::loadDashboardConfig(dashboard, catalog)) {
      files.dashboard = std::move(*loaded);
    } else {
      skipped(dashboard);
    }
  }
  return files;
}

/// Every action of the machine (entry, exit, transitions).
template <typename Visit>
void forEachAction(const fsm::Machine& machine, Visit&& visit) {
  for (const fsm::State& state : machine.states) {
    for (const fsm::Action& action : state.entry) visit(action);
    for (const fsm::Action& action : state.exit) visit(action);
    for (const fsm::Transition& transition : state.transitions) {
      for (const fsm::Action& action : transition.actions) visit(action);
    }
  }
}

/// The signals of `message` (catalog indices of those it holds).
template <typename Visit>
void forEachSignalOf(const dbc::Message& message, const signals::Catalog& catalog, Visit&& visit) {
  for (const dbc::Signal& signal : message.signals) {
    if (const auto index = catalog.indexOf(config::signalKey(message, signal))) visit(*index);
  }
}

bool forwardMatches(const config::ForwardRule& rule, const dbc::Message& message) {
  if (!rule.byPgn) return message.id == rule.id && message.extended == rule.extended;
  if (!message.extended) return false;
  const j1939::Id id = j1939::Id::fromCanId(message.id);
  return id.pgn() == rule.id && (!rule.source || *rule.source == id.sourceAddress);
}

/// The catalog indices some file of the vehicle reads.
std::vector<bool> readSignals(const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                              const VehicleFiles& files) {
  std::vector<bool> used(catalog.size(), false);
  const auto mark = [&](const std::string& key) {
    if (const auto index = catalog.indexOf(key)) used[*index] = true;
  };
  if (files.machine) {
    for (const fsm::SignalRef& ref : files.machine->signals) used[ref.index] = true;
    forEachAction(*files.machine, [&](const fsm::Action& action) {
      if (action.kind == fsm::ActionKind::SetSignal && action.copy) used[action.source] = true;
    });
  }
  if (files.dashboard) {
    const config::DashboardConfig& dashboard = *files.dashboard;
    for (const std::string* key : {&dashboard.voltageKey, &dashboard.currentKey, &dashboard.powerKey, &dashboard.socKey,
                                   &dashboard.sohKey, &dashboard.chargerKey}) {
      mark(*key);
    }
    for (const std::string& key : dashboard.statusKeys) mark(key);
    for (const config::DashboardItem& item : dashboard.items) mark(item.key);
  }
  if (files.simulation) mark(files.simulation->wakeSignal);
  if (files.diagnostics) {
    for (const config::DtcConfig& dtc : files.diagnostics->dtcs) mark(dtc.signal);
  }
  if (files.schedule) {
    for (const schedule::SendGroup& group : files.schedule->groups) used[group.signal] = true;
    for (const schedule::SafeValue& safe : files.schedule->safeValues) used[safe.signal] = true;
  }
  for (const config::GpioLine& line : vehicle.gpio.lines) mark(line.signal);
  if (files.receive) {
    const auto& messages = vehicle.database.messages;
    for (const config::SafetyGroup& group : files.receive->safety) {
      forEachSignalOf(messages[group.dataMessage], catalog, [&](signals::SignalIndex i) { used[i] = true; });
    }
    for (const config::ForwardRule& rule : files.receive->forward) {
      for (const std::size_t m : vehicle.buses[rule.fromBus].messages) {
        if (!forwardMatches(rule, messages[m])) continue;
        forEachSignalOf(messages[m], catalog, [&](signals::SignalIndex i) { used[i] = true; });
      }
    }
  }
  return used;
}

/// One warning per bus with received signals nobody reads (see the header for why one).
void checkUnusedSignals(const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                        const VehicleFiles& files, std::vector<Error>& out) {
  // A file that does not load reads nothing here: counting would blame signals it may read.
  const bool complete = files.schedule && files.receive && (vehicle.fsmFile.empty() || files.machine) &&
                        (vehicle.simulationFile.empty() || files.simulation) &&
                        (config::dashboardBeside(vehicle.path).empty() || files.dashboard) &&
                        (vehicle.diagnosticsFile.empty() || files.diagnostics);
  if (!complete) return;
  const std::vector<bool> used = readSignals(vehicle, catalog, files);
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    const config::BusConfig& bus = vehicle.buses[b];
    std::size_t total = 0;
    std::size_t unused = 0;
    std::size_t receivedMessages = 0;
    std::vector<std::string> unusedMessages;
    for (const std::size_t m : bus.messages) {
      const dbc::Message& message = vehicle.database.messages[m];
      if (config::sentBy(message, vehicle.node) || protocolMessage(message, files)) continue;
      std::size_t signalCount = 0;
      std::size_t unusedCount = 0;
      forEachSignalOf(message, catalog, [&](signals::SignalIndex i) {
        ++signalCount;
        if (!used[i]) ++unusedCount;
      });
      if (signalCount == 0) continue;
      ++receivedMessages;
      total += signalCount;
      unused += unusedCount;
      if (unusedCount == signalCount) {
        const Location where = messageLocation(vehicle, message);
        unusedMessages.push_back(message.name + (where.line > 0 ? " (line " + std::to_string(where.line) + ")" : ""));
      }
    }
    if (unused == 0) continue;
    std::string text = "bus '" + bus.name + "': " + std::to_string(unused) + " of " + std::to_string(total) +
                       " received signals are read by no file of the vehicle (FSM, dashboard, schedule, receive, "
                       "simulation, diagnostics, GPIO map)";
    if (!unusedMessages.empty()) {
      text += "; " + std::to_string(unusedMessages.size()) + " of its " + std::to_string(receivedMessages) +
              " received messages " + (unusedMessages.size() == 1 ? "has" : "have") +
              " none read: " + listNames(unusedMessages) +
              ". vcu-can-rx still decodes them and vcu-hmi shows them; to drop a message, list the bus' "
              "messages without it";
    }
    out.push_back(Error{std::move(text),
                        Location::json(vehicle.path, config::JsonChecker::join("/buses", b) + "/messages"),
                        Severity::Warning});
  }
}

/// Why nobody writes the signal a condition reads, or empty when someone does.
std::optional<std::string> unwrittenReason(const config::VehicleConfig& vehicle, const signals::SignalInfo& info,
                                           bool written, const VehicleFiles& files) {
  using signals::SignalDirection;
  if (info.direction == SignalDirection::Received) return std::nullopt;  // can-rx, when its message arrives
  if (info.direction == SignalDirection::Transmitted) {
    if (written) return std::nullopt;
    return "it is a signal " + vehicle.node + " sends, but the schedule does not send its message " + info.message +
           " and no FSM action sets it";
  }
  if (info.reported) {
    if (info.owner == signals::NO_OWNER) {
      return "it is declared in a status namespace (internal.fsm., .service., .bus., .dm1., .gpio.) that no service "
             "of the stack writes";
    }
    if (info.key.starts_with("internal.dm1.") && files.receive && !files.receive->dm1) {
      return "vcu-can-rx's DM1 decoding is off (\"dm1\": false in " + vehicle.receiveFile + ")";
    }
    return std::nullopt;
  }
  if (vehicle.gpio.inputBoundTo(info.key) != nullptr || written) return std::nullopt;
  if (info.key.starts_with("internal.operator.")) return std::nullopt;  // the HMI's operator switches
  if (info.key.starts_with(config::SEND_GROUP_NAMESPACE)) {
    return "no FSM action switches this send group; only an operator command (vcu signal set) would";
  }
  return "no FSM action sets it, no GPIO input line is bound to it and it is no operator switch "
         "(internal.operator.*): it keeps its initial value unless someone runs vcu signal set";
}

/// One warning per signal the FSM's conditions read and nobody writes.
void checkUnwrittenConditions(const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                              const VehicleFiles& files, std::vector<Error>& out) {
  if (!files.machine) return;
  const fsm::Machine& machine = *files.machine;
  std::vector<bool> written(catalog.size(), false);
  forEachAction(machine, [&](const fsm::Action& action) {
    if (action.kind == fsm::ActionKind::SetSignal) written[action.signal] = true;
  });
  if (files.schedule) {
    for (const schedule::ScheduledMessage& entry : files.schedule->messages) {
      for (const auto& key : entry.keys) {
        if (key) written[*key] = true;
      }
    }
  }
  // Per read signal (Machine::signals order): the paths of the conditions reading it.
  std::map<std::uint32_t, std::vector<const std::string*>> readers;
  for (const fsm::ConditionNode& node : machine.nodes) {
    if (node.signal == fsm::NONE) continue;
    if (node.kind != fsm::NodeKind::Compare && node.kind != fsm::NodeKind::Quality && node.kind != fsm::NodeKind::Age) {
      continue;
    }
    readers[node.signal].push_back(&node.path);
  }
  for (const auto& [slot, paths] : readers) {
    const signals::SignalIndex index = machine.signals[slot].index;
    const signals::SignalInfo& info = catalog[index];
    const auto reason = unwrittenReason(vehicle, info, written[index], files);
    if (!reason) continue;
    std::string text = "the condition reads " + info.key + ", which nobody writes: " + *reason;
    if (paths.size() > 1) text += " (" + std::to_string(paths.size() - 1) + " more conditions read it)";
    out.push_back(Error{std::move(text), Location::json(machine.file, *paths.front()), Severity::Warning});
  }
}

/// The simulation's J1939-76 checks on messages no configured bus carries (its loader only
/// looks the name up in the DBC): the simulated node would never see them.
void checkSimulationMessages(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::vector<Error>& out) {
  if (!files.simulation) return;
  for (std::size_t i = 0; i < files.simulation->safety.size(); ++i) {
    const std::string& name = files.simulation->safety[i].message;
    const dbc::Message* message = vehicle.database.findMessage(name);
    if (message == nullptr) continue;
    if (vehicle.busOf(static_cast<std::size_t>(message - vehicle.database.messages.data())) != nullptr) continue;
    out.push_back(
        Error{"message '" + name + "' is on no configured bus: list it in a bus' \"messages\" of " + vehicle.path,
              Location::json(vehicle.simulationFile, config::JsonChecker::join("/safety", i) + "/message")});
  }
}

/// The HHEA simulation's wake signal must be a catalog key: vcu-ecu-sim looks it up at start
/// and refuses to run without it (its loader has no catalog to check it with).
void checkSimulationWakeSignal(const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                               const VehicleFiles& files, std::vector<Error>& out) {
  if (!files.simulation || files.simulation->wakeSignal.empty()) return;
  const std::string& key = files.simulation->wakeSignal;
  if (catalog.indexOf(key)) return;
  std::string text = "unknown signal '" + key + "'";
  if (auto suggestion = catalog.suggest(key)) text += "; did you mean '" + *suggestion + "'?";
  text += " (the simulated VIC wakes only while this table key is 1)";
  out.push_back(Error{std::move(text), Location::json(vehicle.simulationFile, "/wakeSignal")});
}

/// A warning per FSM state whose entry raises a fault that no DTC of diagnostics.json maps
/// (the file's own errors and warnings come from loadFiles()).
void checkUnmappedFaultStates(const config::VehicleConfig& vehicle, const VehicleFiles& files,
                              std::vector<Error>& out) {
  if (!files.diagnostics || !files.machine) return;
  for (std::size_t i = 0; i < files.machine->states.size(); ++i) {
    const fsm::State& state = files.machine->states[i];
    const auto raise = std::find_if(state.entry.begin(), state.entry.end(),
                                    [](const fsm::Action& action) { return action.kind == fsm::ActionKind::RaiseFault; });
    if (raise == state.entry.end()) continue;
    const auto& dtcs = files.diagnostics->dtcs;
    const bool mapped = std::any_of(dtcs.begin(), dtcs.end(), [&](const config::DtcConfig& dtc) {
      return dtc.source == config::DtcSource::FsmState && dtc.fsmState == state.name;
    });
    if (mapped) continue;
    out.push_back(Error{"state '" + state.name + "' raises fault '" + raise->name + "' but no DTC of " +
                            vehicle.diagnosticsFile + " has \"fsmState\": \"" + state.name + "\"",
                        Location::json(files.machine->file, config::JsonChecker::join("/states", i)),
                        Severity::Warning});
  }
}

}  // namespace

std::vector<Error> checkVehicle(const config::VehicleConfig& vehicle, const signals::Catalog& catalog) {
  std::vector<Error> out;
  const VehicleFiles files = loadFiles(vehicle, catalog, out);
  checkUnusedSignals(vehicle, catalog, files, out);
  checkUnwrittenConditions(vehicle, catalog, files, out);
  checkBusLoads(vehicle, files, out);
  checkAddresses(vehicle, files, out);
  checkSafetyAddressPolicy(vehicle, files, out);
  checkSimulationMessages(vehicle, files, out);
  checkSimulationWakeSignal(vehicle, catalog, files, out);
  checkUnmappedFaultStates(vehicle, files, out);
  return out;
}

}  // namespace openvcu::check
