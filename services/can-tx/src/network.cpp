#include "network.hpp"

#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cstdio>

#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/address_claim.hpp"
#include "openvcu/j1939/diagnostic_state.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/dm_encode.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/j1939/transport.hpp"
#include "openvcu/j1939/transport_sender.hpp"

namespace openvcu::cantx {

namespace {

constexpr std::int64_t MS = 1'000'000;
/// The DTC conditions are read at the first run() this long after the last reading (at the
/// latest half of it later: the transmit thread wakes for them only when nothing else woke it).
constexpr std::int64_t DTC_EVALUATION_NS = 100 * MS;
/// After a missed try-lock of the view, the next attempt (never a busy retry).
constexpr std::int64_t VIEW_RETRY_NS = 10 * MS;
constexpr std::uint8_t DM_PRIORITY = 6;  ///< J1939-73 default priority of DM1/DM2
/// RTS byte 4: at most 8 packets per CTS window, so a window fits a CAN controller's
/// transmit queue (SocketCAN's default txqueuelen is 10) when it goes out back to back.
constexpr std::uint8_t TP_WINDOW = 8;

std::string hexByte(std::uint8_t value) {
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "0x%02X", value);
  return buffer;
}

/// A NAME as 16 hex digits: "0x3002800000000001".
std::string hexName(std::uint64_t value) {
  char buffer[24];
  std::snprintf(buffer, sizeof buffer, "0x%016llX", static_cast<unsigned long long>(value));
  return buffer;
}

/// A DM1's lamp byte (byte 0): protect bits 1-0, amber 3-2, red 5-4, malfunction 7-6.
std::uint8_t lampByte(const j1939::LampStates& lamps) noexcept {
  return static_cast<std::uint8_t>(
      (static_cast<unsigned>(lamps.malfunction) << 6) | (static_cast<unsigned>(lamps.redStop) << 4) |
      (static_cast<unsigned>(lamps.amberWarning) << 2) | static_cast<unsigned>(lamps.protect));
}

ipc::ClaimState toIpc(j1939::ClaimState state) noexcept {
  switch (state) {
    case j1939::ClaimState::Idle:
      return ipc::ClaimState::Off;
    case j1939::ClaimState::Claiming:
      return ipc::ClaimState::Claiming;
    case j1939::ClaimState::Claimed:
      return ipc::ClaimState::Claimed;
    case j1939::ClaimState::CannotClaim:
      return ipc::ClaimState::CannotClaim;
  }
  return ipc::ClaimState::Off;
}

}  // namespace

/// One DTC's condition, resolved against the catalog.
struct DtcCondition {
  const config::DtcConfig* config{};
  signals::SignalIndex index{};  ///< the signal read (internal.fsm.state for FsmState)
  double fsmStateIndex{-1};      ///< FsmState: the state's position in the FSM file
};

/// One bus with a J1939 address.
struct NetworkBus final : j1939::ClaimSink, j1939::TpSendSink {
  NetworkImpl* owner{};
  std::size_t bus{};
  std::string name;
  std::optional<j1939::AddressClaimer> claimer;  ///< empty: the bus claims nothing (fixed address)
  std::unique_ptr<j1939::TpSender> tp;
  std::uint8_t preferred{j1939::NULL_ADDRESS};
  std::uint64_t nameValue{};
  bool fd{};  ///< a CAN FD bus carries up to 64 bytes in one frame; a classic one needs TP above 8

  // A lost address: addressLost() notes it, the addressChanged() that follows publishes it
  // (transmit thread) under a sequence lock the loop thread reads (takeAddressLosses()).
  bool lossPending{};
  std::uint8_t pendingLostAddress{};
  std::uint64_t pendingClaimant{};
  std::atomic<std::uint32_t> lossSequence{};  ///< odd while the fields below are written
  std::atomic<std::uint64_t> lostClaimant{};
  std::atomic<std::uint32_t> lostOutcome{};  ///< lost address | new address << 8 | safety held << 16
  std::uint32_t lossesTaken{};               ///< loop thread: lossSequence at the last take

  [[nodiscard]] std::uint8_t address() const noexcept { return claimer ? claimer->address() : preferred; }
  [[nodiscard]] bool mayTransmit() const noexcept { return !claimer || claimer->mayTransmit(); }

  void send(const j1939::ClaimFrame& frame) noexcept override;
  void addressChanged(std::uint8_t oldAddress, std::uint8_t newAddress, j1939::ClaimState state) noexcept override;
  void addressLost(std::uint8_t address, const j1939::Name& claimant) noexcept override;
  void send(const j1939::TpFrame& frame) noexcept override;
  void finished(const j1939::TpSendResult& result) noexcept override;
};

struct NetworkImpl {
  TxPort& out;
  signals::SignalTable& table;
  std::vector<std::unique_ptr<NetworkBus>> buses;
  std::vector<std::int32_t> busSlot;  ///< config bus index -> index into buses, or -1
  const config::DiagnosticsConfig& diagnostics;
  std::optional<j1939::DiagnosticState> dtcs;
  std::vector<DtcCondition> conditions;
  std::vector<std::uint8_t> activeScratch;  ///< bool per DTC, reused by evaluate()
  std::int64_t nextEvaluationNs{};
  std::int64_t callNs{};                               ///< the time of the call in progress (the claim sink has none)
  std::vector<std::uint8_t> software, ecu, component;  ///< identification payloads, built once
  std::array<std::uint8_t, j1939::DM1_MAX_LENGTH> dmScratch{};
  NetworkCounters counters;
  std::vector<std::uint32_t> safetySdms;  ///< sorted 29-bit CAN IDs of the schedule's SDMs

  /// An SHM, or an SDM of the schedule (both from the preferred address).
  [[nodiscard]] bool isSafetyFrame(const can::Frame& frame) const noexcept {
    if (!frame.extended()) return false;
    const std::uint32_t id = frame.id & 0x1FFFFFFFu;
    if (j1939::Id::fromCanId(id).pgn() == j1939::PGN_SAFETY_HEADER) return true;
    return std::binary_search(safetySdms.begin(), safetySdms.end(), id);
  }

  mutable std::mutex viewLock;  ///< guards the members below (the transmit thread try-locks)
  std::vector<ipc::J1939Network> view;
  bool viewChanged{true};
  bool viewDirty{true};        ///< the transmit thread has something newer than `view`
  std::int64_t viewRetryNs{};  ///< a missed try-lock (or no memory): publishView() again then
  bool countsDirty{};
  std::vector<j1939::Dtc> countsToSave;
  std::vector<std::string> log;  ///< reserved at create(); the transmit thread appends while it has room
  std::string version;

  NetworkImpl(TxPort& port, signals::SignalTable& signalTable, const config::DiagnosticsConfig& diagnosticsConfig)
      : out(port), table(signalTable), diagnostics(diagnosticsConfig) {}

  NetworkBus* busOf(std::size_t bus) noexcept {
    if (bus >= busSlot.size() || busSlot[bus] < 0) return nullptr;
    return buses[static_cast<std::size_t>(busSlot[bus])].get();
  }

  void sendRaw(std::size_t bus, std::uint32_t canId, std::span<const std::uint8_t> data) noexcept {
    can::Frame frame;
    frame.id = canId;
    frame.flags = can::FLAG_EXTENDED;
    frame.length = static_cast<std::uint8_t>(std::min<std::size_t>(data.size(), 8));
    std::copy_n(data.begin(), frame.length, frame.data.begin());
    (void)out.send(bus, frame);
  }

  /// A PDU2 message of any length from `bus`'s address: one frame up to 8 bytes (padded
  /// with FF; PDU2 has no destination address, so it goes to all), else TP: BAM to global,
  /// RTS/CTS to `destination`. false when nothing left: no address, or TP refused it.
  bool sendMessage(NetworkBus& bus, std::uint32_t pgn, std::uint8_t priority, std::span<const std::uint8_t> data,
                   std::uint8_t destination, std::int64_t nowNs) noexcept {
    if (!bus.mayTransmit() || bus.address() >= j1939::NULL_ADDRESS) return false;
    if (data.size() <= 8) {
      std::array<std::uint8_t, 8> padded{};
      padded.fill(0xFF);
      std::copy(data.begin(), data.end(), padded.begin());
      sendRaw(bus.bus, j1939::Id::fromPgn(pgn, priority, bus.address(), destination).toCanId(), padded);
      return true;
    }
    const j1939::TpSendStatus status = bus.tp->send(pgn, destination, j1939::TP_CM_PRIORITY, data, nowNs, bus);
    if (status == j1939::TpSendStatus::Started || status == j1939::TpSendStatus::Queued) {
      counters.tpStarted.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    counters.tpRefused.fetch_add(1, std::memory_order_relaxed);
    return false;
  }

  void acknowledge(NetworkBus& bus, j1939::AckControl control, const j1939::Request& request) noexcept {
    if (!bus.mayTransmit() || bus.address() >= j1939::NULL_ADDRESS) return;
    const j1939::AcknowledgementPayload payload = j1939::encodeAcknowledgement(
        j1939::Acknowledgement{control, j1939::GROUP_FUNCTION_NOT_APPLICABLE, request.requester, request.pgn});
    sendRaw(bus.bus, j1939::acknowledgementCanId(j1939::ACKNOWLEDGEMENT_DEFAULT_PRIORITY, bus.address()), payload);
  }

  // ---- diagnostics ------------------------------------------------------------------------

  /// Reads each DTC's condition: the effective command of an internal signal, else its bus
  /// value; a signal never written is inactive.
  void evaluate(std::int64_t nowNs) noexcept {
    if (!dtcs) return;
    for (std::size_t i = 0; i < conditions.size(); ++i) {
      const DtcCondition& condition = conditions[i];
      const auto snapshot = table.read(condition.index);
      if (!snapshot) continue;  // a write in progress: keep the previous state
      std::optional<double> value;
      if (const auto command = signals::effectiveCommand(*snapshot)) {
        value = command->value;
      } else if (snapshot->bus.updates > 0) {
        value = snapshot->bus.value;
      }
      bool active = false;
      if (value) {
        active = condition.config->source == config::DtcSource::FsmState ? *value == condition.fsmStateIndex
                                                                         : condition.config->activeFor(*value);
      }
      activeScratch[i] = active ? 1 : 0;
    }
    std::array<bool, j1939::DM1_MAX_DTCS> flags{};
    for (std::size_t i = 0; i < activeScratch.size() && i < flags.size(); ++i) flags[i] = activeScratch[i] != 0;
    if (dtcs->update(std::span<const bool>(flags.data(), activeScratch.size()), nowNs)) markChanged(true);
    nextEvaluationNs = nowNs + DTC_EVALUATION_NS;
  }

  void sendDm1(std::int64_t nowNs, std::optional<std::size_t> onlyBus = std::nullopt,
               std::uint8_t destination = j1939::GLOBAL_ADDRESS) noexcept {
    const std::size_t length = dtcs->encodeDm1(dmScratch);
    for (auto& bus : buses) {
      if (onlyBus && bus->bus != *onlyBus) continue;
      // counted per bus it left on: a bus without an address (Cannot Claim) sends none
      if (sendMessage(*bus, j1939::PGN_DM1, DM_PRIORITY, std::span<const std::uint8_t>(dmScratch.data(), length),
                      destination, nowNs)) {
        counters.dm1Sent.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }

  // ---- the view for OPENVCU_<I>_J1939 ------------------------------------------------------

  void markChanged(bool counts) noexcept {
    viewDirty = true;
    if (counts) countsDirty = true;
  }

  /// Copies the state into `view` when the loop thread does not hold the lock; else later.
  /// Runs only after a change (a claim, a DTC, a clear), never per frame; the DTC names it
  /// copies may allocate.
  void publishView() noexcept {
    if (!viewDirty) return;
    viewRetryNs = callNs + VIEW_RETRY_NS;
    std::unique_lock lock(viewLock, std::try_to_lock);
    if (!lock.owns_lock()) return;
    try {
      std::size_t slot = 0;
      for (const auto& bus : buses) {
        ipc::J1939Network& entry = view[slot++];
        entry.claimState = bus->claimer ? toIpc(bus->claimer->state()) : ipc::ClaimState::Off;
        entry.address = bus->address();
        entry.name = bus->nameValue;
        entry.nodes.clear();
        if (bus->claimer) {
          for (const j1939::AddressEntry node : bus->claimer->table()) {
            entry.nodes.push_back(ipc::J1939Node{node.address, node.name.toValue()});
          }
        }
        entry.dtcs.clear();
        if (dtcs) {
          for (std::size_t i = 0; i < dtcs->definitions().size(); ++i) {
            const std::uint8_t count = dtcs->counts()[i];
            if (!dtcs->active(i) && count == 0) continue;
            const j1939::DtcDefinition& definition = dtcs->definitions()[i];
            entry.dtcs.push_back(
                ipc::J1939Dtc{diagnostics.dtcs[i].name, definition.spn, definition.fmi, count, dtcs->active(i)});
          }
          entry.lamps = lampByte(dtcs->lamps());
        }
      }
      if (countsDirty && dtcs) {
        countsToSave.clear();
        for (std::size_t i = 0; i < dtcs->definitions().size(); ++i) {
          const j1939::DtcDefinition& definition = dtcs->definitions()[i];
          countsToSave.push_back(j1939::Dtc{definition.spn, definition.fmi, dtcs->counts()[i], false});
        }
        countsPending = true;
        countsDirty = false;
      }
    } catch (...) {
      return;  // out of memory: try again on the next run
    }
    viewChanged = true;
    viewDirty = false;
  }

  void note(std::string text) noexcept {
    std::unique_lock lock(viewLock, std::try_to_lock);
    if (!lock.owns_lock() || log.size() == log.capacity()) return;  // the log is best effort
    try {
      log.push_back(std::move(text));
    } catch (...) {
    }
  }

  bool countsPending{};
};

// ---- the sinks ------------------------------------------------------------------------------

void NetworkBus::send(const j1939::ClaimFrame& frame) noexcept {
  owner->sendRaw(bus, frame.canId, frame.data);
  if ((frame.canId & 0xFFu) == j1939::NULL_ADDRESS) {
    owner->counters.cannotClaim.fetch_add(1, std::memory_order_relaxed);
  } else {
    owner->counters.claimsSent.fetch_add(1, std::memory_order_relaxed);
  }
}

void NetworkBus::addressChanged(std::uint8_t oldAddress, std::uint8_t newAddress, j1939::ClaimState state) noexcept {
  tp->setOwnAddress(newAddress < j1939::NULL_ADDRESS ? newAddress : j1939::NULL_ADDRESS, owner->callNs, *this);
  owner->markChanged(false);
  if (oldAddress != newAddress) {
    owner->note("bus '" + name + "': J1939 address " + hexByte(oldAddress) + " -> " + hexByte(newAddress) + " (" +
                std::string(j1939::claimStateName(state)) + ")");
  }
  if (!lossPending) return;
  lossPending = false;
  const bool moved = newAddress < j1939::NULL_ADDRESS && newAddress != preferred;
  const bool safetyHeld = moved && !owner->safetySdms.empty();
  const std::uint32_t outcome = static_cast<std::uint32_t>(pendingLostAddress) |
                                static_cast<std::uint32_t>(newAddress) << 8 | (safetyHeld ? 1u << 16 : 0u);
  // sequence lock: odd while writing; the reader retries when it changed under it
  const std::uint32_t sequence = lossSequence.load(std::memory_order_relaxed);
  lossSequence.store(sequence + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  lostClaimant.store(pendingClaimant, std::memory_order_relaxed);
  lostOutcome.store(outcome, std::memory_order_relaxed);
  lossSequence.store(sequence + 2, std::memory_order_release);
  owner->markChanged(false);
}

void NetworkBus::addressLost(std::uint8_t address, const j1939::Name& claimant) noexcept {
  lossPending = true;
  pendingLostAddress = address;
  pendingClaimant = claimant.toValue();
  owner->counters.addressesLost.fetch_add(1, std::memory_order_relaxed);
}

void NetworkBus::send(const j1939::TpFrame& frame) noexcept {
  owner->sendRaw(bus, frame.canId, frame.data);
}

void NetworkBus::finished(const j1939::TpSendResult& result) noexcept {
  if (result.outcome == j1939::TpSendOutcome::Completed) {
    owner->counters.tpCompleted.fetch_add(1, std::memory_order_relaxed);
  } else {
    owner->counters.tpFailed.fetch_add(1, std::memory_order_relaxed);
  }
}

// ---- Network --------------------------------------------------------------------------------

Result<std::unique_ptr<Network>> Network::create(const config::VehicleConfig& vehicle,
                                                 const config::DiagnosticsConfig& diagnostics,
                                                 const std::vector<std::string>& fsmStates,
                                                 const signals::Catalog& catalog, signals::SignalTable& table,
                                                 TxPort& out, const std::string& version) {
  auto impl = std::make_unique<NetworkImpl>(out, table, diagnostics);
  impl->version = version;
  impl->busSlot.assign(vehicle.buses.size(), -1);
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    const config::BusConfig& busConfig = vehicle.buses[b];
    if (!busConfig.j1939) continue;
    auto bus = std::make_unique<NetworkBus>();
    bus->owner = impl.get();
    bus->bus = b;
    bus->name = busConfig.name;
    bus->preferred = busConfig.j1939->preferredAddress;
    bus->nameValue = busConfig.j1939->name.toValue();
    bus->fd = busConfig.fd;
    if (busConfig.j1939->claim) bus->claimer.emplace(busConfig.j1939->claimerConfig());
    j1939::TpSenderConfig tpConfig;
    tpConfig.ownAddress = busConfig.j1939->claim ? j1939::NULL_ADDRESS : bus->preferred;
    tpConfig.maxPacketsPerCts = TP_WINDOW;
    bus->tp = std::make_unique<j1939::TpSender>(tpConfig);
    impl->busSlot[b] = static_cast<std::int32_t>(impl->buses.size());
    impl->buses.push_back(std::move(bus));
  }

  if (!diagnostics.dtcs.empty()) {
    auto stateResult = j1939::DiagnosticState::create(diagnostics.definitions(), diagnostics.dm1PeriodNs);
    if (!stateResult) return Error{diagnostics.file + ": " + stateResult.error().message};
    impl->dtcs.emplace(std::move(*stateResult));
    const auto fsmStateIndex = catalog.indexOf("internal.fsm.state");
    for (const config::DtcConfig& dtc : diagnostics.dtcs) {
      DtcCondition condition;
      condition.config = &dtc;
      if (dtc.source == config::DtcSource::FsmState) {
        const auto found = std::find(fsmStates.begin(), fsmStates.end(), dtc.fsmState);
        if (found == fsmStates.end()) {
          return Error{diagnostics.file + ": " + dtc.path + "/fsmState: the FSM has no state '" + dtc.fsmState + "'"};
        }
        if (!fsmStateIndex) return Error{"the catalog has no internal.fsm.state"};
        condition.index = *fsmStateIndex;
        condition.fsmStateIndex = static_cast<double>(found - fsmStates.begin());
      } else {
        const auto index = catalog.indexOf(dtc.signal);
        if (!index) return Error{diagnostics.file + ": " + dtc.path + "/signal: no signal '" + dtc.signal + "'"};
        condition.index = *index;
      }
      impl->conditions.push_back(condition);
    }
    impl->activeScratch.assign(impl->conditions.size(), 0);
    impl->countsToSave.reserve(impl->conditions.size());
  }

  // Identification answers, built once (they do not change while the service runs).
  const config::IdentificationConfig& identification = diagnostics.identification;
  std::vector<std::string_view> softwareFields(identification.software.begin(), identification.software.end());
  const std::string softwareVersion = "openvcu " + version;
  softwareFields.push_back(softwareVersion);
  std::array<std::uint8_t, j1939::TP_MAX_MESSAGE_SIZE> scratch{};
  std::size_t length = j1939::encodeSoftwareIdentification(softwareFields, scratch);
  if (length == 0) return Error{diagnostics.file + ": identification/software does not fit one message"};
  impl->software.assign(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(length));
  length = j1939::encodeEcuIdentification(identification.ecu(), scratch);
  if (length == 0) return Error{diagnostics.file + ": identification/ecu does not fit one message"};
  impl->ecu.assign(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(length));
  length = j1939::encodeComponentIdentification(identification.component(), scratch);
  if (length == 0) return Error{diagnostics.file + ": identification/component does not fit one message"};
  impl->component.assign(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(length));

  // The view: one entry per bus, its vectors reserved for every node and DTC there can be.
  for (const auto& bus : impl->buses) {
    ipc::J1939Network entry;
    entry.service = "vcu-can-tx";
    entry.instance = vehicle.instance;
    entry.pid = static_cast<std::int32_t>(::getpid());
    entry.bus = bus->name;
    entry.nodes.reserve(254);
    entry.dtcs.reserve(impl->conditions.size());
    impl->view.push_back(std::move(entry));
  }
  impl->log.reserve(64);
  return std::unique_ptr<Network>(new Network(std::move(impl)));
}

Network::Network(std::unique_ptr<NetworkImpl> impl) noexcept : m_impl(std::move(impl)) {}
Network::~Network() = default;

void Network::holdSafetyMessages(std::span<const std::uint32_t> sdmCanIds) {
  std::vector<std::uint32_t>& sdms = m_impl->safetySdms;
  sdms.clear();
  for (const std::uint32_t id : sdmCanIds) sdms.push_back(id & 0x1FFFFFFFu);
  std::sort(sdms.begin(), sdms.end());
}

void Network::restoreCounts(std::span<const j1939::Dtc> counts) noexcept {
  if (m_impl->dtcs) (void)m_impl->dtcs->restoreCounts(counts);
  m_impl->markChanged(false);
}

void Network::start(std::int64_t nowNs) noexcept {
  m_impl->callNs = nowNs;
  for (auto& bus : m_impl->buses) {
    if (bus->claimer) bus->claimer->start(nowNs, *bus);
  }
  m_impl->evaluate(nowNs);
  m_impl->publishView();
}

void Network::run(std::int64_t nowNs) noexcept {
  NetworkImpl& impl = *m_impl;
  impl.callNs = nowNs;
  for (auto& bus : impl.buses) {
    if (bus->claimer) {
      const auto deadline = bus->claimer->nextDeadlineNs();
      if (deadline && *deadline <= nowNs) bus->claimer->poll(nowNs, *bus);
    }
    const auto tpDeadline = bus->tp->nextDeadlineNs();
    if (tpDeadline && *tpDeadline <= nowNs) bus->tp->poll(nowNs, *bus);
  }
  if (impl.dtcs) {
    if (nowNs >= impl.nextEvaluationNs) impl.evaluate(nowNs);
    if (impl.dtcs->dm1Due(nowNs)) {
      impl.sendDm1(nowNs);
      impl.dtcs->dm1Sent(nowNs);
    }
  }
  impl.publishView();
}

std::int64_t Network::nextDeadlineNs() const noexcept {
  const NetworkImpl& impl = *m_impl;
  std::int64_t next = INT64_MAX;
  for (const auto& bus : impl.buses) {
    if (bus->claimer) {
      if (const auto deadline = bus->claimer->nextDeadlineNs()) next = std::min(next, *deadline);
    }
    if (const auto deadline = bus->tp->nextDeadlineNs()) next = std::min(next, *deadline);
  }
  if (impl.dtcs) {
    // the evaluation rides on wake-ups the schedule makes anyway; it forces its own only
    // when none came for half a period more (a bus of slow messages)
    next = std::min(next, impl.nextEvaluationNs + DTC_EVALUATION_NS / 2);
    next = std::min(next, std::max(impl.dtcs->nextDm1DueNs(), std::int64_t{0}));
  }
  if (impl.viewDirty) next = std::min(next, impl.viewRetryNs);  // a missed try-lock: again soon
  return next;
}

void Network::onFrame(std::size_t busIndex, const can::Frame& frame, std::int64_t nowNs) noexcept {
  NetworkBus* bus = m_impl->busOf(busIndex);
  if (bus == nullptr || !frame.extended()) return;
  m_impl->callNs = nowNs;
  if (const auto claimed = j1939::parseAddressClaimed(frame.id, true, frame.payload())) {
    if (bus->claimer) {
      const j1939::ClaimCounters before = bus->claimer->counters();
      bus->claimer->onAddressClaimed(claimed->sourceAddress, claimed->name, nowNs, *bus);
      const j1939::ClaimCounters& after = bus->claimer->counters();
      m_impl->counters.contestsWon.fetch_add(after.contestsWon - before.contestsWon, std::memory_order_relaxed);
      m_impl->counters.contestsLost.fetch_add(after.contestsLost - before.contestsLost, std::memory_order_relaxed);
      m_impl->markChanged(false);
    }
    return;
  }
  bus->tp->onFrame(frame.id, frame.payload(), nowNs, *bus);
}

bool Network::answerRequest(std::size_t busIndex, const j1939::Request& request, std::int64_t nowNs) noexcept {
  NetworkImpl& impl = *m_impl;
  NetworkBus* bus = impl.busOf(busIndex);
  if (bus == nullptr) return false;
  impl.callNs = nowNs;
  // A PDU2 answer goes to global for a global request; a long one to the requester by RTS/CTS.
  const std::uint8_t destination = request.global ? j1939::GLOBAL_ADDRESS : request.requester;
  auto answered = [&] {
    impl.counters.requestsAnswered.fetch_add(1, std::memory_order_relaxed);
    return true;
  };
  switch (request.pgn) {
    case j1939::PGN_ADDRESS_CLAIMED:
      if (!bus->claimer) return false;
      bus->claimer->onRequestForAddressClaimed(request.global ? j1939::GLOBAL_ADDRESS : bus->address(), nowNs, *bus);
      return answered();
    case j1939::PGN_SOFTWARE_IDENTIFICATION:
      impl.sendMessage(*bus, request.pgn, DM_PRIORITY, impl.software, destination, nowNs);
      return answered();
    case j1939::PGN_ECU_IDENTIFICATION:
      impl.sendMessage(*bus, request.pgn, DM_PRIORITY, impl.ecu, destination, nowNs);
      return answered();
    case j1939::PGN_COMPONENT_IDENTIFICATION:
      impl.sendMessage(*bus, request.pgn, DM_PRIORITY, impl.component, destination, nowNs);
      return answered();
    default:
      break;
  }
  if (!impl.dtcs) return false;
  switch (request.pgn) {
    case j1939::PGN_DM1: {
      impl.evaluate(nowNs);
      impl.sendDm1(nowNs, busIndex, destination);
      return answered();
    }
    case j1939::PGN_DM2: {
      const std::size_t length = impl.dtcs->encodeDm2(impl.dmScratch);
      impl.sendMessage(*bus, j1939::PGN_DM2, DM_PRIORITY, std::span<const std::uint8_t>(impl.dmScratch.data(), length),
                       destination, nowNs);
      return answered();
    }
    case j1939::PGN_DM3:
    case j1939::PGN_DM11: {
      const bool dm3 = request.pgn == j1939::PGN_DM3;
      const config::ClearPolicy policy = dm3 ? impl.diagnostics.dm3 : impl.diagnostics.dm11;
      if (policy == config::ClearPolicy::Refuse) {
        impl.counters.clearsRefused.fetch_add(1, std::memory_order_relaxed);
        impl.acknowledge(*bus, j1939::AckControl::AccessDenied, request);
        impl.note(std::string(dm3 ? "DM3" : "DM11") + " from " + hexByte(request.requester) + " on bus '" + bus->name +
                  "' refused (diagnostics.json)");
        return answered();
      }
      const bool dm1Changed = dm3 ? impl.dtcs->clearPreviouslyActive() : impl.dtcs->clearActive();
      (void)dm1Changed;
      impl.counters.clearsAccepted.fetch_add(1, std::memory_order_relaxed);
      impl.acknowledge(*bus, j1939::AckControl::Positive, request);
      impl.markChanged(true);
      impl.note(std::string(dm3 ? "DM3 (previously active DTCs cleared)" : "DM11 (active DTCs cleared)") + " from " +
                hexByte(request.requester) + " on bus '" + bus->name + "'");
      return answered();
    }
    default:
      return false;
  }
}

void Network::setNow(std::int64_t nowNs) noexcept {
  m_impl->callNs = nowNs;
}

can::SendStatus Network::send(std::size_t busIndex, const can::Frame& frame) noexcept {
  NetworkBus* bus = m_impl->busOf(busIndex);
  if (bus != nullptr && frame.extended() && frame.length > 8 && !bus->fd) return sendLong(*bus, frame);
  if (bus == nullptr || !bus->claimer) return m_impl->out.send(busIndex, frame);
  if (!bus->mayTransmit()) {
    m_impl->counters.framesHeldByClaim.fetch_add(1, std::memory_order_relaxed);
    return can::SendStatus::Down;
  }
  if (!frame.extended() || (frame.id & 0xFFu) != bus->preferred || bus->address() == bus->preferred) {
    return m_impl->out.send(busIndex, frame);
  }
  if (m_impl->isSafetyFrame(frame)) {
    m_impl->counters.safetyFramesHeld.fetch_add(1, std::memory_order_relaxed);
    return can::SendStatus::Down;
  }
  can::Frame moved = frame;
  moved.id = (frame.id & ~0xFFu) | bus->address();
  return m_impl->out.send(busIndex, moved);
}

can::SendStatus Network::sendLong(NetworkBus& bus, const can::Frame& frame) noexcept {
  if (!bus.mayTransmit()) {
    m_impl->counters.framesHeldByClaim.fetch_add(1, std::memory_order_relaxed);
    return can::SendStatus::Down;
  }
  const j1939::Id id = j1939::Id::fromCanId(frame.id);
  // The transport sender speaks from the VCU's address only: a long message of another
  // source address cannot leave on a classic bus (the link refuses it as Invalid).
  if (id.sourceAddress != bus.preferred) return m_impl->out.send(bus.bus, frame);
  // false: refused (its destination's queue is full: a long message due faster than its
  // transfer takes), so this frame was not sent
  return m_impl->sendMessage(bus, id.pgn(), id.priority, frame.payload(), id.destination(), m_impl->callNs)
             ? can::SendStatus::Sent
             : can::SendStatus::Busy;
}

std::vector<ipc::J1939Network> Network::snapshot() const {
  std::lock_guard lock(m_impl->viewLock);
  return m_impl->view;
}

bool Network::takeChanged() noexcept {
  std::lock_guard lock(m_impl->viewLock);
  const bool changed = m_impl->viewChanged;
  m_impl->viewChanged = false;
  return changed;
}

std::optional<std::vector<j1939::Dtc>> Network::takeCountsToSave() {
  std::lock_guard lock(m_impl->viewLock);
  if (!m_impl->countsPending) return std::nullopt;
  m_impl->countsPending = false;
  return m_impl->countsToSave;
}

std::vector<std::string> Network::takeLog() {
  std::lock_guard lock(m_impl->viewLock);
  std::vector<std::string> lines;
  lines.swap(m_impl->log);
  m_impl->log.reserve(64);
  return lines;
}

std::vector<AddressLoss> Network::takeAddressLosses() {
  std::vector<AddressLoss> losses;
  for (const auto& bus : m_impl->buses) {
    std::uint32_t sequence = bus->lossSequence.load(std::memory_order_acquire);
    if (sequence == bus->lossesTaken) continue;
    std::uint64_t claimant{};
    std::uint32_t outcome{};
    for (;;) {  // the writer publishes a loss in a few stores: at most a retry or two
      if ((sequence & 1u) == 0) {
        claimant = bus->lostClaimant.load(std::memory_order_relaxed);
        outcome = bus->lostOutcome.load(std::memory_order_relaxed);
        std::atomic_thread_fence(std::memory_order_acquire);
        if (bus->lossSequence.load(std::memory_order_relaxed) == sequence) break;
      }
      sequence = bus->lossSequence.load(std::memory_order_acquire);
    }
    bus->lossesTaken = sequence;
    losses.push_back(AddressLoss{bus->name, static_cast<std::uint8_t>(outcome & 0xFFu), claimant, bus->nameValue,
                                 static_cast<std::uint8_t>((outcome >> 8) & 0xFFu), (outcome & (1u << 16)) != 0});
  }
  return losses;
}

std::string AddressLoss::describe() const {
  const auto addressText = [](std::uint8_t address) { return hexByte(address) + " (" + std::to_string(address) + ")"; };
  std::string text = "bus '" + bus + "': address " + addressText(lostAddress) + " taken by NAME " + hexName(claimant) +
                     ", which has priority over this VCU's NAME " + hexName(ourName) + "; ";
  if (newAddress >= j1939::NULL_ADDRESS) {
    return text + "the VCU sent Cannot Claim and sends nothing more on this bus (J1939-81) until vcu-can-tx restarts";
  }
  text += "the VCU moved to " + addressText(newAddress);
  if (safetyPairsHeld)
    text += "; its J1939-76 safety pairs are not sent from there (they leave only from its preferred address)";
  return text;
}

bool AddressLoss::critical() const noexcept {
  return newAddress >= j1939::NULL_ADDRESS || safetyPairsHeld;
}

const NetworkCounters& Network::counters() const noexcept {
  return m_impl->counters;
}

bool Network::active() const noexcept {
  return !m_impl->buses.empty() || m_impl->dtcs.has_value();
}

}  // namespace openvcu::cantx
