#pragma once
// The scripted J1939 peer of simulation.json's "j1939Peer" (config::SimPeerConfig): one more
// node on a J1939 bus that claims its address at the start (and sends a global Request for
// Address Claimed, so it learns who was there before it), runs its script (Address
// Claimed for an address, Requests to the VCU), answers Requests for Address Claimed, keeps
// a j1939::AddressTable from every claim it sees and receives the answers sent to it:
// single frames, BAM and RTS/CTS (a j1939::TpReceiver at its current address; its CTS and
// EndOfMsgAck go out on the bus). Answers are counted per requested PGN and logged decoded
// (DM1/DM2 DTCs, identification text).
//
//   peer.emplace(simConfig.peer.value(), runtime.log());
//   peer->receive(frame, atNs);           // every received frame of any bus index
//   peer->step(nowNs, send);              // script steps due, TP timeouts, queued frames
//   sleep until min(..., peer->nextDueNs())

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

#include "openvcu/can/frame.hpp"
#include "openvcu/config/simulation_peer.hpp"
#include "openvcu/j1939/address_table.hpp"
#include "openvcu/j1939/transport.hpp"
#include "openvcu/service/logger.hpp"
#include "virtual_bus.hpp"

namespace openvcu::ecusim {

/// @note restricted thread-safe: one thread (the simulation's) calls receive(), step() and
///       start(); the counters are atomics any thread may read (heartbeat). Allocation-free
///       per frame except the log lines of answers and claims (rare events).
class J1939Peer final : private j1939::TpSink {
 public:
  J1939Peer(const config::SimPeerConfig& config, service::Logger& log);

  /// The script's times count from `nowNs`; the peer's claim and its Request for Address
  /// Claimed go out at the next step().
  void start(std::int64_t nowNs) noexcept;
  /// A frame received on bus `busIndex` (other buses are ignored).
  void receive(std::size_t busIndex, const can::Frame& frame, std::int64_t atNs) noexcept;
  /// Sends the script steps due, the TP frames and claims queued, and applies TP deadlines.
  template <typename Send>
  void step(std::int64_t nowNs, Send&& send);
  [[nodiscard]] std::int64_t nextDueNs() const noexcept;

  // Counters (heartbeat: peer_*).
  std::atomic<std::int64_t> claimsSeen{};    ///< Address Claimed frames from other nodes
  std::atomic<std::int64_t> vcuAddress{-1};  ///< the VCU's address as last claimed, -1 none
  std::atomic<std::int64_t> ownAddress{-1};  ///< the peer's address, -1 none (lost it)
  std::atomic<std::int64_t> requestsSent{};
  std::atomic<std::int64_t> tpCompleted{};  ///< BAM and RTS/CTS messages received whole
  std::atomic<std::int64_t> dm1Dtcs{-1};    ///< DTCs in the last DM1 from the VCU, -1 none
  std::atomic<std::int64_t> nacks{};        ///< Acknowledgements (PGN 59392) to the peer
  /// Answers by the config's requestedPgns index: messages of a requested PGN from the
  /// address the request went to, while that request is outstanding (one per request).
  [[nodiscard]] const config::SimPeerConfig& config() const noexcept { return m_config; }
  [[nodiscard]] std::atomic<std::int64_t>& answers(std::size_t index) noexcept { return m_answers[index]; }

 private:
  struct Outstanding {
    bool waiting{};
    std::uint8_t from{};
  };

  void send(const j1939::TpFrame& frame) noexcept override;
  void completed(const j1939::TpMessage& message) noexcept override;
  void event(const j1939::TpEvent& event) noexcept override;
  void onClaim(std::uint8_t source, const j1939::Name& name, std::int64_t atNs) noexcept;
  void onMessage(std::uint32_t pgn, std::uint8_t source, std::span<const std::uint8_t> data) noexcept;
  void queue(std::uint32_t canId, std::span<const std::uint8_t> data) noexcept;
  void queueClaim(std::uint8_t address) noexcept;
  void runStep(const config::SimPeerStep& step) noexcept;
  void setOwn(std::uint8_t address) noexcept;

  static constexpr std::size_t QUEUE = 32;  ///< frames between two steps (CTS, EoMA, claims)

  config::SimPeerConfig m_config;
  service::Logger* m_log;
  j1939::AddressTable m_table;
  j1939::TpReceiver m_tp;
  std::unique_ptr<std::atomic<std::int64_t>[]> m_answers;
  std::unique_ptr<Outstanding[]> m_outstanding;
  std::array<can::Frame, QUEUE> m_queue{};
  std::size_t m_queued{};
  std::uint8_t m_address{};  ///< current; NULL_ADDRESS once lost
  std::size_t m_next{};      ///< next script step
  std::int64_t m_startNs{-1};
  std::int64_t m_nowNs{};
};

template <typename Send>
void J1939Peer::step(std::int64_t nowNs, Send&& send) {
  m_nowNs = nowNs;
  if (m_startNs < 0) return;
  while (m_next < m_config.script.size() && m_startNs + m_config.script[m_next].atNs <= nowNs) {
    runStep(m_config.script[m_next++]);
  }
  m_tp.poll(nowNs, *this);
  for (std::size_t i = 0; i < m_queued; ++i) send(m_config.busIndex, m_queue[i]);
  m_queued = 0;
}

}  // namespace openvcu::ecusim
