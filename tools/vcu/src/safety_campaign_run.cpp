// `vcu safety campaign` against a running stack: bringing the vehicle to a state, injecting
// a hazard's faults, watching the safe state, clearing and recovering.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "command_request.hpp"
#include "diagnostics.hpp"
#include "inject_commands.hpp"
#include "openvcu/config/faults.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/safety/safety_case.hpp"
#include "openvcu/signals/table.hpp"
#include "safety_campaign.hpp"
#include "safety_campaign_inject.hpp"
#include "safety_campaign_plan.hpp"
#include "safety_commands.hpp"

namespace openvcu::cli {
namespace {

using namespace std::chrono_literals;

constexpr std::int64_t NS_PER_MS = 1'000'000;
/// The watch loop waits at most this long for an LCM event between two looks at the table
/// and the bus (the resolution of table and process observations).
constexpr auto WATCH_TICK = 5ms;

double msBetween(std::int64_t fromNs, std::int64_t toNs) {
  return static_cast<double>(toNs - fromNs) / static_cast<double>(NS_PER_MS);
}

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : separator) + item;
  return text;
}

std::string lastPart(const std::string& key) {
  const auto dot = key.find('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

/// One thing a repetition waits for.
struct Watch {
  ItemResult result;
  std::vector<std::uint32_t> states;         ///< FsmState: any of these indices
  std::optional<signals::SignalIndex> slot;  ///< GpioLevel: internal.gpio.<line>; Restarted: its heartbeat
  double value{};                            ///< GpioLevel, BusSignal
  std::int32_t messageIndex{-1};             ///< BusSignal: Database::messages
  std::uint32_t signalIndex{};               ///< BusSignal: in the message
  std::string faultName;                     ///< Fault: the exact name, or
  std::string faultPrefix, faultSuffix;      ///< Fault: rx_timeout.<any bus>.<Message>
  std::string service;                       ///< Restarted
  std::vector<std::int32_t> pidsBefore;      ///< Restarted
  std::uint64_t beatsSeen{};                 ///< Restarted: the heartbeat updates last looked at
};

class Campaign {
 public:
  Campaign(const Stack& stack, fsm::Machine machine, signals::SignalTable table, ipc::EventBus events,
           const SafetyCampaignOptions& options, Streams streams)
      : m_stack(stack),
        m_machine(std::move(machine)),
        m_table(std::move(table)),
        m_planner(stack, m_machine, m_table, options.stepTimeoutSeconds, streams.err),
        m_injector(stack, options.stack, m_planner, streams.err),
        m_events(std::move(events)),
        m_options(options),
        m_streams(streams),
        m_matcher(stack.config.database, dbc::MatchMode::J1939),
        m_codecs(stack.config.database) {}

  /// Subscribes to fault events and to the wire of every simulated bus.
  Status open() {
    auto subscription = m_events.onFault([this](const ipc::FaultEvent& event) { m_faults.push_back(event); });
    if (!subscription) return Status(subscription.error());
    m_subscription.emplace(std::move(*subscription));
    for (const config::BusConfig& bus : m_stack.config.buses) {
      if (bus.link.kind != config::LinkKind::Sim) continue;
      if (!ipc::Runtime::initialized()) {
        if (Status init = ipc::Runtime::init("vcu-safety-" + std::to_string(::getpid())); !init) return init;
      }
      auto subscriber =
          ipc::FrameSubscriber::create(ipc::FrameTopic{"sim", bus.link.target, ipc::FrameStream::SimWire});
      if (!subscriber) return Status(subscriber.error());
      m_wires.push_back(std::move(*subscriber));
    }
    return {};
  }

  HazardResult run(const safety::Hazard& hazard) {
    HazardResult result;
    result.id = hazard.id;
    result.description = hazard.description;
    result.severity = hazard.severity;
    result.fttiMs = hazard.fttiMs;
    result.during = hazard.during;
    std::vector<const safety::Injection*> runnable;
    for (const safety::Injection& fault : hazard.faults) {
      if (const std::string why = m_injector.whyNot(fault); !why.empty()) {
        result.notInjected.push_back(why);
      } else {
        runnable.push_back(&fault);
      }
    }
    if (hazard.faults.empty()) result.notRunReasons.push_back("the hazard names no fault to inject");
    if (!hazard.faults.empty() && runnable.empty()) {
      result.notRunReasons.push_back("none of its faults can be injected today");
    }
    std::vector<Watch> watches = watchesOf(hazard, result);
    if (watches.empty()) result.notRunReasons.push_back("nothing of its safe state or detection can be observed");
    if (!result.notRunReasons.empty()) return result;

    // each fault of the list is one injection of its own: the faults are alternative causes
    int index = 0;
    for (int i = 1; i <= m_options.repeat; ++i) {
      for (const safety::Injection* fault : runnable) {
        Repetition repetition = runOnce(hazard, *fault, watches, ++index);
        m_streams.out.write(formatRepetition(result, repetition));
        m_streams.out.flush();
        result.repetitions.push_back(std::move(repetition));
      }
    }
    return result;
  }

  /// The index of every FSM state named, for coverage.
  [[nodiscard]] const fsm::Machine& machine() const noexcept { return m_machine; }

 private:
  // ---- what is watched --------------------------------------------------------------------

  std::vector<Watch> watchesOf(const safety::Hazard& hazard, HazardResult& result) {
    std::vector<Watch> watches;
    const safety::SafeState& safe = hazard.safeState;
    if (!safe.fsmStates.empty()) {
      Watch watch;
      watch.result.kind = ItemKind::FsmState;
      watch.result.item = "fsm " + join(safe.fsmStates, "|");
      for (const std::string& name : safe.fsmStates) {
        if (const auto index = m_machine.findState(name)) watch.states.push_back(*index);
      }
      if (watch.states.empty()) {
        result.notRunReasons.push_back("no FSM state " + join(safe.fsmStates, ", ") + " in " + m_machine.file);
      } else {
        watches.push_back(std::move(watch));
      }
    }
    for (const safety::SafeCommand& command : safe.bus) {
      Watch watch;
      watch.result.kind = ItemKind::BusSignal;
      watch.result.item = "bus " + lastPart(command.signal) + "=" + formatNumber(command.value);
      watch.value = command.value;
      const auto index = m_stack.catalog.indexOf(command.signal);
      const dbc::Database& database = m_stack.config.database;
      if (index) {
        const signals::SignalInfo& info = m_stack.catalog[*index];
        for (std::size_t m = 0; m < database.messages.size() && watch.messageIndex < 0; ++m) {
          if (database.messages[m].name != info.message) continue;
          const auto& signals = database.messages[m].signals;
          const std::string name = command.signal.substr(command.signal.rfind('.') + 1);
          for (std::size_t s = 0; s < signals.size(); ++s) {
            if (signals[s].name == name) {
              watch.messageIndex = static_cast<std::int32_t>(m);
              watch.signalIndex = static_cast<std::uint32_t>(s);
            }
          }
        }
      }
      const config::BusConfig* bus = nullptr;
      if (index) {
        for (const config::BusConfig& candidate : m_stack.config.buses) {
          if (candidate.name == m_stack.catalog[*index].bus) bus = &candidate;
        }
      }
      if (watch.messageIndex < 0) {
        result.notRunReasons.push_back("bus command " + command.signal + ": not a DBC signal of this vehicle");
      } else if (bus == nullptr || bus->link.kind != config::LinkKind::Sim) {
        result.unobserved.push_back("bus " + command.signal + ": its bus is not simulated (frames not seen)");
      } else {
        watches.push_back(std::move(watch));
      }
    }
    for (const safety::SafeLevel& level : safe.gpio) {
      Watch watch;
      watch.result.kind = ItemKind::GpioLevel;
      watch.result.item = "gpio " + level.line + "=" + (level.level ? "1" : "0");
      watch.value = level.level ? 1 : 0;
      watch.slot = m_stack.catalog.indexOf("internal.gpio." + level.line);
      if (!watch.slot) {
        result.unobserved.push_back("gpio " + level.line + ": no internal.gpio." + level.line + " in the catalog");
      } else {
        watches.push_back(std::move(watch));
      }
    }
    for (const std::string& service : safe.restarted) {
      Watch watch;
      watch.result.kind = ItemKind::Restarted;
      watch.result.item = "restarted " + service;
      watch.service = service;
      watch.slot = m_stack.catalog.indexOf("internal.service." + service + ".heartbeat");
      if (!watch.slot) {
        result.unobserved.push_back("restarted " + service + ": no heartbeat slot");
      } else {
        watches.push_back(std::move(watch));
      }
    }
    for (const safety::Detection& detection : hazard.detection) {
      using safety::DetectionKind;
      Watch watch;
      watch.result.kind = ItemKind::Fault;
      watch.result.detection = std::string(safety::detectionKindName(detection.kind));
      switch (detection.kind) {
        case DetectionKind::ServiceWatchdog:
          watch.faultName = faults::serviceSilent(detection.service);
          break;
        case DetectionKind::Dtc:
          watch.faultName = detection.fault;
          break;
        case DetectionKind::AddressLoss:
          watch.faultName = "j1939_address_lost." + detection.bus;
          break;
        case DetectionKind::J1939_76:
          watch.faultName = "j1939_76." + detection.message;
          break;
        case DetectionKind::ReceiveTimeout:
          // can-rx raises rx_timeout.<bus>.<Message> for the message, or the signal's message
          if (!detection.message.empty()) {
            watch.faultPrefix = "rx_timeout.";
            watch.faultSuffix = "." + detection.message;
          } else if (const auto index = m_stack.catalog.indexOf(detection.signal);
                     index && !m_stack.catalog[*index].message.empty()) {
            watch.faultPrefix = "rx_timeout.";
            watch.faultSuffix = "." + m_stack.catalog[*index].message;
          }
          break;
        case DetectionKind::Dm1:
        case DetectionKind::GpioInput:
        case DetectionKind::StatusSignal:
          break;
      }
      const std::string what = watch.result.detection + " " + detection.message + detection.signal + detection.node +
                               detection.fault + detection.line + detection.service + detection.bus;
      if (watch.faultName.empty() && watch.faultPrefix.empty()) {
        result.unobserved.push_back(what + ": no fault event names it (judged through the safe state only)");
        continue;
      }
      watch.result.item =
          "fault " + (watch.faultName.empty() ? watch.faultPrefix + "*" + watch.faultSuffix : watch.faultName);
      watches.push_back(std::move(watch));
    }
    return watches;
  }

  // ---- watching ---------------------------------------------------------------------------

  /// Takes the frames before the injection; a bus watch whose last value there was already
  /// the safe one gets a note (its time then says when the next frame came, not a reaction).
  void drainWires(std::vector<Watch>& watches) {
    for (ipc::FrameSubscriber& wire : m_wires) {
      while (const auto sample = wire.take()) {
        const std::int32_t match = m_matcher.match(sample->frame.id, sample->frame.extended());
        if (match == dbc::MessageMatcher::NO_MATCH) continue;
        for (Watch& watch : watches) {
          if (watch.result.kind != ItemKind::BusSignal || watch.messageIndex != match) continue;
          m_codecs[static_cast<std::size_t>(match)].decode(
              sample->frame.payload(), [&](std::uint32_t signal, const dbc::DecodedValue& value) {
                if (signal != watch.signalIndex) return;
                watch.result.note = std::abs(value.physical - watch.value) < 1e-9
                                        ? "already at the safe value before the injection"
                                        : "";
              });
        }
      }
    }
  }

  /// Looks at every watch once; `log` adds to the timeline.
  void observe(std::vector<Watch>& watches, const InjectionStamp& at, Repetition& repetition,
               std::optional<std::uint32_t>& lastState) {
    // the FSM state (and its changes, for the timeline)
    const auto stateIndex = m_stack.catalog.indexOf("internal.fsm.state");
    std::int64_t stateStampNs = 0;  // when internal.fsm.state was written last
    bool stateKnown = false;
    if (stateIndex) {
      if (const auto reading = m_planner.read(*stateIndex)) {
        stateStampNs = reading->timestampNs;
        stateKnown = true;
      }
    }
    const auto state = m_planner.currentState();
    if (state != lastState && state && stateKnown) {
      repetition.timeline.push_back({msBetween(at.monotonicNs, stateStampNs), "FSM " + m_planner.stateName(state)});
      lastState = state;
    }
    // frames on the simulated buses
    for (ipc::FrameSubscriber& wire : m_wires) {
      while (const auto sample = wire.take()) {
        if (sample->monotonicNs < at.monotonicNs) continue;
        const std::int32_t match = m_matcher.match(sample->frame.id, sample->frame.extended());
        if (match == dbc::MessageMatcher::NO_MATCH) continue;
        for (Watch& watch : watches) {
          if (watch.result.reachedMs || watch.result.kind != ItemKind::BusSignal || watch.messageIndex != match)
            continue;
          bool equal = false;
          m_codecs[static_cast<std::size_t>(match)].decode(
              sample->frame.payload(), [&](std::uint32_t signal, const dbc::DecodedValue& value) {
                if (signal == watch.signalIndex && std::abs(value.physical - watch.value) < 1e-9) equal = true;
              });
          if (equal) reached(watch, msBetween(at.monotonicNs, sample->monotonicNs), repetition);
        }
      }
    }
    for (Watch& watch : watches) {
      if (watch.result.reachedMs) continue;
      switch (watch.result.kind) {
        case ItemKind::FsmState:
          if (state && stateKnown &&
              std::find(watch.states.begin(), watch.states.end(), *state) != watch.states.end()) {
            watch.result.reached = m_planner.stateName(state);
            reached(watch, std::max(0.0, msBetween(at.monotonicNs, stateStampNs)), repetition);
          }
          break;
        case ItemKind::GpioLevel:
          if (const auto level = m_planner.read(*watch.slot); level && level->value == watch.value) {
            // e.g. Cl15 still in its on-delay after the state was reached: no reaction
            if (level->timestampNs < at.monotonicNs)
              watch.result.note = "already at the safe level before the injection";
            reached(watch, std::max(0.0, msBetween(at.monotonicNs, level->timestampNs)), repetition);
          }
          break;
        case ItemKind::Restarted:
          if (const auto beat = m_planner.read(*watch.slot);
              beat && beat->updates != watch.beatsSeen && beat->timestampNs > at.monotonicNs) {
            watch.beatsSeen = beat->updates;
            for (const std::int32_t pid : findServiceProcesses(watch.service)) {
              if (std::find(watch.pidsBefore.begin(), watch.pidsBefore.end(), pid) == watch.pidsBefore.end()) {
                watch.result.note = "new pid " + std::to_string(pid);
                reached(watch, msBetween(at.monotonicNs, beat->timestampNs), repetition);
                break;
              }
            }
          }
          break;
        case ItemKind::Fault:
          for (const ipc::FaultEvent& event : m_faults) {
            const bool named = watch.faultName.empty() ? event.name.starts_with(watch.faultPrefix) &&
                                                             event.name.ends_with(watch.faultSuffix)
                                                       : event.name == watch.faultName;
            if (named && event.active && event.timestampNs >= at.realtimeNs) {
              watch.result.note = event.source + ": " + event.text;
              reached(watch, msBetween(at.realtimeNs, event.timestampNs), repetition);
              break;
            }
          }
          break;
        case ItemKind::BusSignal:
          break;
      }
    }
  }

  static void reached(Watch& watch, double ms, Repetition& repetition) {
    watch.result.reachedMs = ms;
    repetition.timeline.push_back(
        {ms, watch.result.item + (watch.result.reached.empty() ? "" : " (" + watch.result.reached + ")")});
  }

  Repetition runOnce(const safety::Hazard& hazard, const safety::Injection& fault, std::vector<Watch> watches,
                     int index) {
    Repetition repetition;
    repetition.index = index;
    std::vector<std::uint32_t> during;
    for (const std::string& name : hazard.during) {
      if (const auto state = m_machine.findState(name)) during.push_back(*state);
    }
    if (!during.empty()) {
      if (const std::string why = m_planner.reach(during); !why.empty()) {
        repetition.error = "cannot bring the vehicle to " + join(hazard.during, " or ") + ": " + why;
        return repetition;
      }
    }
    // the state just entered settles first (HHEA's inverters step up for 400 ms in Driving):
    // a safe value the vehicle has not yet left is no reaction
    std::this_thread::sleep_for(std::chrono::duration<double>(m_options.settleSeconds));
    const auto home = m_planner.currentState();
    for (Watch& watch : watches) {
      if (watch.result.kind == ItemKind::Restarted) watch.pidsBefore = findServiceProcesses(watch.service);
    }
    drainWires(watches);
    while (m_events.handle(0ms) == ipc::HandleResult::Handled) {
    }
    m_faults.clear();

    std::vector<AppliedFault> applied;
    std::optional<InjectionStamp> first;
    {
      InjectionStamp stamp;
      std::string error;
      auto maybeApplied = m_injector.inject(fault, &stamp, &error);
      if (maybeApplied) {
        first = stamp;
        repetition.injected.push_back(maybeApplied->label);
        applied.push_back(std::move(*maybeApplied));
      } else {
        repetition.error = "injection failed: " + error;
      }
    }
    if (first) {
      repetition.injectedMonotonicNs = first->monotonicNs;
      repetition.injectedRealtimeNs = first->realtimeNs;
      repetition.timeline.push_back({0, "injected " + join(repetition.injected, ", ")});
    }
    if (repetition.error.empty() && first) {
      const std::int64_t windowNs = 2 * hazard.fttiMs * NS_PER_MS;
      std::optional<std::uint32_t> lastState = home;
      for (;;) {
        (void)m_events.handle(WATCH_TICK);
        m_events.handleAll();
        observe(watches, *first, repetition, lastState);
        const bool all =
            std::all_of(watches.begin(), watches.end(), [](const Watch& w) { return w.result.reachedMs.has_value(); });
        const std::int64_t elapsed = clock::monotonicNs() - first->monotonicNs;
        if (all || elapsed >= windowNs) {
          repetition.windowMs = msBetween(0, std::min(elapsed, windowNs));
          break;
        }
      }
      for (Watch& watch : watches) repetition.items.push_back(watch.result);
    }
    std::sort(repetition.timeline.begin(), repetition.timeline.end(),
              [](const TimelineEntry& a, const TimelineEntry& b) { return a.ms < b.ms; });
    // clear in reverse order, then back to where the repetition started (fault reset included)
    for (auto it = applied.rbegin(); it != applied.rend(); ++it) {
      if (it->clear) it->clear();
    }
    if (home) {
      if (const std::string why = m_planner.reach({*home}); !why.empty()) {
        m_streams.err.write("vcu: warning: " + hazard.id + " #" + std::to_string(index) + ": not back in " +
                            m_planner.stateName(home) + ": " + why + "\n");
      }
    }
    return repetition;
  }

  const Stack& m_stack;
  fsm::Machine m_machine;
  signals::SignalTable m_table;
  StatePlanner m_planner;
  FaultInjector m_injector;
  ipc::EventBus m_events;
  std::optional<ipc::Subscription> m_subscription;
  const SafetyCampaignOptions& m_options;
  Streams m_streams;
  dbc::MessageMatcher m_matcher;
  dbc::DatabaseCodec m_codecs;
  std::vector<ipc::FrameSubscriber> m_wires;
  std::vector<ipc::FaultEvent> m_faults;
};

bool writeFile(const std::string& path, const std::string& text, Sink& err) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) {
    reportError(err, "cannot write " + path);
    return false;
  }
  return true;
}

std::string hostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "?";
  return name;
}

}  // namespace

ExitCode runSafetyCampaign(const SafetyCampaignOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const Stack& stack = *maybeStack;
  const std::string safetyFile = options.safetyFile.empty() ? stack.config.safetyFile : options.safetyFile;
  if (safetyFile.empty()) {
    reportError(
        streams.err,
        stack.config.path + ": no \"safety\" file (a vehicle without one has no safety case); --safety FILE names one");
    return ExitCode::Usage;
  }
  auto safetyResult = safety::loadSafety(safetyFile);
  if (!safetyResult) {
    reportError(streams.err, safetyResult.error().message);
    return ExitCode::Failure;
  }
  const safety::SafetyCase& safetyCase = *safetyResult;
  std::vector<const safety::Hazard*> selected;
  for (const std::string& id : options.hazards) {
    const safety::Hazard* hazard = safetyCase.findHazard(id);
    if (hazard == nullptr) {
      std::string known;
      for (const safety::Hazard& h : safetyCase.hazards) known += (known.empty() ? "" : ", ") + h.id;
      reportError(streams.err,
                  safetyFile + ": no hazard '" + id + "' (hazards: " + (known.empty() ? "none" : known) + ")");
      return ExitCode::Usage;
    }
    selected.push_back(hazard);
  }
  if (options.hazards.empty()) {
    for (const safety::Hazard& hazard : safetyCase.hazards) selected.push_back(&hazard);
  }
  if (stack.config.fsmFile.empty()) {
    reportError(streams.err,
                stack.config.path + ": no \"fsm\" file: the campaign brings the vehicle to states through it");
    return ExitCode::Failure;
  }
  auto machine = fsm::loadMachine(stack.config.fsmFile, stack.config, stack.catalog);
  if (!machine) {
    reportError(streams.err, machine.error().message);
    return ExitCode::Failure;
  }
  auto table = signals::SignalTable::open(stack.catalog, stack.config.instance, signals::OpenMode::AttachOnly);
  if (!table) {
    reportError(streams.err, table.error().message + " (is the stack running?)");
    return ExitCode::Failure;
  }
  auto events = ipc::EventBus::open(stack.config.lcmUrl, stack.config.instance);
  if (!events) {
    reportError(streams.err, events.error().message);
    return ExitCode::Failure;
  }
  Campaign campaign(stack, std::move(*machine), std::move(*table), std::move(*events), options, streams);
  if (const Status opened = campaign.open(); !opened) {
    reportError(streams.err, opened.error().message);
    return ExitCode::Failure;
  }

  CampaignResult result;
  result.vehicle = stack.config.path;
  result.safetyFile = safetyFile;
  result.host = hostName();
  result.startedRealtimeNs = clock::realtimeNs();
  for (int kind = 0; kind <= static_cast<int>(safety::DetectionKind::StatusSignal); ++kind) {
    result.detectionKinds.emplace_back(safety::detectionKindName(static_cast<safety::DetectionKind>(kind)));
  }
  for (const safety::Hazard* hazard : selected) {
    for (const std::string& state : hazard->safeState.fsmStates) {
      if (std::find(result.safeFsmStates.begin(), result.safeFsmStates.end(), state) == result.safeFsmStates.end()) {
        result.safeFsmStates.push_back(state);
      }
    }
    result.hazards.push_back(campaign.run(*hazard));
    if (!result.hazards.back().notRunReasons.empty()) {
      streams.out.write(hazard->id + " NOT RUN: " + join(result.hazards.back().notRunReasons, "; ") + "\n");
    }
  }
  streams.out.write(formatSummary(result));
  bool written = true;
  if (!options.jsonFile.empty())
    written = writeFile(options.jsonFile, toJson(result).dump(2) + "\n", streams.err) && written;
  if (!options.junitFile.empty()) written = writeFile(options.junitFile, toJunit(result), streams.err) && written;
  if (!options.htmlFile.empty()) written = writeFile(options.htmlFile, toHtml(result), streams.err) && written;
  // a hazard named with --hazard that cannot run is a failure: it was asked for
  const bool strict = options.strict || !options.hazards.empty();
  return campaignPassed(result, strict) && written ? ExitCode::Ok : ExitCode::Failure;
}

}  // namespace openvcu::cli
