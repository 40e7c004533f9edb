#include "receiver.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "address_map.hpp"
#include "openvcu/bridge/message_binding.hpp"
#include "openvcu/can/wire_time.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/j1939/address_claim.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/dm_encode.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/j1939/transport.hpp"

namespace openvcu::canrx {
namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int32_t NO_SLOT = -1;
constexpr std::string_view SOURCE = "vcu-can-rx";

/// Bus states as written to internal.bus.<bus>.state.
enum class BusState : std::uint8_t { Active = 0, Warning = 1, Passive = 2, BusOff = 3, Down = 4 };

/// The VCU's J1939-81 NAME on `bus`, when it claims an address there.
std::optional<std::uint64_t> ownNameOf(const config::BusConfig& bus) {
  if (!bus.j1939 || !bus.j1939->claim) return std::nullopt;
  return bus.j1939->name.toValue();
}

std::string hex(std::uint32_t value, int digits) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%0*X", digits, value);
  return buffer;
}

}  // namespace

/// One tracked (received) message.
struct MessageState {
  std::size_t messageIndex{};
  std::size_t bus{};
  std::int64_t timeoutNs{};
  std::int64_t lastNs{};  ///< last frame, or the receiver's start
  MessageCounters counters;
  std::int64_t windowSumNs{};
  std::int64_t windowMaxNs{};
  std::uint64_t windowIntervals{};
  bool seen{};
  bool faultActive{};          ///< timeoutFault raised and not yet cleared
  std::int32_t expectation{};  ///< index into ReceiverImpl::expectations, or config::ALWAYS_EXPECTED
  std::string timeoutFault;    ///< "rx_timeout.<bus>.<Message>"
};

/// A receive.json "expectedWhen" condition as the receiver follows it.
struct ExpectationState {
  signals::SignalIndex slot{};
  double equals{};
  std::int64_t startNs{};
  bool expected{};
  std::int64_t fromNs{};  ///< expected since (plus startNs): timeouts count from here at the earliest
  std::string text;       ///< "internal.gpio.Cl15 = 1"
};

struct SafetyState {
  j1939::SafetyPairChecker checker;
  std::uint32_t headerCanId{};
  std::uint32_t dataCanId{};
  std::size_t messageIndex{};
  bool failing{};
  bool headerOverdue{};
  std::string fault;  ///< "j1939_76.<Message>"
};

struct Dm1State {
  j1939::Dm1 last{};
  bool has{};
  std::int64_t publishedNs{};                                   ///< when outputs.dm1() last got this node's DM1
  std::array<std::int32_t, config::DM1_FIELDS.size()> slots{};  ///< NO_SLOT when the node has none
  std::string label;                                            ///< node name, or "SA 0x.."
};

struct BusSlot {
  std::string name;
  std::unique_ptr<j1939::TpReceiver> transport;
  std::unique_ptr<AddressMap> addresses;  ///< J1939-81 claims: the VCU's address, moved nodes' home addresses
  j1939::AddressSet requestAddresses{};   ///< the addresses the VCU answers requests on, on this bus
  std::unique_ptr<can::BusLoadMeter> load;
  BusCounters counters;
  std::int32_t loadSlot{NO_SLOT};
  std::int32_t stateSlot{NO_SLOT};
  BusState state{BusState::Active};
};

struct ReceiverImpl;

/// Routes the TP receiver's answers and results back into the receiver.
class TpSink final : public j1939::TpSink {
 public:
  TpSink(ReceiverImpl& owner, std::size_t bus, std::int64_t nowNs) : m_owner(owner), m_bus(bus), m_nowNs(nowNs) {}
  void send(const j1939::TpFrame& frame) noexcept override;
  void completed(const j1939::TpMessage& message) noexcept override;
  void event(const j1939::TpEvent& event) noexcept override;

 private:
  ReceiverImpl& m_owner;
  std::size_t m_bus;
  std::int64_t m_nowNs;
};

struct ReceiverImpl {
  const config::VehicleConfig& vehicle;
  config::ReceiveConfig receive;
  signals::SignalTable& table;
  ReceiverOutputs& outputs;
  bridge::DatabaseBinding bindings;  ///< per DBC message: codec, table slots and ranges
  dbc::MessageMatcher matcher;
  std::vector<BusSlot> buses;
  std::vector<std::int32_t> trackedByMessage;  ///< DBC message index -> index into messages, or -1
  std::vector<std::int32_t> busByMessage;      ///< DBC message index -> bus index, or -1
  std::vector<MessageState> messages;
  std::vector<std::size_t> trackedIndices;
  std::vector<SafetyState> safety;
  std::vector<ExpectationState> expectations;
  std::array<std::unique_ptr<Dm1State>, 256> dm1;  ///< by source address
  j1939::AddressSet ownAddress{};                  ///< addresses this node answers requests on
  std::uint8_t tpAddress{j1939::NULL_ADDRESS};
  MessageCounters noCounters;
  std::int64_t startNs{};
  std::int64_t lastTickNs{};

  ReceiverImpl(const config::VehicleConfig& vehicleConfig, config::ReceiveConfig receiveConfig,
               const signals::Catalog& catalog, signals::SignalTable& signalTable, ReceiverOutputs& receiverOutputs)
      : vehicle(vehicleConfig),
        receive(std::move(receiveConfig)),
        table(signalTable),
        outputs(receiverOutputs),
        bindings(vehicleConfig.database, catalog),
        matcher(vehicleConfig.database, dbc::MatchMode::J1939) {}

  // ---- per frame ------------------------------------------------------------------------

  void onFrame(std::size_t busIndex, const can::ReceivedFrame& received) noexcept {
    BusSlot& bus = buses[busIndex];
    ++bus.counters.frames;
    bus.load->add(received.frame, received.monotonicNs);
    handle(busIndex, received);
    // After the table writes: whoever sees the frame on a stream finds its values written.
    outputs.received(busIndex, received);
    forward(busIndex, received.frame);
  }

  void handle(std::size_t busIndex, const can::ReceivedFrame& received) noexcept {
    BusSlot& bus = buses[busIndex];
    const can::Frame& frame = received.frame;
    if (frame.extended()) {
      const j1939::Id id = j1939::Id::fromCanId(frame.id);
      const std::uint32_t pgn = id.pgn();
      if (pgn == j1939::PGN_ADDRESS_CLAIMED) onAddressClaimed(busIndex, id.sourceAddress, received);
      if (pgn == j1939::PGN_TP_CM && answersOurTransfer(bus, id, frame)) outputs.network(busIndex, received);
      if (pgn == j1939::PGN_TP_CM || pgn == j1939::PGN_TP_DT) {
        TpSink sink(*this, busIndex, received.monotonicNs);
        bus.transport->onFrame(frame.id, frame.payload(), received.monotonicNs, sink);
        bus.counters.tpSessions = bus.transport->counters().sessionsStarted;
        return;
      }
      if (pgn == j1939::PGN_REQUEST) {
        if (const auto maybeRequest = j1939::parseRequest(frame.id, true, frame.payload(), bus.requestAddresses)) {
          ++bus.counters.requests;
          outputs.request(busIndex, *maybeRequest, received.monotonicNs);
        }
        // and decoded below when the DBC defines it (HHEA: RQST_VIC_PGN59904)
      }
      if (receive.dm1 && pgn == j1939::PGN_DM1)
        onDm1(busIndex, id.sourceAddress, frame.payload(), received.monotonicNs);
      if (checkSafetyHeader(frame, received.monotonicNs)) return;
    }
    // A node that claimed a new address is decoded by its home address (address_map.hpp).
    const std::uint32_t matchId =
        frame.extended() ? (frame.id & ~0xFFu) | bus.addresses->homeAddress(static_cast<std::uint8_t>(frame.id & 0xFFu))
                         : frame.id;
    const std::int32_t match = matcher.match(matchId, frame.extended());
    if (match == dbc::MessageMatcher::NO_MATCH ||
        busByMessage[static_cast<std::size_t>(match)] != static_cast<std::int32_t>(busIndex)) {
      ++bus.counters.unknownIds;
      return;
    }
    const auto messageIndex = static_cast<std::size_t>(match);
    const std::int32_t tracked = trackedByMessage[messageIndex];
    if (tracked < 0) {
      ++bus.counters.ownFrames;
      return;
    }
    MessageState& message = messages[static_cast<std::size_t>(tracked)];
    if (!safetyAllowsData(frame, received.monotonicNs, messageIndex, bus.counters)) return;
    const std::uint16_t source = frame.extended() ? j1939::Id::fromCanId(frame.id).sourceAddress : 0;
    decodeInto(message, frame.payload(), received.monotonicNs, source, bus.counters);
  }

  void decodeInto(MessageState& message, std::span<const std::uint8_t> payload, std::int64_t nowNs,
                  std::uint16_t source, BusCounters& counters) noexcept {
    const bridge::DecodeResult result =
        bindings[message.messageIndex].decodeInto(table, payload, nowNs, source, bridge::RangeCheck::Mark);
    counters.outOfRange += result.outOfRange;
    if (result.missing > 0) ++counters.decodeErrors;
    ++counters.decoded;
    seen(message, nowNs);
  }

  void seen(MessageState& message, std::int64_t nowNs) noexcept {
    if (message.seen) {
      const std::int64_t interval = nowNs - message.lastNs;
      message.windowSumNs += interval;
      message.windowMaxNs = std::max(message.windowMaxNs, interval);
      ++message.windowIntervals;
    }
    message.seen = true;
    message.lastNs = nowNs;
    ++message.counters.frames;
    message.counters.stale = false;
    if (message.faultActive) {
      message.faultActive = false;
      raise(message.timeoutFault, false, ipc::FaultSeverity::Warning,
            vehicle.database.messages[message.messageIndex].name + " received again");
    }
  }

  // ---- expectations ---------------------------------------------------------------------

  /// The condition's value now: the override or command when the slot has one, else the bus
  /// value; a slot never written reads as false (nothing has switched the sender on).
  bool holds(const ExpectationState& expectation) const noexcept {
    const auto maybeSnapshot = table.read(expectation.slot);
    if (!maybeSnapshot) return false;
    double value = 0.0;
    if (const auto command = signals::effectiveCommand(*maybeSnapshot)) {
      value = command->value;
    } else if (maybeSnapshot->bus.updates > 0) {
      value = maybeSnapshot->bus.value;
    } else {
      return false;
    }
    return std::fabs(value - expectation.equals) < 1e-9;
  }

  void updateExpectations(std::int64_t nowNs) noexcept {
    for (ExpectationState& expectation : expectations) {
      const bool now = holds(expectation);
      if (now == expectation.expected) continue;
      expectation.expected = now;
      if (now) expectation.fromNs = nowNs + expectation.startNs;
    }
  }

  bool expected(const MessageState& message) const noexcept {
    return message.expectation == config::ALWAYS_EXPECTED ||
           expectations[static_cast<std::size_t>(message.expectation)].expected;
  }

  /// The time a message's timeout counts from: its last frame (or the start), or the moment
  /// its sender became expected when that is later.
  std::int64_t supervisedFromNs(const MessageState& message) const noexcept {
    if (message.expectation == config::ALWAYS_EXPECTED) return message.lastNs;
    return std::max(message.lastNs, expectations[static_cast<std::size_t>(message.expectation)].fromNs);
  }

  // ---- forwarding -----------------------------------------------------------------------

  void forward(std::size_t busIndex, const can::Frame& frame) noexcept {
    for (const config::ForwardRule& rule : receive.forward) {
      if (rule.fromBus != busIndex || rule.extended != frame.extended()) continue;
      if (rule.byPgn) {
        const j1939::Id id = j1939::Id::fromCanId(frame.id);
        if (id.pgn() != rule.id || (rule.source && *rule.source != id.sourceAddress)) continue;
      } else if (frame.id != rule.id) {
        continue;
      }
      can::Frame copy = frame;
      if (rule.rewriteId) copy.id = *rule.rewriteId;
      outputs.forward(rule.toBus, copy);
      ++buses[busIndex].counters.forwarded;
    }
  }

  // ---- J1939-76 -------------------------------------------------------------------------

  /// J1939-81: follows the VCU's own address and moved nodes, and hands the claim to can-tx.
  void onAddressClaimed(std::size_t busIndex, std::uint8_t source, const can::ReceivedFrame& received) noexcept {
    BusSlot& bus = buses[busIndex];
    ++bus.counters.addressClaims;
    const std::uint8_t before = bus.addresses->ownAddress();
    if (bus.addresses->onAddressClaimed(source, received.frame.payload())) {
      ++bus.counters.ownAddressChanges;
      const std::uint8_t address = bus.addresses->ownAddress();
      bus.transport->setOwnAddress(address);
      // requests to the address the VCU left are another node's now
      if (before < j1939::NULL_ADDRESS) bus.requestAddresses[before] = false;
      if (address < j1939::NULL_ADDRESS) bus.requestAddresses[address] = true;
    }
    outputs.network(busIndex, received);
  }

  /// A TP.CM CTS, EndOfMsgAck or Abort to the VCU's current address on this bus: an answer
  /// to a transfer can-tx sends (an Abort may also end a session we receive: both see it).
  static bool answersOurTransfer(const BusSlot& bus, const j1939::Id& id, const can::Frame& frame) noexcept {
    if (frame.length == 0 || id.pduSpecific != bus.addresses->ownAddress()) return false;
    const std::uint8_t control = frame.data[0];
    return control == j1939::TP_CM_CTS || control == j1939::TP_CM_END_OF_MSG_ACK || control == j1939::TP_CM_ABORT;
  }

  /// true when `frame` is the SHM of a configured group (then it is consumed here).
  bool checkSafetyHeader(const can::Frame& frame, std::int64_t nowNs) noexcept {
    for (SafetyState& group : safety) {
      if (group.headerCanId == frame.id) {
        group.checker.onHeader(frame.payload(), nowNs);
        return true;
      }
    }
    return false;
  }

  /// false when `frame` is the SDM of a group and fails its check.
  bool safetyAllowsData(const can::Frame& frame, std::int64_t nowNs, std::size_t messageIndex,
                        BusCounters& counters) noexcept {
    for (SafetyState& group : safety) {
      if (group.messageIndex != messageIndex) continue;
      if (group.dataCanId != frame.id) {  // same PGN, other priority or source: not the protected group
        ++counters.safetyFailures;
        return false;
      }
      const j1939::SafetyResult result = group.checker.onData(frame.payload(), nowNs);
      // Synchronising: intact and timely, but the first of a sequence: not used, not a fault.
      if (result == j1939::SafetyResult::Synchronising) return false;
      const bool ok = result == j1939::SafetyResult::Ok;
      if (!ok) ++counters.safetyFailures;
      if (!ok && !group.failing) {
        group.failing = true;
        raise(group.fault, true, ipc::FaultSeverity::Error,
              "J1939-76 check of " + vehicle.database.messages[messageIndex].name +
                  " failed: " + std::string(j1939::safetyResultName(result)) + "; its data are not used");
      } else if (ok && group.failing) {
        group.failing = false;
        raise(group.fault, false, ipc::FaultSeverity::Error,
              vehicle.database.messages[messageIndex].name + " passes the J1939-76 check again");
      }
      return ok;
    }
    return true;
  }

  // ---- DM1 ------------------------------------------------------------------------------

  void onDm1(std::size_t busIndex, std::uint8_t source, std::span<const std::uint8_t> payload,
             std::int64_t nowNs) noexcept {
    const std::optional<j1939::Dm1> maybeDm1 = j1939::decodeDm1(payload);
    if (!maybeDm1) return;
    std::unique_ptr<Dm1State>& state = dm1[source];
    if (!state) {
      // First DM1 from an address no DBC node has: allocated once per address (at most 256).
      state = std::make_unique<Dm1State>();
      state->slots.fill(NO_SLOT);
      state->label = "SA " + hex(source, 2);
    }
    const j1939::Dm1& now = *maybeDm1;
    const double values[config::DM1_FIELDS.size()] = {
        static_cast<double>(now.dtcCount),
        static_cast<double>(now.lamps.protect),
        static_cast<double>(now.lamps.amberWarning),
        static_cast<double>(now.lamps.redStop),
        static_cast<double>(now.lamps.malfunction),
        now.dtcCount > 0 ? static_cast<double>(now.dtcs[0].spn) : 0.0,
        now.dtcCount > 0 ? static_cast<double>(now.dtcs[0].fmi) : 0.0,
    };
    for (std::size_t f = 0; f < config::DM1_FIELDS.size(); ++f) {
      if (state->slots[f] != NO_SLOT) {
        table.writeBus(static_cast<signals::SignalIndex>(state->slots[f]), values[f], nowNs, source,
                       signals::Quality::Valid);
      }
    }
    // The table first, then the events: whoever reacts to a fault finds the slots written.
    static const j1939::Dm1 NONE{};
    const j1939::Dm1& before = state->has ? state->last : NONE;
    j1939::diffDtcs(
        before, now, [&](const j1939::Dtc& dtc) { dtcFault(*state, dtc, now, true); },
        [&](const j1939::Dtc& dtc) { dtcFault(*state, dtc, now, false); });
    const bool changed =
        !state->has || now.lamps != before.lamps || !std::ranges::equal(now.activeDtcs(), before.activeDtcs());
    if (changed || nowNs - state->publishedNs >= DM1_REPUBLISH_NS) {
      publishDm1(busIndex, source, *state, now);
      state->publishedNs = nowNs;
    }
    state->last = now;
    state->has = true;
    ++buses[busIndex].counters.dm1Messages;
  }

  /// The node's whole DM1 for other processes (vcu-telemetry): lamps and every active DTC.
  void publishDm1(std::size_t busIndex, std::uint8_t source, const Dm1State& state,
                  const j1939::Dm1& dm1Message) noexcept {
    try {
      ipc::NodeDm1 message;
      message.bus = buses[busIndex].name;
      message.node = state.label;
      message.source = source;
      std::array<std::uint8_t, j1939::DM1_MIN_LENGTH + 2> lampBytes{};  // the two lamp bytes, as on the bus
      if (j1939::encodeDm1(dm1Message.lamps, {}, lampBytes) >= j1939::DM1_LAMP_BYTES) {
        message.lamps = lampBytes[0];
        message.flash = lampBytes[1];
      }
      message.dtcs.reserve(dm1Message.dtcCount);
      for (const j1939::Dtc& dtc : dm1Message.activeDtcs()) {
        message.dtcs.push_back(ipc::NodeDtc{.spn = dtc.spn,
                                            .fmi = dtc.fmi,
                                            .occurrences = dtc.occurrenceCount,
                                            .conversionMethod = dtc.spnConversionMethod});
      }
      outputs.dm1(message);
    } catch (...) {
      // Out of memory: the table still holds the DM1 summary; the next DM1 tries again.
    }
  }

  void dtcFault(const Dm1State& state, const j1939::Dtc& dtc, const j1939::Dm1& dm1Message, bool active) {
    const std::string name = "dm1." + state.label + ".spn" + std::to_string(dtc.spn) + ".fmi" + std::to_string(dtc.fmi);
    std::string text = state.label + " DTC SPN " + std::to_string(dtc.spn) + " FMI " + std::to_string(dtc.fmi);
    if (active) {
      text += " active, occurrence " + std::to_string(dtc.occurrenceCount) + ", red stop lamp " +
              std::string(j1939::lampStatusName(dm1Message.lamps.redStop)) + ", amber warning lamp " +
              std::string(j1939::lampStatusName(dm1Message.lamps.amberWarning));
    } else {
      text += " no longer active";
    }
    const bool severe = dm1Message.lamps.redStop == j1939::LampStatus::On;
    raise(name, active, severe ? ipc::FaultSeverity::Error : ipc::FaultSeverity::Warning, text);
  }

  // ---- TP results -----------------------------------------------------------------------

  void onTpMessage(std::size_t busIndex, const j1939::TpMessage& message, std::int64_t nowNs) noexcept {
    BusSlot& bus = buses[busIndex];
    ++bus.counters.tpCompleted;
    if (message.pgn == j1939::PGN_DM1) {
      if (receive.dm1) onDm1(busIndex, message.source, message.data, nowNs);
    }
    // Decode through the DBC: the message defined for this PGN (and destination).
    const std::uint8_t destination = message.broadcast ? j1939::GLOBAL_ADDRESS : message.destination;
    const std::uint32_t canId = j1939::Id::fromPgn(message.pgn, 6, message.source, destination).toCanId();
    const std::int32_t match = matcher.match(canId, true);
    if (match == dbc::MessageMatcher::NO_MATCH ||
        busByMessage[static_cast<std::size_t>(match)] != static_cast<std::int32_t>(busIndex)) {
      return;
    }
    const std::int32_t tracked = trackedByMessage[static_cast<std::size_t>(match)];
    if (tracked < 0) return;
    decodeInto(messages[static_cast<std::size_t>(tracked)], message.data, nowNs, message.source, bus.counters);
  }

  // ---- bus events -----------------------------------------------------------------------

  void onBusEvent(std::size_t busIndex, const can::BusEvent& event) noexcept {
    BusSlot& bus = buses[busIndex];
    BusState next = bus.state;
    switch (event.kind) {
      case can::BusEventKind::LinkUp:
      case can::BusEventKind::Restarted:
      case can::BusEventKind::ErrorActive:
        next = BusState::Active;
        break;
      case can::BusEventKind::LinkDown:
        next = BusState::Down;
        break;
      case can::BusEventKind::ErrorWarning:
        next = BusState::Warning;
        break;
      case can::BusEventKind::ErrorPassive:
        next = BusState::Passive;
        break;
      case can::BusEventKind::BusOff:
        next = BusState::BusOff;
        break;
      default:
        break;
    }
    if (event.kind != can::BusEventKind::LinkUp) ++bus.counters.busErrors;
    if (bus.stateSlot != NO_SLOT) {
      table.writeBus(static_cast<signals::SignalIndex>(bus.stateSlot), static_cast<double>(next), event.monotonicNs, 0,
                     signals::Quality::Valid);
    }
    const bool wasBad = bus.state == BusState::BusOff || bus.state == BusState::Down;
    const bool isBad = next == BusState::BusOff || next == BusState::Down;
    if (isBad != wasBad || (isBad && next != bus.state)) {
      raise("bus." + bus.name, isBad, ipc::FaultSeverity::Error,
            "bus " + bus.name + ": " + std::string(can::busEventName(event.kind)));
    }
    bus.state = next;
  }

  // ---- time -----------------------------------------------------------------------------

  void onTick(std::int64_t nowNs) noexcept {
    lastTickNs = nowNs;
    updateExpectations(nowNs);
    for (MessageState& message : messages) {
      if (message.timeoutNs <= 0) continue;
      // The data: stale once the message stops, whether or not its sender is expected.
      if (!message.counters.stale && nowNs - message.lastNs > message.timeoutNs) {
        message.counters.stale = true;
        bindings[message.messageIndex].markBusQuality(table, signals::Quality::Stale);
      }
      // The fault: only while the sender is expected, counted from when it became so.
      const std::string& name = vehicle.database.messages[message.messageIndex].name;
      if (!expected(message)) {
        if (message.faultActive) {
          message.faultActive = false;
          const ExpectationState& expectation = expectations[static_cast<std::size_t>(message.expectation)];
          raise(message.timeoutFault, false, ipc::FaultSeverity::Warning,
                name + " no longer expected (" + expectation.text + " does not hold)");
        }
        continue;
      }
      if (message.faultActive || nowNs - supervisedFromNs(message) <= message.timeoutNs) continue;
      message.faultActive = true;
      ++buses[message.bus].counters.timeouts;
      raise(message.timeoutFault, true, ipc::FaultSeverity::Warning,
            name + (message.seen ? " not received for " : " never received within ") +
                std::to_string(message.timeoutNs / MS) + " ms" +
                (message.expectation == config::ALWAYS_EXPECTED
                     ? std::string()
                     : " while expected (" + expectations[static_cast<std::size_t>(message.expectation)].text + ")"));
    }
    for (std::size_t b = 0; b < buses.size(); ++b) {
      BusSlot& bus = buses[b];
      TpSink sink(*this, b, nowNs);
      bus.transport->poll(nowNs, sink);
      bus.counters.tpSessions = bus.transport->counters().sessionsStarted;
      const double load = bus.load->loadPercent(nowNs);
      bus.counters.loadPermille = static_cast<std::uint64_t>(load * 10.0 + 0.5);
      if (bus.loadSlot != NO_SLOT) {
        table.writeBus(static_cast<signals::SignalIndex>(bus.loadSlot), load, nowNs, 0, signals::Quality::Valid);
      }
      // the state as of the last bus event (Active from the link's opening: a sim link has no
      // LinkUp event), rewritten with the load so its age says can-rx is looking
      if (bus.stateSlot != NO_SLOT) {
        table.writeBus(static_cast<signals::SignalIndex>(bus.stateSlot), static_cast<double>(bus.state), nowNs, 0,
                       signals::Quality::Valid);
      }
    }
    for (SafetyState& group : safety) {
      // From the start, a group gets one SHM cycle before its first SHM is overdue.
      const bool overdue =
          group.checker.headerOverdue(nowNs) && nowNs - startNs > group.checker.config().maxHeaderCycleNs;
      if (overdue == group.headerOverdue) continue;
      group.headerOverdue = overdue;
      raise(group.fault + ".header", overdue, ipc::FaultSeverity::Error,
            vehicle.database.messages[group.messageIndex].name +
                (overdue ? ": safety header (SHM) overdue" : ": safety header (SHM) arriving again"));
    }
  }

  void raise(const std::string& name, bool active, ipc::FaultSeverity severity, std::string text) noexcept {
    try {
      ipc::FaultEvent event;
      event.name = name;
      event.source = std::string(SOURCE);
      event.severity = severity;
      event.active = active;
      event.text = std::move(text);
      outputs.fault(event);
    } catch (...) {
      // Out of memory while building a fault text: the table still shows the state.
    }
  }
};

void TpSink::send(const j1939::TpFrame& tpFrame) noexcept {
  can::Frame frame;
  frame.id = tpFrame.canId;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = tpFrame.length;
  std::copy_n(tpFrame.data.begin(), tpFrame.length, frame.data.begin());
  frame.timestampNs = m_nowNs;
  (void)m_owner.outputs.transmit(m_bus, frame);
}

void TpSink::completed(const j1939::TpMessage& message) noexcept {
  m_owner.onTpMessage(m_bus, message, m_nowNs);
}

void TpSink::event(const j1939::TpEvent& event) noexcept {
  BusCounters& counters = m_owner.buses[m_bus].counters;
  switch (event.kind) {
    case j1939::TpEventKind::Aborted:
    case j1939::TpEventKind::AbortSent:
    case j1939::TpEventKind::Timeout:
    case j1939::TpEventKind::Dropped:
      ++counters.tpAborted;
      break;
    default:
      break;
  }
}

// ---- construction -------------------------------------------------------------------------

Result<Receiver> Receiver::create(const config::VehicleConfig& vehicle, config::ReceiveConfig receive,
                                  const signals::Catalog& catalog, signals::SignalTable& table,
                                  ReceiverOutputs& outputs, std::int64_t startNs) {
  auto impl = std::make_unique<ReceiverImpl>(vehicle, std::move(receive), catalog, table, outputs);
  impl->startNs = startNs;
  impl->lastTickNs = startNs;
  const dbc::Database& database = vehicle.database;
  impl->trackedByMessage.assign(database.messages.size(), -1);
  impl->busByMessage.assign(database.messages.size(), -1);

  auto slotOf = [&](const std::string& key) -> std::int32_t {
    const auto maybeIndex = catalog.indexOf(key);
    return maybeIndex ? static_cast<std::int32_t>(*maybeIndex) : NO_SLOT;
  };

  // This node's addresses: its NmStationAddress and the source addresses of the
  // extended messages it transmits (a VCU often speaks as several J1939 nodes).
  if (const dbc::Node* self = database.findNode(vehicle.node)) {
    if (const auto address = config::nodeAddress(database, *self)) {
      impl->ownAddress[*address] = true;
      impl->tpAddress = *address;
    }
  }
  for (const dbc::Message& message : database.messages) {
    if (config::sentBy(message, vehicle.node) && message.extended && !message.pseudo) {
      impl->ownAddress[j1939::Id::fromCanId(message.id).sourceAddress] = true;
    }
  }

  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    const config::BusConfig& busConfig = vehicle.buses[b];
    BusSlot bus;
    bus.name = busConfig.name;
    j1939::TpReceiverConfig tpConfig;
    tpConfig.ownAddress = impl->tpAddress;
    tpConfig.maxPacketsPerCts = impl->receive.maxPacketsPerCts;
    const std::uint8_t ownAddress = busConfig.j1939 ? busConfig.j1939->preferredAddress : impl->tpAddress;
    if (busConfig.j1939) tpConfig.ownAddress = ownAddress;
    bus.transport = std::make_unique<j1939::TpReceiver>(tpConfig);
    bus.addresses = std::make_unique<AddressMap>(ownNameOf(busConfig), ownAddress);
    bus.requestAddresses = impl->ownAddress;
    bus.requestAddresses[ownAddress] = ownAddress < j1939::NULL_ADDRESS;
    bus.load = std::make_unique<can::BusLoadMeter>(busConfig.bitrate, busConfig.dataBitrate);
    bus.loadSlot = slotOf("internal.bus." + busConfig.name + ".load");
    bus.stateSlot = slotOf("internal.bus." + busConfig.name + ".state");
    impl->buses.push_back(std::move(bus));
    for (const std::size_t messageIndex : busConfig.messages) {
      impl->busByMessage[messageIndex] = static_cast<std::int32_t>(b);
      const dbc::Message& message = database.messages[messageIndex];
      if (config::directionOf(vehicle, message) == signals::SignalDirection::Transmitted) continue;  // can-tx's
      MessageState state;
      state.messageIndex = messageIndex;
      state.bus = b;
      state.timeoutNs = impl->receive.timeoutNs[messageIndex];
      state.expectation = messageIndex < impl->receive.expectationOf.size() ? impl->receive.expectationOf[messageIndex]
                                                                            : config::ALWAYS_EXPECTED;
      if (state.expectation >= static_cast<std::int32_t>(impl->receive.expectations.size())) {
        return Error{"receive configuration: message " + message.name + " names expectation " +
                     std::to_string(state.expectation) + " of " + std::to_string(impl->receive.expectations.size())};
      }
      state.lastNs = startNs;
      const auto cycle = database.attribute(message.attributes, "GenMsgCycleTime", dbc::ObjectType::Message);
      if (cycle && cycle->kind == dbc::AttributeValue::Kind::Number && cycle->number > 0) {
        state.counters.dbcCycleNs = static_cast<std::int64_t>(cycle->number * 1e6);
      }
      state.timeoutFault = "rx_timeout." + busConfig.name + "." + message.name;
      impl->trackedByMessage[messageIndex] = static_cast<std::int32_t>(impl->messages.size());
      impl->trackedIndices.push_back(messageIndex);
      impl->messages.push_back(std::move(state));
    }
  }

  // A condition that already holds at the start (a restart while the vehicle is awake) has
  // held since the start: no wake-up grace then.
  for (const config::ReceiveExpectation& expectation : impl->receive.expectations) {
    const auto maybeSlot = catalog.indexOf(expectation.signal);
    if (!maybeSlot) {
      return Error{"receive configuration " + expectation.origin + ": no signal '" + expectation.signal +
                   "' in the catalog"};
    }
    char value[32];
    std::snprintf(value, sizeof value, "%g", expectation.equals);
    ExpectationState state{
        *maybeSlot, expectation.equals, expectation.startNs, false, startNs, expectation.signal + " = " + value};
    state.expected = impl->holds(state);
    impl->expectations.push_back(std::move(state));
  }

  for (const config::SafetyGroup& group : impl->receive.safety) {
    const dbc::Message& message = database.messages[group.dataMessage];
    j1939::SafetyPairConfig pairConfig;
    pairConfig.dataCanId = message.id;
    pairConfig.maxHeaderToDataNs = group.maxHeaderToDataNs;
    pairConfig.maxHeaderCycleNs = group.maxHeaderCycleNs;
    SafetyState state{j1939::SafetyPairChecker(pairConfig),
                      j1939::safetyHeaderCanId(message.id),
                      message.id,
                      group.dataMessage,
                      false,
                      false,
                      "j1939_76." + message.name};
    impl->safety.push_back(std::move(state));
  }

  for (const dbc::Node& node : database.nodes) {
    if (node.name == vehicle.node) continue;
    const auto address = config::nodeAddress(database, node);
    if (!address) continue;
    auto state = std::make_unique<Dm1State>();
    state->label = node.name;
    for (std::size_t f = 0; f < config::DM1_FIELDS.size(); ++f) {
      state->slots[f] = slotOf("internal.dm1." + node.name + "." + std::string(config::DM1_FIELDS[f]));
    }
    impl->dm1[*address] = std::move(state);
  }
  return Receiver(std::move(impl));
}

Receiver::Receiver(std::unique_ptr<ReceiverImpl> impl) noexcept : m_impl(std::move(impl)) {}
Receiver::Receiver(Receiver&&) noexcept = default;
Receiver& Receiver::operator=(Receiver&&) noexcept = default;
Receiver::~Receiver() = default;

void Receiver::onFrame(std::size_t bus, const can::ReceivedFrame& frame) noexcept {
  if (bus < m_impl->buses.size()) m_impl->onFrame(bus, frame);
}
void Receiver::onBusEvent(std::size_t bus, const can::BusEvent& event) noexcept {
  if (bus < m_impl->buses.size()) m_impl->onBusEvent(bus, event);
}
void Receiver::onTick(std::int64_t nowNs) noexcept {
  m_impl->onTick(nowNs);
}

std::int64_t Receiver::nextDeadlineNs() const noexcept {
  std::int64_t next = m_impl->lastTickNs + LOAD_UPDATE_NS;
  for (const MessageState& message : m_impl->messages) {
    if (message.timeoutNs <= 0) continue;
    if (!message.counters.stale) next = std::min(next, message.lastNs + message.timeoutNs + 1);
    if (!message.faultActive && m_impl->expected(message)) {
      next = std::min(next, m_impl->supervisedFromNs(message) + message.timeoutNs + 1);
    }
  }
  for (const BusSlot& bus : m_impl->buses) {
    if (const auto maybeDeadline = bus.transport->nextDeadlineNs()) next = std::min(next, *maybeDeadline);
  }
  for (const SafetyState& group : m_impl->safety) {
    // The checker keeps its last SHM time to itself: look again every quarter cycle.
    next = std::min(next, m_impl->lastTickNs + std::max<std::int64_t>(group.checker.config().maxHeaderCycleNs / 4, MS));
  }
  return next;
}

void Receiver::rollPeriodWindow() noexcept {
  for (MessageState& message : m_impl->messages) {
    message.counters.meanPeriodNs =
        message.windowIntervals > 0 ? message.windowSumNs / static_cast<std::int64_t>(message.windowIntervals) : 0;
    message.counters.maxPeriodNs = message.windowMaxNs;
    message.windowSumNs = 0;
    message.windowMaxNs = 0;
    message.windowIntervals = 0;
  }
}

std::uint32_t Receiver::batchWindowUs() const noexcept {
  return m_impl->receive.batchWindowUs;
}

std::size_t Receiver::busCount() const noexcept {
  return m_impl->buses.size();
}
const BusCounters& Receiver::counters(std::size_t bus) const noexcept {
  return m_impl->buses[bus].counters;
}
std::span<const std::size_t> Receiver::trackedMessages() const noexcept {
  return m_impl->trackedIndices;
}
const MessageCounters& Receiver::messageCounters(std::size_t messageIndex) const noexcept {
  if (messageIndex >= m_impl->trackedByMessage.size() || m_impl->trackedByMessage[messageIndex] < 0) {
    return m_impl->noCounters;
  }
  return m_impl->messages[static_cast<std::size_t>(m_impl->trackedByMessage[messageIndex])].counters;
}

std::vector<can::IdFilter> Receiver::filters(std::size_t busIndex) const {
  std::vector<can::IdFilter> result;
  const config::VehicleConfig& vehicle = m_impl->vehicle;
  auto addPgn = [&](std::uint32_t pgn) {
    // PGN bits 8..25 of the ID; for PDU1 PGNs the PS byte is the destination: match any.
    const bool pdu1 = ((pgn >> 8) & 0xFF) < j1939::PDU2_THRESHOLD;
    const std::uint32_t mask = pdu1 ? 0x03FF0000u : 0x03FFFF00u;
    const can::IdFilter filter{(pgn << 8) & mask, mask, true};
    if (std::find(result.begin(), result.end(), filter) == result.end()) result.push_back(filter);
  };
  for (const std::size_t messageIndex : vehicle.buses[busIndex].messages) {
    const dbc::Message& message = vehicle.database.messages[messageIndex];
    if (message.extended) {
      addPgn(j1939::Id::fromCanId(message.id).pgn());
    } else {
      result.push_back(can::IdFilter{message.id, can::STANDARD_ID_MASK, false});
    }
  }
  addPgn(j1939::PGN_REQUEST);
  addPgn(j1939::PGN_TP_CM);
  addPgn(j1939::PGN_TP_DT);
  addPgn(j1939::PGN_DM1);
  addPgn(j1939::PGN_ADDRESS_CLAIMED);
  for (const SafetyState& group : m_impl->safety) {
    if (m_impl->busByMessage[group.messageIndex] == static_cast<std::int32_t>(busIndex)) {
      result.push_back(can::IdFilter{group.headerCanId, can::EXTENDED_ID_MASK, true});
    }
  }
  for (const config::ForwardRule& rule : m_impl->receive.forward) {
    if (rule.fromBus != busIndex) continue;
    if (rule.byPgn) {
      addPgn(rule.id);
    } else {
      result.push_back(
          can::IdFilter{rule.id, rule.extended ? can::EXTENDED_ID_MASK : can::STANDARD_ID_MASK, rule.extended});
    }
  }
  return result;
}

}  // namespace openvcu::canrx
