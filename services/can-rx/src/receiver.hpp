#pragma once
// The receive path of every configured bus, independent of processes and links so that
// it can be tested frame by frame: a ReceivedFrame goes in; decoded values go to the
// signal table's bus plane; J1939 requests, transport sessions, DM1 and J1939-76 safety
// groups are handled; forwarding rules and every frame go out through ReceiverOutputs.
//
//   canrx::Receiver sut(vehicle, receiveConfig, catalog, table, outputs);
//   sut.onFrame(busIndex, receivedFrame);      // per frame: noexcept, allocation-free
//   sut.onTick(nowNs);                         // timeouts (staleness, TP), bus load
//
// Decisions (services/can-rx/README.md):
//   - a frame of a message this node transmits is published on "rx" but not decoded:
//     can-tx writes what it sent to the bus plane itself;
//   - a message is stale when nothing arrived for its timeout (also right after start:
//     an ECU that never speaks is reported), its signals are marked Stale and the fault
//     "rx_timeout.<bus>.<Message>" is raised; the next frame clears both. The fault only
//     while its sender is expected (receive.json "expectedWhen": a wake condition read from
//     the table on each tick), counted from when it became so; when the condition ends an
//     active fault is cleared, the signals stay Stale;
//   - TP control answers (CTS, EndOfMsgAck, Abort) go out on the same link directly,
//     so reassembly never depends on another service.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "openvcu/can/link.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"
#include "openvcu/config/receive.hpp"

namespace openvcu::canrx {

/// Where the receiver's results go besides the table. The app sends them to iceoryx,
/// LCM and the links; tests record them.
class ReceiverOutputs {
 public:
  virtual ~ReceiverOutputs() = default;
  /// Every frame read from bus `bus` ("rx" stream).
  virtual void received(std::size_t bus, const can::ReceivedFrame& frame) noexcept = 0;
  /// A J1939 Request for this node (or global), parsed (j1939::parseRequest): for can-tx
  /// ("req" stream). `monotonicNs`: when its frame was received.
  virtual void request(std::size_t bus, const j1939::Request& request, std::int64_t monotonicNs) noexcept = 0;
  /// A J1939 network-management frame for can-tx ("net" stream): every Address Claimed
  /// (PGN 0xEE00) and the TP.CM CTS, EndOfMsgAck and Abort frames to this node's address.
  virtual void network(std::size_t bus, const can::ReceivedFrame& frame) noexcept = 0;
  /// A frame to forward onto bus `toBus` (can-tx's "send" stream).
  virtual void forward(std::size_t toBus, const can::Frame& frame) noexcept = 0;
  /// A TP control frame to send on bus `bus` now (CTS, EndOfMsgAck, Abort). false: not sent.
  virtual bool transmit(std::size_t bus, const can::Frame& frame) noexcept = 0;
  /// A fault raised or cleared (rare: allocation allowed).
  virtual void fault(const ipc::FaultEvent& event) = 0;
  /// A node's DM1 whose content changed, or unchanged DM1_REPUBLISH_NS after the last one
  /// (rare: allocation allowed). The app publishes it (EventKind::Dm1); `service` and
  /// `instance` are left for it to fill.
  virtual void dm1(const ipc::NodeDm1& message) = 0;
};

/// An unchanged DM1 of a node goes out again after this long (J1939-73 sends DM1 once a
/// second), so a subscriber started later learns every node's DTCs.
inline constexpr std::int64_t DM1_REPUBLISH_NS = 1'000'000'000;

/// Counters of one bus (read by the heartbeat).
struct BusCounters {
  std::uint64_t frames{};         ///< frames read
  std::uint64_t decoded{};        ///< frames decoded into the table
  std::uint64_t ownFrames{};      ///< frames of messages this node transmits (not decoded)
  std::uint64_t unknownIds{};     ///< frames matching no DBC message of this bus
  std::uint64_t decodeErrors{};   ///< frames shorter than their message (signals missing)
  std::uint64_t outOfRange{};     ///< signal values outside their DBC range
  std::uint64_t requests{};       ///< J1939 requests for this node handed to can-tx (well-formed ones)
  std::uint64_t tpSessions{};     ///< transport sessions started
  std::uint64_t tpCompleted{};    ///< ... reassembled
  std::uint64_t tpAborted{};      ///< ... aborted (either side) or timed out
  std::uint64_t addressClaims{};  ///< J1939-81 Address Claimed frames seen (any node, Cannot Claim too)
  std::uint64_t ownAddressChanges{};  ///< the VCU's address on this bus changed (seen in its claims)
  std::uint64_t dm1Messages{};    ///< DM1 messages decoded
  std::uint64_t safetyFailures{}; ///< SDMs refused by the J1939-76 check
  std::uint64_t forwarded{};      ///< frames forwarded to another bus
  std::uint64_t busErrors{};      ///< bus events other than LinkUp
  std::uint64_t timeouts{};       ///< messages that went stale
  std::uint64_t loadPermille{};   ///< bus load over the last second, 0.1 % units
};

/// Receive statistics of one message (for the heartbeat and `vcu status`).
struct MessageCounters {
  std::uint64_t frames{};
  std::int64_t dbcCycleNs{};         ///< GenMsgCycleTime, 0 when none
  std::int64_t meanPeriodNs{};       ///< mean interval over the last heartbeat period
  std::int64_t maxPeriodNs{};        ///< largest interval over the last heartbeat period
  bool stale{};
};

struct ReceiverImpl;

/// @note restricted thread-safe: one thread. onFrame/onTick are noexcept and allocate
///       nothing except to publish a fault event (a state change, not per frame).
class Receiver {
 public:
  /// Compiles codecs and the lookup tables. `table` and `outputs` must outlive it.
  /// Fails when a bus has no J1939 address for TP answers and ... never otherwise.
  static Result<Receiver> create(const config::VehicleConfig& vehicle, config::ReceiveConfig receive,
                                 const signals::Catalog& catalog, signals::SignalTable& table,
                                 ReceiverOutputs& outputs, std::int64_t startNs);
  Receiver(Receiver&&) noexcept;
  Receiver& operator=(Receiver&&) noexcept;
  ~Receiver();

  void onFrame(std::size_t bus, const can::ReceivedFrame& frame) noexcept;
  void onBusEvent(std::size_t bus, const can::BusEvent& event) noexcept;
  /// Staleness, TP timeouts, J1939-76 header cycles, bus load. Call it at
  /// nextDeadlineNs() (and after frames arrived, when that moved earlier); more often is
  /// harmless.
  void onTick(std::int64_t nowNs) noexcept;
  /// When onTick must run next: the earliest receive timeout still running, TP deadline
  /// or J1939-76 check, and at least every LOAD_UPDATE_NS for the bus-load slots.
  /// @note noexcept, allocation-free; O(tracked messages).
  [[nodiscard]] std::int64_t nextDeadlineNs() const noexcept;
  static constexpr std::int64_t LOAD_UPDATE_NS = 250'000'000;
  /// The receive file's batch window (for the service loop).
  [[nodiscard]] std::uint32_t batchWindowUs() const noexcept;
  /// Closes the heartbeat window of the per-message period statistics.
  void rollPeriodWindow() noexcept;

  [[nodiscard]] std::size_t busCount() const noexcept;
  [[nodiscard]] const BusCounters& counters(std::size_t bus) const noexcept;
  /// Messages this receiver tracks (received messages of every bus), by DBC index.
  [[nodiscard]] std::span<const std::size_t> trackedMessages() const noexcept;
  [[nodiscard]] const MessageCounters& messageCounters(std::size_t messageIndex) const noexcept;
  /// Acceptance filters for bus `bus` (BusFilter::Dbc): its messages plus the J1939 PGNs
  /// the receiver handles and the forwarding rules.
  [[nodiscard]] std::vector<can::IdFilter> filters(std::size_t bus) const;

 private:
  explicit Receiver(std::unique_ptr<ReceiverImpl> impl) noexcept;
  std::unique_ptr<ReceiverImpl> m_impl;
};

}  // namespace openvcu::canrx
