#include "can_tx_app.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <deque>
#include <filesystem>
#include <optional>

#include "network.hpp"
#include "openvcu/config/diagnostics.hpp"
#include "openvcu/config/faults.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/request_stream.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/service/app_impl.hpp"
#include "openvcu/service/bus_ports.hpp"
#include "openvcu/service/timer.hpp"
#include "openvcu/signals/writer_watch.hpp"
#include "schedule_commands.hpp"
#include "scheduler.hpp"
#include "tx_thread.hpp"

namespace openvcu::cantx {
namespace {

constexpr std::chrono::milliseconds WATCH_PERIOD{100};
constexpr std::int64_t NS_PER_MS = 1'000'000;

using signals::WriterChange;
using signals::WriterWatch;
using text::number;

}  // namespace

/// One bus: its link and streams (service::BusPorts, Transmitter role) and their counters.
struct BusIo : service::BusPorts {
  std::atomic<std::uint64_t> publishFailures{};
  std::atomic<std::uint64_t> framesSent{};
};

struct CanTxAppImpl final : TxPort, Clock, ScheduleChangeSink {
  service::Service& runtime;
  const config::VehicleConfig& vehicle;
  Schedule schedule;  ///< the loop thread's view: checks and persistence
  Overlay overlay;
  std::deque<BusIo> buses;  // deque: stable addresses (atomics, the loop's callbacks)
  std::unique_ptr<Scheduler> scheduler;
  config::DiagnosticsConfig diagnostics;  ///< the network's DTC map (it keeps a reference)
  std::unique_ptr<Network> network;       ///< J1939 address claim, own DM1, TP sending (issue 24)
  std::int64_t lastNetworkPublishNs{};
  std::optional<TxThread> thread;
  std::optional<ScheduleCommands> commands;  ///< the schedule commands and overrides (loop thread)
  std::optional<service::PeriodicTimer> watchTimer;
  std::vector<WriterWatch> writers;  ///< per schedule.writers entry
  std::int64_t startNs{};
  std::uint64_t writersLost{};
  std::uint64_t seenDamage{};  ///< the table's damageCount() when can-tx last wrote its values

  explicit CanTxAppImpl(service::Service& service) : runtime(service), vehicle(service.config()) {}
  ~CanTxAppImpl() override {
    if (thread) thread->stop();  // before the links, streams and the scheduler it uses
    if (watchTimer) runtime.loop().removeFd(watchTimer->fd());
  }

  // ---- TxPort and Clock (transmit thread) -------------------------------------------------

  can::SendStatus send(std::size_t bus, const can::Frame& frame) noexcept override {
    BusIo& io = buses[bus];
    const can::SendStatus status = io.link->send(frame);
    if (status != can::SendStatus::Sent) return status;
    io.framesSent.fetch_add(1, std::memory_order_relaxed);
    ipc::FramePublisher& publisher = *io.sent;
    if (!publisher.hasSubscribers()) return status;
    std::optional<ipc::FrameLoan> maybeLoan = publisher.loan();
    if (!maybeLoan) {
      io.publishFailures.fetch_add(1, std::memory_order_relaxed);
      return status;
    }
    ipc::FrameSample& sample = maybeLoan->sample();
    sample.frame = frame;
    sample.monotonicNs = clock::monotonicNs();
    sample.hardwareNs = 0;
    sample.busIndex = static_cast<std::uint16_t>(bus);
    if (!publisher.publish(std::move(*maybeLoan))) io.publishFailures.fetch_add(1, std::memory_order_relaxed);
    return status;
  }

  std::int64_t monotonicNs() noexcept override { return clock::monotonicNs(); }
  std::int64_t realtimeNs() noexcept override {
    timespec now{};
    ::clock_gettime(CLOCK_REALTIME, &now);
    return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
  }

  // ---- start-up ---------------------------------------------------------------------------

  void fault(const std::string& name, ipc::FaultSeverity severity, bool active, const std::string& text) {
    runtime.events().publish(ipc::FaultEvent{0, name, runtime.program(), severity, active, text});
    const std::string line = std::string(active ? "fault raised: " : "fault cleared: ") + name + ": " + text;
    if (active) {
      runtime.log().error(line);
    } else {
      runtime.log().info(line);
    }
  }

  /// The overlay over the schedule; a bad overlay is set aside whole (never half applied).
  void loadOverlayOrSetAside() {
    auto overlayResult = loadOverlay(schedule.overlay);
    Result<Schedule> applied = overlayResult ? applyOverlay(schedule, *overlayResult, vehicle, runtime.catalog())
                                             : Result<Schedule>(overlayResult.error());
    if (applied) {
      schedule = std::move(*applied);
      overlay = std::move(*overlayResult);
      if (!overlay.empty()) runtime.log().info("runtime changes from " + schedule.overlay + " applied");
      return;
    }
    const std::string rejected = schedule.overlay + ".rejected";
    std::error_code renameError;
    std::filesystem::rename(schedule.overlay, rejected, renameError);
    fault("schedule_overlay_rejected", ipc::FaultSeverity::Warning, true,
          applied.error().message + "; ignored whole, moved to " + rejected +
              (renameError ? " (move failed: " + renameError.message() + ")" : ""));
  }

  void applyOverrides() {
    const std::int64_t now = clock::monotonicNs();
    for (const auto& [key, value] : overlay.overrides) {
      if (const auto index = runtime.catalog().indexOf(key)) {
        runtime.table().setOverride(*index, value, now, CAN_TX_WRITER);
        runtime.log().warning("override " + key + " = " + number(value) + " restored from " + schedule.overlay);
      }
    }
  }

  Status open() {
    auto scheduleResult = loadSchedule(vehicle, runtime.catalog());
    if (!scheduleResult) return scheduleResult.error();
    schedule = std::move(*scheduleResult);
    loadOverlayOrSetAside();
    applyOverrides();
    for (const std::string& warning : safetyIdentityWarnings(schedule, vehicle)) runtime.log().warning(warning);

    const std::string& instance = runtime.instance();
    for (const config::BusConfig& bus : vehicle.buses) {
      auto portsResult = service::openBusPorts(instance, bus, bus.linkOptions(), service::BusRole::Transmitter);
      if (!portsResult) return portsResult.error();
      static_cast<service::BusPorts&>(buses.emplace_back()) = std::move(*portsResult);
    }
    if (Status opened = openNetwork(); !opened) return opened.error();
    std::vector<std::uint32_t> sdms;
    for (const ScheduledMessage& entry : schedule.messages) {
      if (entry.safetyDeltaNs && entry.extended) sdms.push_back(entry.canId);
    }
    network->holdSafetyMessages(sdms);
    startNs = clock::monotonicNs();
    auto schedulerResult =
        Scheduler::create(vehicle, schedule, runtime.catalog(), runtime.table(), *network, *this, startNs);
    if (!schedulerResult) return schedulerResult.error();
    scheduler = std::move(*schedulerResult);
    commands.emplace(vehicle, runtime.catalog(), schedule, overlay, *scheduler, *this);

    for (std::size_t b = 0; b < buses.size(); ++b) {
      ipc::FrameSubscriber& sendRequests = *buses[b].sendRequestsIn;
      if (Status added = runtime.loop().addSubscriber(sendRequests, [this, b] { takeSendRequests(b); }); !added)
        return added.error();
      ipc::RequestSubscriber& requests = *buses[b].requestsIn;
      if (Status added = runtime.loop().addSubscriber(requests, [this, b] { takeRequests(b); }); !added)
        return added.error();
      ipc::FrameSubscriber& networkFrames = *buses[b].networkIn;
      if (Status added = runtime.loop().addSubscriber(networkFrames, [this, b] { takeNetworkFrames(b); }); !added)
        return added.error();
    }
    if (Status answering = runtime.answerCommands(commandPolicy()); !answering) return answering.error();

    seenDamage = runtime.table().damageCount();
    writers.clear();
    for (const WatchedWriter& writer : schedule.writers) writers.emplace_back(writer.timeoutNs, startNs, seenDamage);
    auto timerResult = service::PeriodicTimer::create(WATCH_PERIOD);
    if (!timerResult) return timerResult.error();
    watchTimer.emplace(std::move(*timerResult));
    if (Status added = runtime.loop().addTimer(*watchTimer,
                                               [this](const service::TimerTick&) {
                                                 watchWriters();
                                                 watchNetwork();
                                               });
        !added)
      return added.error();

    std::vector<can::Link*> links;
    for (BusIo& io : buses) links.push_back(io.link.get());
    thread.emplace(
        *scheduler, std::move(links),
        [this](std::size_t bus, const can::BusEvent& event) {
          // transmit thread: logging is thread-safe
          if (event.kind == can::BusEventKind::LinkUp || event.kind == can::BusEventKind::LinkDown ||
              event.kind == can::BusEventKind::BusOff || event.kind == can::BusEventKind::Restarted) {
            runtime.log().warning("bus " + vehicle.buses[bus].name + ": " + std::string(can::busEventName(event.kind)));
          }
        },
        network.get());
    registerCounters();
    if (const std::string warning = thread->start(schedule.realtimePriority, schedule.sdmSpinNs); !warning.empty()) {
      runtime.log().warning(warning);
    }
    runtime.log().info(std::to_string(schedule.messages.size()) + " messages scheduled" +
                       (schedule.file.empty() ? " (defaults: every message " + vehicle.node + " transmits)"
                                              : " from " + schedule.file));
    return {};
  }

  /// The J1939 network citizen: diagnostics.json (DTCs by FSM state name: the FSM file
  /// gives the order), the occurrence counts kept across restarts, the build version for SOFT.
  Status openNetwork() {
    std::vector<std::string> fsmStates;
    if (!vehicle.fsmFile.empty()) {
      auto machineResult = fsm::loadMachine(vehicle.fsmFile, vehicle, runtime.catalog());
      if (!machineResult) return machineResult.error();
      for (const fsm::State& state : machineResult->states) fsmStates.push_back(state.name);
    }
    auto diagnosticsResult = config::loadDiagnosticsConfig(vehicle, runtime.catalog(), &fsmStates);
    if (!diagnosticsResult) return diagnosticsResult.error();
    diagnostics = std::move(*diagnosticsResult);
    auto networkResult =
        Network::create(vehicle, diagnostics, fsmStates, runtime.catalog(), runtime.table(), *this, OPENVCU_VERSION);
    if (!networkResult) return networkResult.error();
    network = std::move(*networkResult);
    if (!diagnostics.dtcs.empty()) {
      config::DtcCountsLoad counts = config::loadDtcCounts(diagnostics.countsFile);
      if (counts.rejected) {
        fault("dtc_counts_rejected", ipc::FaultSeverity::Warning, true, counts.rejected->toString());
      }
      network->restoreCounts(counts.counts);
      runtime.log().info(std::to_string(diagnostics.dtcs.size()) + " DTCs from " + diagnostics.file + ", " +
                         std::to_string(counts.counts.size()) + " occurrence counts from " + diagnostics.countsFile);
    }
    return {};
  }

  /// Loop thread, every WATCH_PERIOD: the J1939 view at once after a change (else after
  /// every beat), the occurrence counts when they changed, the network's log lines.
  void watchNetwork() {
    if (!network->active()) return;
    for (const std::string& line : network->takeLog()) runtime.log().info(line);
    for (const AddressLoss& loss : network->takeAddressLosses()) {
      fault("j1939_address_lost." + loss.bus,
            loss.critical() ? ipc::FaultSeverity::Critical : ipc::FaultSeverity::Warning, true, loss.describe());
    }
    if (network->takeChanged()) publishNetwork();
    if (auto counts = network->takeCountsToSave()) {
      if (Status saved = config::saveDtcCounts(diagnostics.countsFile, *counts); !saved) {
        runtime.log().warning("DTC occurrence counts not saved: " + saved.error().toString());
      }
    }
  }

  void publishNetwork() {
    for (ipc::J1939Network& view : network->snapshot()) runtime.events().publish(view);
  }

  // ---- streams in (loop thread) -----------------------------------------------------------

  void takeNetworkFrames(std::size_t bus) {
    while (const auto maybeSample = buses[bus].networkIn->take()) {
      (void)thread->post(NetworkFrame{bus, maybeSample->frame});
    }
  }

  void takeSendRequests(std::size_t bus) {
    while (const auto maybeSample = buses[bus].sendRequestsIn->take()) {
      (void)thread->post(SendOnce{bus, maybeSample->frame});
    }
  }

  /// The requests can-rx parsed for this node (j1939::parseRequest); answered on the bus
  /// they came from.
  void takeRequests(std::size_t bus) {
    while (const auto maybeSample = buses[bus].requestsIn->take()) {
      const j1939::Request request{maybeSample->pgn, maybeSample->requester, maybeSample->global};
      (void)thread->post(AnswerRequest{bus, request});
    }
  }

  // ---- commands (loop thread) ---------------------------------------------------------------

  bool scheduledSignal(std::string_view key) const {
    return static_cast<bool>(findScheduledSignal(schedule, vehicle, runtime.catalog(), key));
  }

  service::CommandPolicy commandPolicy() {
    // The keys the catalog gives can-tx (shared/config/catalog.hpp): the signals this VCU
    // transmits, the send groups and its heartbeat.
    service::CommandPolicy policy = service::CommandPolicy::byOwner(runtime.catalog(), CAN_TX_WRITER);
    policy.veto = [this](const ipc::CommandRequest& request,
                         const signals::SignalInfo& info) -> std::optional<std::string> {
      if (auto refusal = service::statusRefusal(info)) return refusal;
      if (info.direction == signals::SignalDirection::Internal) return std::nullopt;  // a send group
      if (!scheduledSignal(info.key)) {
        return "'" + info.key + "' is not sent: its message " + info.message +
               " is not in the transmit schedule (vcu schedule add " + info.message + " MS)";
      }
      if (request.kind == ipc::CommandKind::SetSignal || request.kind == ipc::CommandKind::OperatorSwitch) {
        return "transmitted signals are commanded by the FSM; an operator sets an override (vcu signal set "
               "--override) or the schedule default (vcu schedule default)";
      }
      return commands->recordOverride(info.key, request.kind == ipc::CommandKind::SetOverride
                                                    ? std::optional<double>(request.value)
                                                    : std::nullopt);
    };
    policy.customKinds = {ipc::CommandKind::ScheduleCycle, ipc::CommandKind::ScheduleEnable,
                          ipc::CommandKind::ScheduleDefault, ipc::CommandKind::ScheduleAdd};
    policy.custom = [this](const ipc::CommandRequest& request) {
      auto refusal = commands->apply(request);
      if (!refusal) publishSchedule();  // watchers see the change at once, not at the next beat
      return refusal;
    };
    return policy;
  }

  // ---- ScheduleChangeSink (loop thread) ------------------------------------------------------

  bool post(TxCommand&& command) noexcept override { return thread->post(std::move(command)); }

  void added(std::size_t scheduled, const MessageStats& stats) override {
    registerMessageCounters(scheduled, stats);
    for (const std::string& warning : safetyIdentityWarnings(schedule, vehicle, scheduled)) {
      runtime.log().warning(warning);
    }
    const ScheduledMessage& message = schedule.messages[scheduled];
    runtime.log().info("message " + vehicle.database.messages[message.message].name +
                       " added to the transmit schedule, every " +
                       number(static_cast<double>(message.cycleNs) / NS_PER_MS) + " ms");
  }

  // ---- writer heartbeats (loop thread) ------------------------------------------------------

  void watchWriters() {
    const std::int64_t now = clock::monotonicNs();
    signals::SignalTable& table = runtime.table();
    for (std::size_t w = 0; w < schedule.writers.size(); ++w) {
      const WatchedWriter& writer = schedule.writers[w];
      const auto beat = table.readBus(writer.heartbeat);
      // The damage count after the read: a read that met the damage counts it.
      const WriterChange change = writers[w].update(beat, table.damageCount(), now);
      if (change == WriterChange::Lost) {
        ++writersLost;
        writeSafeValues(now);
        fault(faults::writerLost(writer.service), ipc::FaultSeverity::Critical, true,
              "no heartbeat from " + writer.service + " for " + std::to_string(writer.timeoutNs / NS_PER_MS) +
                  " ms: " + std::to_string(schedule.safeValues.size()) +
                  " safe values commanded; keep-alive and safety messages continue");
        runtime.setStatus("writer " + writer.service + " lost: safe values commanded");
      } else if (change == WriterChange::Back) {
        fault(faults::writerLost(writer.service), ipc::FaultSeverity::Critical, false,
              writer.service + " is back; the safe values stay until it commands otherwise");
        if (std::none_of(writers.begin(), writers.end(), [](const WriterWatch& watch) { return watch.lost(); })) {
          runtime.setStatus("ready");
        }
      }
    }
    if (const std::uint64_t damage = table.damageCount(); damage != seenDamage) {
      seenDamage = damage;
      restoreAfterDamage(now);
    }
  }

  void writeSafeValues(std::int64_t now) {
    for (const SafeValue& safe : schedule.safeValues) {
      runtime.table().writeCommand(safe.signal, safe.value, now, CAN_TX_WRITER);
    }
  }

  /// The table lost its values (docs/design/signal-table.md, "Damage"): writes again what
  /// only can-tx writes and nobody re-writes by itself: the overlay's overrides (every
  /// override can-tx answered is in it) and, while a writer is lost, the safe values. The
  /// bus plane of what it sends comes back with each message's next frame, its heartbeat
  /// with the next tick.
  void restoreAfterDamage(std::int64_t now) {
    for (const auto& [key, value] : overlay.overrides) {
      if (const auto index = runtime.catalog().indexOf(key))
        runtime.table().setOverride(*index, value, now, CAN_TX_WRITER);
    }
    const bool anyLost =
        std::any_of(writers.begin(), writers.end(), [](const WriterWatch& watch) { return watch.lost(); });
    if (anyLost) writeSafeValues(now);
    if (overlay.overrides.empty() && !anyLost) return;
    runtime.log().warning(
        "the signal table lost its values: " + std::to_string(overlay.overrides.size()) + " overrides" +
        (anyLost ? " and " + std::to_string(schedule.safeValues.size()) + " safe values" : "") + " written again");
  }

  // ---- heartbeat ----------------------------------------------------------------------------

  void registerCounters() {
    service::HeartbeatPublisher& heartbeat = runtime.heartbeat();
    heartbeat.addCounterSource("wakeups", [this] { return static_cast<std::int64_t>(thread->wakeups()); });
    heartbeat.addCounterSource("sdm_spins", [this] { return static_cast<std::int64_t>(thread->spins()); });
    heartbeat.addCounterSource("sdm_spin_us", [this] { return thread->spinNs() / 1000; });
    heartbeat.addCounterSource("sdm_guard_us", [this] { return thread->guardNs() / 1000; });
    heartbeat.addCounterSource("inbox_refused", [this] { return static_cast<std::int64_t>(thread->refusedPosts()); });
    heartbeat.addCounterSource("one_shots", [this] {
      return static_cast<std::int64_t>(scheduler->counters().oneShots.load(std::memory_order_relaxed));
    });
    heartbeat.addCounterSource("one_shot_failures", [this] {
      return static_cast<std::int64_t>(scheduler->counters().oneShotFailures.load(std::memory_order_relaxed));
    });
    heartbeat.addCounterSource("requests_answered", [this] {
      return static_cast<std::int64_t>(scheduler->counters().requestsAnswered.load(std::memory_order_relaxed));
    });
    heartbeat.addCounterSource("requests_nacked", [this] {
      return static_cast<std::int64_t>(scheduler->counters().requestsNacked.load(std::memory_order_relaxed));
    });
    heartbeat.addCounterSource("held_for_sdm", [this] {
      return static_cast<std::int64_t>(scheduler->counters().held.load(std::memory_order_relaxed));
    });
    heartbeat.addCounterSource("sdms_early", [this] {
      return static_cast<std::int64_t>(scheduler->counters().sdmsEarly.load(std::memory_order_relaxed));
    });
    heartbeat.addCounterSource("writers_lost", [this] { return static_cast<std::int64_t>(writersLost); });
    if (network->active()) {
      auto add = [&](const std::string& name, std::atomic<std::uint64_t> NetworkCounters::*member) {
        heartbeat.addCounterSource(name, [this, member] {
          return static_cast<std::int64_t>((network->counters().*member).load(std::memory_order_relaxed));
        });
      };
      add("j1939_claims_sent", &NetworkCounters::claimsSent);
      add("j1939_contests_won", &NetworkCounters::contestsWon);
      add("j1939_contests_lost", &NetworkCounters::contestsLost);
      add("j1939_cannot_claim", &NetworkCounters::cannotClaim);
      add("j1939_frames_held_by_claim", &NetworkCounters::framesHeldByClaim);
      add("dm1_sent", &NetworkCounters::dm1Sent);
      add("tp_started", &NetworkCounters::tpStarted);
      add("tp_completed", &NetworkCounters::tpCompleted);
      add("tp_failed", &NetworkCounters::tpFailed);
      add("tp_refused", &NetworkCounters::tpRefused);
      add("j1939_requests_answered", &NetworkCounters::requestsAnswered);
      add("dtc_clears_accepted", &NetworkCounters::clearsAccepted);
      add("dtc_clears_refused", &NetworkCounters::clearsRefused);
      add("j1939_addresses_lost", &NetworkCounters::addressesLost);
      add("j1939_safety_frames_held", &NetworkCounters::safetyFramesHeld);
    }
    for (std::size_t b = 0; b < buses.size(); ++b) {
      const std::string prefix = vehicle.buses[b].name + ".";
      heartbeat.addStatSource(prefix + "frames_sent", [this, b] {
        return static_cast<std::int64_t>(buses[b].framesSent.load(std::memory_order_relaxed));
      });
      heartbeat.addStatSource(prefix + "send_failures",
                              [this, b] { return static_cast<std::int64_t>(buses[b].link->stats().sendFailures); });
      heartbeat.addStatSource(prefix + "publish_failures", [this, b] {
        return static_cast<std::int64_t>(buses[b].publishFailures.load(std::memory_order_relaxed));
      });
    }
    for (std::size_t s = 0; s < schedule.messages.size(); ++s) registerMessageCounters(s, scheduler->stats(s));
    heartbeat.addBeatListener([this] {
      publishSchedule();
      if (network->active()) publishNetwork();
    });
  }

  /// The live schedule (cycle, enabled, added per message) on the SCHEDULE channel, which
  /// the HMI's ECU Setup shows: after every beat and after every accepted schedule command.
  void publishSchedule() {
    ipc::TxSchedule live{.service = runtime.program(),
                         .instance = runtime.config().instance,
                         .pid = static_cast<std::int32_t>(::getpid()),
                         .entries = {}};
    live.entries.reserve(schedule.messages.size());
    for (const ScheduledMessage& entry : schedule.messages) {
      live.entries.push_back(ipc::ScheduleEntry{vehicle.database.messages[entry.message].name, entry.cycleNs / 1000,
                                                entry.enabled, entry.added});
    }
    runtime.events().publish(live);
  }

  /// tx.<Msg>.*: the message's statistics on the STATS channel.
  void registerMessageCounters(std::size_t s, const MessageStats& stats) {
    service::HeartbeatPublisher& heartbeat = runtime.heartbeat();
    const std::string prefix = "tx." + vehicle.database.messages[schedule.messages[s].message].name + ".";
    auto add = [&](const std::string& name, auto read) {
      heartbeat.addStatSource(prefix + name, [&stats, read] { return static_cast<std::int64_t>(read(stats)); });
    };
    add("frames", [](const MessageStats& m) { return m.frames.load(std::memory_order_relaxed); });
    add("missed", [](const MessageStats& m) { return m.missed.load(std::memory_order_relaxed); });
    add("send_failures", [](const MessageStats& m) { return m.sendFailures.load(std::memory_order_relaxed); });
    add("encode_errors", [](const MessageStats& m) { return m.encodeErrors.load(std::memory_order_relaxed); });
    add("period_err_p50_us", [](const MessageStats& m) { return m.periodError.summary().p50Us; });
    add("period_err_p99_us", [](const MessageStats& m) { return m.periodError.summary().p99Us; });
    add("period_err_max_us", [](const MessageStats& m) { return m.periodError.summary().maxUs; });
    if (schedule.messages[s].safetyDeltaNs) {
      add("delta_err_p50_us", [](const MessageStats& m) { return m.deltaError.summary().p50Us; });
      add("delta_err_p99_us", [](const MessageStats& m) { return m.deltaError.summary().p99Us; });
      add("delta_err_max_us", [](const MessageStats& m) { return m.deltaError.summary().maxUs; });
    }
  }
};

}  // namespace openvcu::cantx

template class openvcu::service::App<openvcu::cantx::CanTxAppImpl>;
