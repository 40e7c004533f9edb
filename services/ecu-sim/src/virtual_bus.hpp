#pragma once
// The simulated nodes' side of the bus: every DBC message a node other than this VCU
// transmits, with its payload (the DBC's initial payload, then what the node models set),
// its cycle (GenMsgCycleTime; messages without one go out only when a model asks) and an
// absolute next deadline; and the VCU's messages decoded as they are received. Signals are
// named by bridge::SignalRef (DBC message and signal index) and encoded and decoded through
// the messages' bridge::MessageBinding (no signal table here: values stay in the process).
//
//   auto busResult = ecusim::VirtualBus::create(vehicle);
//   const auto soc = bus.output("HVESSD2_PGN61585", "HS_FastUpdSOC");   // a bridge::SignalRef, resolved once
//   bus.set(*soc, 62.5);                                                     // encoded at once
//   bus.sendDue(now, [&](std::size_t busIndex, const can::Frame& frame) { links[busIndex]->send(frame); });
//   bus.receive(frame, atNs);   // a VCU frame: decoded; bus.get(*relay) reads it

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "openvcu/bridge/message_binding.hpp"
#include "openvcu/can/frame.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::ecusim {

inline constexpr std::int64_t NEVER = std::numeric_limits<std::int64_t>::max();

/// One frame a simulated node sends: its bus and identifier.
struct FrameTarget {
  std::size_t bus{};
  std::uint32_t id{};
  bool extended{};
};

/// @note restricted thread-safe: one thread (the simulation's).
class VirtualBus {
 public:
  static Result<VirtualBus> create(const config::VehicleConfig& vehicle);

  /// A signal of a simulated node's message (for set()). Errors name the message and
  /// signal (and say no simulated node transmits it).
  Result<bridge::SignalRef> output(const std::string& message, const std::string& signal) const;
  /// A signal of a VCU message (for get()). Errors name the message and signal.
  Result<bridge::SignalRef> input(const std::string& message, const std::string& signal) const;
  /// The transmitted message `name`, for sendNow().
  Result<std::size_t> outputMessage(const std::string& name) const;

  /// Sets a physical value of an output() signal (clamped to the signal's DBC range; a
  /// non-finite value is ignored); no allocation. A ref of no transmitted message: no-op.
  void set(bridge::SignalRef ref, double value) noexcept;
  /// The last received value of an input() signal; NaN before the first frame of its
  /// message (and for a ref of no VCU message).
  [[nodiscard]] double get(bridge::SignalRef ref) const noexcept {
    const Rx* rx = rxOf(ref);
    return rx != nullptr ? rx->values[ref.signal] : std::numeric_limits<double>::quiet_NaN();
  }
  /// The value an output() signal has in its message's payload now (what the node sends);
  /// NaN when it is not decoded (not active, not inside the payload) or for a ref of no
  /// transmitted message. @note noexcept, allocation-free.
  [[nodiscard]] double current(bridge::SignalRef ref) const noexcept;
  /// true when a simulated node transmits ref's message (set() writes it).
  [[nodiscard]] bool isOutput(bridge::SignalRef ref) const noexcept {
    return ref.message < m_txByMessage.size() && m_txByMessage[ref.message] >= 0;
  }
  /// true when the VCU transmits ref's message (get() reads it).
  [[nodiscard]] bool isInput(bridge::SignalRef ref) const noexcept { return rxOf(ref) != nullptr; }
  /// CLOCK_MONOTONIC ns of the last frame of a VCU message; 0 when none came.
  [[nodiscard]] std::int64_t lastReceivedNs(bridge::SignalRef ref) const noexcept {
    const Rx* rx = rxOf(ref);
    return rx != nullptr ? rx->lastNs : 0;
  }

  /// Decodes `frame` when it is a VCU message; false otherwise.
  bool receive(const can::Frame& frame, std::int64_t atNs) noexcept;

  /// Sends every cyclic message due at `nowNs` (missed cycles are skipped, never sent in a
  /// burst) through `send(busIndex, frame)`; messages of silent nodes are not sent.
  template <typename Send>
  void sendDue(std::int64_t nowNs, Send&& send);
  /// Sends one message now (an answer to a request), unless its node is silent.
  template <typename Send>
  void sendNow(std::size_t message, std::int64_t nowNs, Send&& send);
  [[nodiscard]] std::int64_t nextDueNs() const noexcept;

  /// Starts the cycles at `nowNs`: a node's messages share one phase, the nodes 1 ms apart.
  void start(std::int64_t nowNs) noexcept;

  /// Silences (or revives) every message `node` transmits. false for an unknown node.
  bool setSilent(const std::string& node, bool silent);
  [[nodiscard]] std::vector<std::string> nodes() const;
  /// The frames of the DBC message `messageOrNode` on every bus that carries it, or of every
  /// message the node `messageOrNode` sends; empty when no simulated node sends it.
  /// @note reads only what create() set: safe beside the simulation thread.
  [[nodiscard]] std::vector<FrameTarget> transmitted(const std::string& messageOrNode) const;
  [[nodiscard]] std::uint32_t frameId(std::size_t message) const noexcept { return m_tx[message].frame.id; }
  [[nodiscard]] std::uint64_t framesSent() const noexcept { return m_sent; }
  [[nodiscard]] std::uint64_t framesReceived() const noexcept { return m_received; }

 private:
  struct Tx {
    std::size_t messageIndex{};  ///< into the database
    std::size_t bus{};
    std::string node;
    can::Frame frame;
    std::int64_t cycleNs{};  ///< 0: on request only
    std::int64_t nextNs{NEVER};
    std::size_t phase{};  ///< its node's phase in ms (start())
    bool silent{};
  };
  struct Rx {
    std::size_t messageIndex{};
    std::uint32_t id{};
    bool extended{};
    std::vector<double> values;  ///< by signal index, NaN before the first frame
    std::int64_t lastNs{};
  };

  [[nodiscard]] const Rx* rxOf(bridge::SignalRef ref) const noexcept {
    if (ref.message >= m_rxByMessage.size() || m_rxByMessage[ref.message] < 0) return nullptr;
    return &m_rx[static_cast<std::size_t>(m_rxByMessage[ref.message])];
  }

  const config::VehicleConfig* m_vehicle{};
  bridge::DatabaseBinding m_bindings;  ///< every DBC message's codec, no table slots
  std::vector<Tx> m_tx;
  std::vector<Rx> m_rx;
  std::vector<std::int32_t> m_txByMessage;  ///< DBC message index -> index into m_tx (first bus), or -1
  std::vector<std::int32_t> m_rxByMessage;  ///< DBC message index -> index into m_rx, or -1
  std::uint64_t m_sent{};
  std::uint64_t m_received{};
};

template <typename Send>
void VirtualBus::sendDue(std::int64_t nowNs, Send&& send) {
  for (Tx& tx : m_tx) {
    if (tx.cycleNs <= 0 || tx.nextNs > nowNs) continue;
    const std::int64_t late = nowNs - tx.nextNs;
    tx.nextNs += (late / tx.cycleNs + 1) * tx.cycleNs;
    if (tx.silent) continue;
    send(tx.bus, tx.frame);
    ++m_sent;
  }
}

template <typename Send>
void VirtualBus::sendNow(std::size_t message, std::int64_t, Send&& send) {
  Tx& tx = m_tx[message];
  if (tx.silent) return;
  send(tx.bus, tx.frame);
  ++m_sent;
}

}  // namespace openvcu::ecusim
