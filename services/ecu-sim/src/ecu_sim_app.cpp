#include "ecu_sim_app.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <ctime>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "frame_faults.hpp"
#include "generic_model.hpp"
#include "j1939_peer.hpp"
#include "openvcu/can_links/open_link.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/service/app_impl.hpp"
#include "vehicle_model.hpp"

namespace openvcu::ecusim {
namespace {

/// How long a fault request waits for the simulation thread to apply it.
constexpr std::chrono::seconds APPLY_TIMEOUT{1};

/// A fault request on its way from the command handler (loop thread) to the simulation
/// thread, and its outcome back.
struct PendingFault {
  std::string name;  ///< the key as asked
  bool on{};
  std::optional<FrameFaultRequest> frame;  ///< a frame fault; else a model fault
  std::vector<FrameTarget> targets;
  bool done{};
  std::optional<std::string> refusal;
};

}  // namespace

struct EcuSimAppImpl {
  service::Service& runtime;
  config::SimConfig config;
  std::optional<VirtualBus> bus;
  std::optional<VehicleModel> model;    ///< "model": "hhea"
  std::optional<GenericModel> generic;  ///< "model": "generic"
  std::optional<J1939Peer> peer;        ///< "j1939Peer"
  std::optional<FrameFaults> faults;    ///< `vcu inject` frame faults on what the nodes send
  std::vector<std::unique_ptr<can::Link>> links;
  std::optional<signals::SignalIndex> wakeIndex;
  std::thread thread;
  std::atomic<bool> stopping{false};
  // fault requests from the command handler (loop thread) to the simulation thread; the
  // simulation thread sleeps on `simWake` (CLOCK_MONOTONIC deadlines) so a request is applied
  // at once, and reports on `applied`
  std::mutex requestsMutex;
  std::condition_variable simWake;
  std::condition_variable applied;
  std::vector<std::shared_ptr<PendingFault>> requests;
  std::vector<std::shared_ptr<PendingFault>> finished;  ///< applied this iteration (simulation thread)
  // heartbeat mirrors
  std::atomic<std::int64_t> sent{}, received{}, sendFailures{}, awake{}, connection{}, socTenths{}, pairsOk{},
      pairsRefused{}, timeRequests{}, timeAnswers{}, timeErrors{}, sohAnswers{}, faultsActive{};
  std::uint64_t refusedLogged{};  ///< VIC refusals already logged (simulation thread)

  explicit EcuSimAppImpl(service::Service& service) : runtime(service) {}
  ~EcuSimAppImpl() {
    {
      std::lock_guard lock(requestsMutex);
      stopping.store(true);
    }
    simWake.notify_all();
    if (thread.joinable()) thread.join();
  }

  Status open() {
    const config::VehicleConfig& vehicle = runtime.config();
    auto configResult = config::loadSimConfig(vehicle.simulationFile, vehicle);
    if (!configResult) return configResult.error();
    config = std::move(*configResult);
    auto busResult = VirtualBus::create(vehicle);
    if (!busResult) return busResult.error();
    bus.emplace(std::move(*busResult));
    if (config.model == config::SimModel::Hhea) {
      auto modelResult = VehicleModel::create(*bus, config);
      if (!modelResult) return modelResult.error();
      model.emplace(std::move(*modelResult));
    } else {
      auto modelResult = GenericModel::create(*bus, config);
      if (!modelResult) return modelResult.error();
      generic.emplace(std::move(*modelResult));
    }
    if (config.peer) peer.emplace(*config.peer, runtime.log());
    std::vector<FaultBus> faultBuses;
    for (const config::BusConfig& busConfig : vehicle.buses) {
      faultBuses.push_back(
          FaultBus{busConfig.name, busConfig.bitrate, busConfig.dataBitrate,
                   busConfig.j1939 ? std::optional<j1939::Name>(busConfig.j1939->name) : std::nullopt});
    }
    faults.emplace(std::move(faultBuses));
    if (!config.wakeSignal.empty()) {
      wakeIndex = runtime.catalog().indexOf(config.wakeSignal);
      if (!wakeIndex) return Error{config.file + ": /wakeSignal: no signal '" + config.wakeSignal + "' in the catalog"};
    }
    for (const config::BusConfig& busConfig : vehicle.buses) {
      auto link = can::openLink(busConfig.link.kind, busConfig.link.target, busConfig.linkOptions());
      if (!link) return Error{"bus " + busConfig.name + ": " + link.error().message};
      links.push_back(std::move(*link));
    }
    service::CommandPolicy policy;
    policy.owns = [](std::string_view) { return false; };
    policy.customKinds = {ipc::CommandKind::SimFault};
    policy.custom = [this](const ipc::CommandRequest& request) { return request_(request); };
    if (Status answering = runtime.answerCommands(std::move(policy)); !answering) return answering.error();
    registerCounters();
    std::string what = "simulating " + std::to_string(bus->nodes().size()) + " nodes on " +
                       std::to_string(links.size()) + " bus(es), model " +
                       std::string(config::simModelName(config.model));
    if (model) what += "; SOC " + std::to_string(static_cast<int>(config.initialSoc)) + " %";
    if (generic) {
      const config::SimRules& rules = config.rules;
      what += " (" + std::to_string(rules.rules.size()) + " rules, " + std::to_string(rules.follow.size()) +
              " follow, " + std::to_string(rules.integrate.size()) + " integrate, " +
              std::to_string(rules.faults.size()) + " faults, " + std::to_string(config.safety.size()) + " pairs)";
    }
    runtime.log().info(what);
    thread = std::thread([this] { run(); });
    return {};
  }

  /// A fault request: checked here, applied by the simulation thread, which is woken for it;
  /// answered once applied (so the fault is in effect when the issuer hears "accepted"), or
  /// refused when the simulation thread did not take it within APPLY_TIMEOUT.
  std::optional<std::string> request_(const ipc::CommandRequest& request) {
    auto pending = std::make_shared<PendingFault>();
    pending->name = request.key;
    pending->on = request.value != 0;
    if (auto frameResult = parseFrameFault(request.key, pending->on)) {
      if (!*frameResult) return frameResult->error().message;
      FrameFaultRequest& frame = **frameResult;
      if (frame.kind != FrameFaultKind::Claim && frame.kind != FrameFaultKind::Babble &&
          frame.kind != FrameFaultKind::BusOff) {
        pending->targets = bus->transmitted(frame.target);
        if (pending->targets.empty()) {
          std::string known;
          for (const std::string& node : bus->nodes()) known += (known.empty() ? "" : ", ") + node;
          return "no DBC message or simulated node '" + frame.target + "' (nodes: " + known + ")";
        }
      }
      pending->frame = std::move(frame);
    } else if (model ? !faultByName(request.key) : !generic->faultIndex(request.key)) {
      std::string known;
      for (std::size_t i = 0; model && i < FAULT_COUNT; ++i)
        known += std::string(faultName(static_cast<Fault>(i))) + ", ";
      for (std::size_t i = 0; generic && i < generic->faultCount(); ++i) known += generic->faultName(i) + ", ";
      return "unknown fault '" + request.key + "' (faults: " + known +
             "silent.<node> or silent.<message>; frame faults delay, corrupt, replay, spoof, claim, babble, "
             "busoff: `vcu inject --help`)";
    }
    std::unique_lock lock(requestsMutex);
    requests.push_back(pending);
    simWake.notify_all();
    if (!applied.wait_for(lock, APPLY_TIMEOUT, [&] { return pending->done; })) {
      std::erase(requests, pending);  // never applied later
      return "the simulation thread did not take the fault within 1 s";
    }
    return pending->refusal;
  }

  /// Applies the waiting requests (simulation thread); their answers go out with
  /// finishRequests(), after this iteration's frames were sent.
  void applyRequests(std::int64_t nowNs) {
    std::lock_guard lock(requestsMutex);
    for (const std::shared_ptr<PendingFault>& pending : requests) {
      const std::string& name = pending->name;
      const bool on = pending->on;
      if (pending->frame) {
        pending->refusal = faults->apply(*pending->frame, on, pending->targets, nowNs);
      } else if (const auto fault = faultByName(name); fault && model) {
        model->setFault(*fault, on);
      } else if (const auto index = generic ? generic->faultIndex(name) : std::nullopt) {
        generic->setFault(*index, on);
      }
      finished.push_back(pending);
      if (pending->refusal) continue;
      const std::string eventName = pending->frame ? pending->frame->name() : name;
      const std::string text = std::string("injected fault ") + name + (on ? " on" : " off") + " at monotonic " +
                               std::to_string(nowNs) + " ns";
      runtime.log().warning(text);
      ipc::FaultEvent event;
      event.timestampNs = clock::realtimeNs();
      event.name = "sim." + eventName;
      event.source = runtime.program();
      event.severity = ipc::FaultSeverity::Warning;
      event.active = on;
      event.text = text;
      runtime.events().publish(event);
    }
    requests.clear();
  }

  /// Answers the requests applied in this iteration.
  void finishRequests() {
    if (finished.empty()) return;
    {
      std::lock_guard lock(requestsMutex);
      for (const std::shared_ptr<PendingFault>& pending : finished) pending->done = true;
    }
    finished.clear();
    applied.notify_all();
  }

  /// Sleeps until `monotonicNs` or a fault request, whichever comes first.
  void sleepUntil(std::int64_t monotonicNs) {
    std::unique_lock lock(requestsMutex);
    const std::chrono::steady_clock::time_point until{std::chrono::nanoseconds(monotonicNs)};
    simWake.wait_until(lock, until, [this] { return !requests.empty() || stopping.load(std::memory_order_relaxed); });
  }

  void run() {
    std::array<can::ReceivedFrame, 64> batch{};
    const auto wire = [this](std::size_t busIndex, const can::Frame& frame) {
      if (links[busIndex]->send(frame) != can::SendStatus::Sent) sendFailures.fetch_add(1, std::memory_order_relaxed);
    };
    std::int64_t now = clock::monotonicNs();
    // every frame of the nodes passes the frame faults on its way to the link
    const auto send = [this, &wire, &now](std::size_t busIndex, const can::Frame& frame) {
      faults->send(busIndex, frame, now, wire);
    };
    std::int64_t nextTick = now;
    bus->start(nextTick);
    if (peer) peer->start(nextTick);
    while (!stopping.load(std::memory_order_relaxed)) {
      now = clock::monotonicNs();
      for (auto& link : links) {
        const std::size_t busIndex = static_cast<std::size_t>(&link - links.data());
        std::size_t count = 0;
        while ((count = link->receive(batch)) > 0) {
          if (faults->cut(busIndex)) {  // a bus off: the nodes hear nothing of the VCU
            faults->dropped.fetch_add(static_cast<std::int64_t>(count), std::memory_order_relaxed);
            if (count < batch.size()) break;
            continue;
          }
          for (std::size_t i = 0; i < count; ++i) {
            receive(batch[i].frame, batch[i].monotonicNs);
            if (peer) peer->receive(busIndex, batch[i].frame, batch[i].monotonicNs);
          }
          if (count < batch.size()) break;
        }
      }
      applyRequests(now);
      if (now >= nextTick) {
        bool wake = true;
        if (wakeIndex) {
          const auto level = runtime.table().readBus(*wakeIndex);
          wake = level && level->updates > 0 && level->value >= 0.5;
        }
        if (model) {
          model->step(now, clock::realtimeNs(), wake, send);
          reportSafety(model->takeSafetyChange(), model->safety(), "sim.vic_safety", "the simulated VIC");
        } else {
          generic->step(now);
          reportSafety(generic->takeSafetyChange(), generic->safety(), "sim.safety_pairs", "the simulator");
        }
        nextTick += ((now - nextTick) / config.tickNs + 1) * config.tickNs;
      }
      if (model) {
        model->sendDue(now, send);
      } else {
        bus->sendDue(now, send);
      }
      if (peer) peer->step(now, send);
      faults->step(now, wire);
      finishRequests();
      mirror();
      sleepUntil(std::min({nextTick, bus->nextDueNs(), peer ? peer->nextDueNs() : NEVER, faults->nextDueNs()}));
    }
  }

  void receive(const can::Frame& frame, std::int64_t atNs) noexcept {
    if (model) {
      model->receive(frame, atNs);
    } else {
      generic->receive(frame, atNs);
    }
  }

  /// One fault event per change of the pair verdict (`name`), and a log line for refusals
  /// that were no change (`who` refused them).
  void reportSafety(std::optional<j1939::SafetyResult> change, const SafetyStats& stats, const char* name,
                    const char* who) {
    // A refusal followed by a good pair within one tick is no change any more by the time it
    // is looked at: the count says it happened, and why.
    if (const std::uint64_t refused = stats.refused; refused != refusedLogged) {
      if (!change || *change == j1939::SafetyResult::Ok) {
        runtime.log().error(std::string(who) + " refused " + std::to_string(refused - refusedLogged) +
                            " J1939-76 pair(s) since its last report, the last for " +
                            std::string(j1939::safetyResultName(stats.lastRefusal)));
      }
      refusedLogged = refused;
    }
    if (!change) return;
    const bool ok = *change == j1939::SafetyResult::Ok;
    ipc::FaultEvent event;
    event.timestampNs = clock::realtimeNs();
    event.name = name;
    event.source = runtime.program();
    event.severity = ipc::FaultSeverity::Error;
    event.active = !ok;
    event.text =
        ok ? std::string(who) + " accepts the VCU's J1939-76 pairs again"
           : std::string(who) + " refuses the VCU's J1939-76 pairs: " + std::string(j1939::safetyResultName(*change));
    runtime.events().publish(event);
    if (ok) {
      runtime.log().info(event.text);
    } else {
      runtime.log().error(event.text);
    }
  }

  void mirror() {
    const auto put = [](std::atomic<std::int64_t>& target, std::int64_t value) {
      target.store(value, std::memory_order_relaxed);
    };
    put(sent, static_cast<std::int64_t>(bus->framesSent()));
    put(received, static_cast<std::int64_t>(bus->framesReceived()));
    if (generic) {
      put(pairsOk, static_cast<std::int64_t>(generic->safety().ok));
      put(pairsRefused, static_cast<std::int64_t>(generic->safety().refused));
      std::int64_t mask = 0;
      for (std::size_t i = 0; i < generic->faultCount() && i < 63; ++i) {
        if (generic->fault(i)) mask |= std::int64_t{1} << i;
      }
      put(faultsActive, mask);
      return;
    }
    put(awake, model->awake() ? 1 : 0);
    put(connection, model->connection());
    put(socTenths, static_cast<std::int64_t>(model->soc() * 10));
    put(pairsOk, static_cast<std::int64_t>(model->safety().ok));
    put(pairsRefused, static_cast<std::int64_t>(model->safety().refused));
    put(timeRequests, static_cast<std::int64_t>(model->timeRequests()));
    put(timeAnswers, static_cast<std::int64_t>(model->timeAnswers()));
    put(timeErrors, static_cast<std::int64_t>(model->timeAnswerErrors()));
    put(sohAnswers, static_cast<std::int64_t>(model->sohAnswers()));
    std::int64_t mask = 0;
    for (std::size_t i = 0; i < FAULT_COUNT; ++i) {
      if (model->fault(static_cast<Fault>(i))) mask |= std::int64_t{1} << i;
    }
    put(faultsActive, mask);
  }

  /// The scripted peer's counters (services/ecu-sim/README.md, "The scripted J1939 peer").
  void registerPeerCounters() {
    const auto add = [this](std::string name, std::atomic<std::int64_t>& value) {
      runtime.heartbeat().addCounterSource(std::move(name), [&value] { return value.load(std::memory_order_relaxed); });
    };
    add("peer_claims_seen", peer->claimsSeen);
    add("peer_vcu_address", peer->vcuAddress);
    add("peer_address", peer->ownAddress);
    add("peer_requests_sent", peer->requestsSent);
    add("peer_tp_completed", peer->tpCompleted);
    add("peer_dm1_dtcs", peer->dm1Dtcs);
    add("peer_acknowledgements", peer->nacks);
    const std::vector<std::uint32_t>& pgns = peer->config().requestedPgns;
    for (std::size_t i = 0; i < pgns.size(); ++i) add("peer_answers." + std::to_string(pgns[i]), peer->answers(i));
  }

  void registerCounters() {
    const auto add = [this](const char* name, std::atomic<std::int64_t>& value) {
      runtime.heartbeat().addCounterSource(name, [&value] { return value.load(std::memory_order_relaxed); });
    };
    add("frames_sent", sent);
    add("frames_received", received);
    add("send_failures", sendFailures);
    add("inject_dropped", faults->dropped);
    add("inject_delayed", faults->delayed);
    add("inject_corrupted", faults->corrupted);
    add("inject_replayed", faults->replayed);
    add("inject_spoofed", faults->spoofed);
    add("inject_claims", faults->claims);
    add("inject_babble_frames", faults->babbleFrames);
    if (peer) registerPeerCounters();
    if (generic) {
      add("faults_active", faultsActive);  // bit i: the file's fault i (file order)
      if (generic->checksPairs()) {
        add("vic_pairs_ok", pairsOk);
        add("vic_pairs_refused", pairsRefused);
      }
      return;
    }
    add("vic_awake", awake);
    add("vic_connection", connection);
    add("soc_tenths", socTenths);
    add("vic_pairs_ok", pairsOk);
    add("vic_pairs_refused", pairsRefused);
    add("time_requests", timeRequests);
    add("time_answers", timeAnswers);
    add("time_answer_errors", timeErrors);
    add("soh_answers", sohAnswers);
    add("faults_active", faultsActive);
  }
};

}  // namespace openvcu::ecusim

template class openvcu::service::App<openvcu::ecusim::EcuSimAppImpl>;
