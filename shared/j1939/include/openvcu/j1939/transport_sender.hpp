#pragma once
// SAE J1939-21 transport protocol (TP), sending side (originator): messages of 9..1785 bytes
// go out as an announcement on TP.CM followed by numbered 7-byte packets on TP.DT (design
// note: docs/design/j1939-transport-sender.md; frame layout: transport.hpp).
//
//   BAM from us (0x21) to global, DM1 of 20 bytes, packets 50 ms apart:
//     t=0    0x1CECFF21  20 14 00 03 FF CA FE 00
//     t=50   0x1CEBFF21  01 b0..b6   t=100 02 b7..b13   t=150 03 b14..b19 FF  -> Completed
//   RTS/CTS from us (0x21) to 0x20, PGN 0xFEEB, 20 bytes:
//     we send 0x1CEC2021  10 14 00 03 FF EB FE 00        (RTS, no limit per CTS)
//     0x1CEC2120  11 03 01 FF FF EB FE 00  -> we send 0x1CEB2021 01 .., 02 .., 03 .. FF
//     0x1CEC2120  13 14 00 03 FF EB FE 00  (EndOfMsgAck)  -> Completed

#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/transport.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace openvcu::j1939 {

/// J1939-21 5.12.3: 2 retries per request, "this includes the situation where the CTS is
/// used to request the retransmission of data packet(s)"; beyond it, Abort reason 5.
inline constexpr std::uint8_t TP_MAX_RETRANSMIT_REQUESTS = 2;

/// What send() did with a message.
enum class TpSendStatus : std::uint8_t {
  Started,             ///< the RTS or BAM went out in this call
  Queued,              ///< waits for its destination (or a session place) to be free
  RefusedNoAddress,    ///< our address is NULL (0xFE) or global: we may not transmit
  RefusedSize,         ///< not 9..1785 bytes
  RefusedPgn,          ///< more than 18 bits
  RefusedPriority,     ///< more than 7
  RefusedDestination,  ///< the null address (0xFE) or our own
  RefusedQueueFull,    ///< the queue holds queueCapacity messages already
};
inline constexpr std::size_t TP_SEND_STATUS_COUNT = 8;

/// "Started", "RefusedQueueFull", ... for logs.
[[nodiscard]] std::string_view tpSendStatusName(TpSendStatus status) noexcept;

/// How an accepted message ended.
enum class TpSendOutcome : std::uint8_t {
  Completed,       ///< BAM: the last packet went out; RTS/CTS: the EndOfMsgAck arrived
  AbortedByPeer,   ///< the destination sent an Abort (reason: the peer's)
  AbortSent,       ///< we sent an Abort for a protocol error of the peer (reason: ours)
  TimedOut,        ///< T3 or T4 passed; we sent Abort reason 3
  AddressChanged,  ///< our address changed: ended (or never started) without a frame
};
inline constexpr std::size_t TP_SEND_OUTCOME_COUNT = 5;

/// "Completed", "TimedOut", ... for logs.
[[nodiscard]] std::string_view tpSendOutcomeName(TpSendOutcome outcome) noexcept;

/// The end of one message accepted by send(), started or still queued.
struct TpSendResult {
  std::uint32_t pgn{};
  std::uint8_t destination{};  ///< GLOBAL_ADDRESS (0xFF) for BAM
  TpSendOutcome outcome{};
  TpAbortReason reason{};      ///< None for Completed and AddressChanged
  friend bool operator==(const TpSendResult&, const TpSendResult&) = default;
};

/// Where the sender puts its output. Called synchronously from send(), onFrame(), poll()
/// and setOwnAddress(); the sink must not call back into the sender.
/// Why virtual: one indirect call per output, no std::function and no allocation.
class TpSendSink {
 public:
  virtual ~TpSendSink() = default;
  /// An RTS, BAM, Abort (TP.CM) or data packet (TP.DT) to transmit now, in this order.
  /// With rtsPacketGapNs = 0 a CTS can produce up to 255 packets in one call: the sink
  /// must be able to queue them (or the gap must be set).
  virtual void send(const TpFrame& frame) noexcept = 0;
  /// A message accepted by send() has ended; exactly once per accepted message.
  virtual void finished(const TpSendResult& result) noexcept = 0;
};

struct TpSenderConfig {
  /// Our J1939 address, the source of every frame; NULL_ADDRESS (0xFE) or GLOBAL_ADDRESS
  /// refuses every message (RefusedNoAddress) until setOwnAddress() gives a valid one.
  std::uint8_t ownAddress{NULL_ADDRESS};
  /// Sessions running at once, 1..255 (one per destination, BAM counting as the global
  /// destination); more wait in the queue.
  std::size_t maxSessions{4};
  /// Messages waiting for their destination or a session place (at most 4096); beyond,
  /// RefusedQueueFull.
  std::size_t queueCapacity{8};
  /// RTS byte 4, 1..255: the most packets one CTS may ask for (255: no limit).
  std::uint8_t maxPacketsPerCts{TP_NO_PACKET_LIMIT};
  /// BAM: from the announcement to packet 1 and between packets; clamped to 50..200 ms.
  std::int64_t bamPacketGapNs{TP_BAM_MIN_GAP_NS};
  /// RTS/CTS: between the packets of a CTS window; 0 sends a window back to back.
  std::int64_t rtsPacketGapNs{0};
  /// CTS asking for packets again, per session; one more gets Abort reason 5.
  std::uint8_t maxRetransmitRequests{TP_MAX_RETRANSMIT_REQUESTS};
};

/// What happened since construction. At any time:
///   sessionsStarted == sessionsCompleted + sessionsAbortedByPeer + sessionsAbortedByUs +
///                      sessionsTimedOut + sessionsEndedByAddressChange + activeSessions()
///   messagesQueued  == messagesStartedFromQueue + queuedDroppedByAddressChange +
///                      queuedMessages()
struct TpSenderCounters {
  std::uint64_t sessionsStarted{};        ///< RTS or BAM sent
  std::uint64_t sessionsCompleted{};
  std::uint64_t sessionsAbortedByPeer{};  ///< Abort from the destination
  std::uint64_t sessionsAbortedByUs{};    ///< Abort sent for a bad CTS or EndOfMsgAck
  std::uint64_t sessionsTimedOut{};       ///< T3 or T4: Abort reason 3 sent
  std::uint64_t sessionsEndedByAddressChange{};
  std::uint64_t messagesQueued{};         ///< send() returned Queued
  std::uint64_t messagesStartedFromQueue{};
  std::uint64_t queuedDroppedByAddressChange{};
  std::uint64_t refusedQueueFull{};
  std::uint64_t refusedInvalid{};         ///< size, PGN, priority or destination
  std::uint64_t refusedNoAddress{};
  std::uint64_t retransmitRequests{};     ///< CTS asking for packets sent before
  std::uint64_t holdsReceived{};          ///< CTS(0)
  std::uint64_t framesIgnored{};          ///< CTS, EndOfMsgAck, Abort to us that changed nothing
  std::uint64_t abortsSent{};
  friend bool operator==(const TpSenderCounters&, const TpSenderCounters&) = default;
};

/// Sends J1939-21 transport sessions on one CAN bus from one own address: one BAM at a time
/// and one RTS/CTS session per destination (J1939-21), up to maxSessions at once; further
/// messages wait in a FIFO queue and start, in order per destination, when their destination
/// is free. Time is passed in; the sender never waits: it produces frames only inside its
/// calls and tells the caller when to call poll() next (nextDeadlineNs()). onFrame(),
/// send() and setOwnAddress() apply passed deadlines first, so the result does not depend on
/// how often poll() runs. A frame at or after a timeout deadline is late.
///
/// @note not thread-safe: one thread drives one sender. Real-time safe after construction:
///       noexcept, no allocation, O(maxSessions + queueCapacity) per call (plus the frames
///       produced), one PGN comparison for frames other than TP.CM.
class TpSender {
 public:
  /// Allocates (maxSessions + queueCapacity) x 1785 bytes of buffer, once.
  explicit TpSender(const TpSenderConfig& config);

  /// Copies `data` and starts its session now (RTS or BAM goes to the sink) or queues it.
  /// `destination` GLOBAL_ADDRESS sends by BAM, any other address by RTS/CTS. `priority`
  /// is that of the session's TP.CM and TP.DT frames: J1939-21's default is 7
  /// (TP_CM_PRIORITY). Nothing is kept and finished() is not called for a refused message.
  [[nodiscard]] TpSendStatus send(std::uint32_t pgn, std::uint8_t destination,
                                  std::uint8_t priority, std::span<const std::uint8_t> data,
                                  std::int64_t nowNs, TpSendSink& sink) noexcept;

  /// One received extended CAN frame (29-bit `canId`). Only TP.CM from a destination of a
  /// running session to our address counts (CTS, EndOfMsgAck, Abort); the rest returns at once.
  void onFrame(std::uint32_t canId, std::span<const std::uint8_t> data, std::int64_t nowNs,
               TpSendSink& sink) noexcept;

  /// Sends the packets that are due and applies passed timeouts (Abort reason 3).
  void poll(std::int64_t nowNs, TpSendSink& sink) noexcept;

  /// Our address changed (J1939-81 address claim lost or a new address claimed). Running
  /// sessions end as AddressChanged without a frame (the old address is no longer ours;
  /// their receivers time out). Queued messages start from the new address, or end as
  /// AddressChanged when it is NULL_ADDRESS or GLOBAL_ADDRESS (and those addressed to the
  /// new address itself). The same address: no effect.
  void setOwnAddress(std::uint8_t address, std::int64_t nowNs, TpSendSink& sink) noexcept;

  /// When poll() has work: the next packet or the earliest timeout; empty when no session
  /// runs (queued messages start inside other calls, they need no poll).
  [[nodiscard]] std::optional<std::int64_t> nextDeadlineNs() const noexcept;

  /// Sessions running (RTS or BAM sent, not yet ended).
  [[nodiscard]] std::size_t activeSessions() const noexcept { return m_activeSessions; }
  /// Messages waiting to start.
  [[nodiscard]] std::size_t queuedMessages() const noexcept { return m_queuedMessages; }
  [[nodiscard]] std::uint8_t ownAddress() const noexcept { return m_ownAddress; }
  [[nodiscard]] const TpSenderCounters& counters() const noexcept { return m_counters; }
  [[nodiscard]] const TpSenderConfig& config() const noexcept { return m_config; }

 private:
  enum class State : std::uint8_t {
    Free,
    Queued,
    Broadcasting,  ///< BAM: the next packet at deadlineNs
    WaitingCts,    ///< RTS or a window sent, not the last packet: T3
    Holding,       ///< CTS(0) received: T4
    SendingWindow, ///< rtsPacketGapNs > 0: the next packet of the window at deadlineNs
    WaitingAck,    ///< the last packet sent: T3 for the EndOfMsgAck
  };
  struct Session {
    std::int64_t deadlineNs{};
    std::uint64_t ticket{};       ///< queue order
    std::uint32_t pgn{};
    std::uint16_t size{};
    std::uint16_t nextPacket{};   ///< the next packet to send, 1..packets
    std::uint16_t windowEnd{};    ///< last packet of the current (or last) CTS window
    std::uint16_t windowStart{};  ///< next packet number of the last CTS (1 before any)
    std::uint8_t destination{};
    std::uint8_t priority{};
    std::uint8_t packets{};
    std::uint8_t retransmitRequests{};
    State state{State::Free};
  };

  void handleCts(Session& session, std::span<const std::uint8_t> data, std::int64_t nowNs,
                 TpSendSink& sink) noexcept;
  void handleEndOfMsgAck(Session& session, std::span<const std::uint8_t> data,
                         TpSendSink& sink) noexcept;
  void start(Session& session, std::int64_t nowNs, TpSendSink& sink) noexcept;
  void startQueued(std::int64_t nowNs, TpSendSink& sink) noexcept;
  void expire(std::int64_t nowNs, TpSendSink& sink) noexcept;
  void sendWindowPackets(Session& session, std::int64_t nowNs, TpSendSink& sink) noexcept;
  void sendPacket(Session& session, TpSendSink& sink) noexcept;
  void abortSession(Session& session, TpAbortReason reason, TpSendOutcome outcome,
                    TpSendSink& sink) noexcept;
  void finish(Session& session, TpSendOutcome outcome, TpAbortReason reason,
              TpSendSink& sink) noexcept;
  void sendControl(const Session& session, const std::array<std::uint8_t, TP_FRAME_LENGTH>& data,
                   TpSendSink& sink) noexcept;
  [[nodiscard]] TpSendStatus check(std::uint32_t pgn, std::uint8_t destination,
                                   std::uint8_t priority, std::size_t size) const noexcept;
  [[nodiscard]] bool canStart(std::uint8_t destination) const noexcept;
  [[nodiscard]] std::span<std::uint8_t> bufferOf(const Session& session) noexcept;

  static constexpr std::uint16_t NO_SESSION = 0xFFFF;
  static constexpr std::size_t DESTINATIONS = 256;

  TpSenderConfig m_config;
  std::uint8_t m_ownAddress{};
  std::vector<Session> m_sessions;      ///< maxSessions + queueCapacity records
  std::vector<std::uint8_t> m_buffers;  ///< one TP_MAX_MESSAGE_SIZE buffer per record
  std::array<std::uint16_t, DESTINATIONS> m_running{};  ///< destination -> running session
  std::size_t m_activeSessions{};
  std::size_t m_queuedMessages{};
  std::uint64_t m_nextTicket{};
  TpSenderCounters m_counters;
};

}  // namespace openvcu::j1939
