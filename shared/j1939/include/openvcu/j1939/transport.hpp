#pragma once
// SAE J1939-21 transport protocol (TP), receiving side: messages of 9..1785 bytes arrive as
// an announcement on TP.CM followed by numbered 7-byte packets on TP.DT (design note:
// docs/design/j1939-transport.md). Bytes are numbered from 0 here, as in data[i];
// J1939-21 numbers them from 1.
//
//   TP.CM byte 0 control | bytes 1-4 by control | bytes 5-7 PGN of the message, LSB first
//     RTS   10 size(LSB, MSB) packets max-packets-per-CTS | to one address, answered by CTS
//     CTS   11 count next-packet FF FF                    | receiver -> originator
//     EoMA  13 size(LSB, MSB) packets FF                  | receiver -> originator, after the last
//     BAM   20 size(LSB, MSB) packets FF                  | to global, never answered
//     Abort FF reason role(FC | role) FF FF               | either side
//   TP.DT byte 0 sequence number 1..n | bytes 1-7 data (the last packet padded with FF)
//
//   BAM from 0x10, DM1 of 20 bytes:
//     0x1CECFF10  20 14 00 03 FF CA FE 00   then 0x1CEBFF10  01 .., 02 .., 03 .. FF
//   RTS from 0x20 to us (0x21), PGN 0xFEEB, 20 bytes:
//     0x1CEC2120  10 14 00 03 FF EB FE 00   -> we send CTS  0x1CEC2021  11 03 01 FF FF EB FE 00
//     0x1CEB2120  01 .., 02 .., 03 ..       -> we send EoMA 0x1CEC2021  13 14 00 03 FF EB FE 00

#include "openvcu/j1939/id.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_TP_CM = 0xEC00;  ///< SAE J1939-21 PGN 60416 TP.CM connection management
inline constexpr std::uint32_t PGN_TP_DT = 0xEB00;  ///< SAE J1939-21 PGN 60160 TP.DT data transfer

inline constexpr std::uint8_t TP_CM_RTS = 0x10;          ///< J1939-21 TP.CM_RTS request to send, 0x10 (16)
inline constexpr std::uint8_t TP_CM_CTS = 0x11;          ///< J1939-21 TP.CM_CTS clear to send, 0x11 (17)
inline constexpr std::uint8_t TP_CM_END_OF_MSG_ACK = 0x13;  ///< J1939-21 TP.CM_EndOfMsgAck, 0x13 (19)
inline constexpr std::uint8_t TP_CM_BAM = 0x20;          ///< J1939-21 TP.CM_BAM broadcast announce, 0x20 (32)
inline constexpr std::uint8_t TP_CM_ABORT = 0xFF;        ///< J1939-21 TP.Conn_Abort, 0xff (255)

inline constexpr std::size_t TP_FRAME_LENGTH = 8;          ///< every TP.CM and TP.DT frame has 8 bytes
inline constexpr std::size_t TP_BYTES_PER_PACKET = 7;      ///< data bytes in one TP.DT packet
inline constexpr std::size_t TP_MAX_PACKETS = 255;         ///< packets of one message, 0xff (255)
inline constexpr std::size_t TP_MIN_MESSAGE_SIZE = 9;      ///< shorter messages fit one frame
inline constexpr std::size_t TP_MAX_MESSAGE_SIZE = 1785;   ///< 255 x 7 bytes, 0x6f9 (1785)
inline constexpr std::uint8_t TP_CM_PRIORITY = 7;          ///< J1939-21 default priority of TP.CM
inline constexpr std::uint8_t TP_NO_PACKET_LIMIT = 0xFF;   ///< RTS byte 4: no limit per CTS (255)
inline constexpr std::uint8_t TP_ABORT_ROLE_ORIGINATOR = 0; ///< Abort byte 2 bits 1-0: the sender is the originator
inline constexpr std::uint8_t TP_ABORT_ROLE_RESPONDER = 1; ///< Abort byte 2 bits 1-0: the sender is the responder

/// J1939-21 timing, in nanoseconds of the caller's monotonic clock.
inline constexpr std::int64_t TP_TR_NS = 200'000'000;   ///< Tr 200 ms: response time (we answer at once)
inline constexpr std::int64_t TP_TH_NS = 500'000'000;   ///< Th 500 ms: a holding receiver repeats CTS(0)
inline constexpr std::int64_t TP_T1_NS = 750'000'000;   ///< T1 750 ms: longest gap between TP.DT packets
inline constexpr std::int64_t TP_T2_NS = 1'250'000'000; ///< T2 1250 ms: our CTS -> the first TP.DT
inline constexpr std::int64_t TP_T3_NS = 1'250'000'000; ///< T3 1250 ms: originator, last TP.DT -> CTS/EoMA
inline constexpr std::int64_t TP_T4_NS = 1'050'000'000; ///< T4 1050 ms: originator, CTS(0) -> next CTS
inline constexpr std::int64_t TP_BAM_MIN_GAP_NS = 50'000'000;  ///< J1939-21 BAM: 50 ms at least between its frames
inline constexpr std::int64_t TP_BAM_MAX_GAP_NS = 200'000'000; ///< J1939-21 BAM: 200 ms at most between its frames

/// J1939-21 connection abort reasons (TP.Conn_Abort byte 1). 251..255 follow the J1939-71
/// conventions (error, not available); a received abort may carry any value.
enum class TpAbortReason : std::uint8_t {
  None = 0,                     ///< not an abort (events that carry no reason)
  AlreadyInSession = 1,         ///< already in one or more sessions, cannot support another
  ResourcesNeeded = 2,          ///< system resources were needed for another task
  Timeout = 3,                  ///< a timeout occurred, this abort closes the session
  CtsWhileTransferring = 4,     ///< CTS received while a data transfer is in progress
  RetransmitLimit = 5,          ///< maximum retransmit request limit reached
  UnexpectedDataPacket = 6,     ///< unexpected TP.DT packet
  BadSequenceNumber = 7,        ///< bad sequence number (and software cannot recover)
  DuplicateSequenceNumber = 8,  ///< duplicate sequence number (and software cannot recover)
  MessageTooLarge = 9,          ///< total message size greater than 1785 bytes
  Other = 250,                  ///< any other reason, 0xfa (250)
};

/// "BadSequenceNumber", ... for logs; "Unknown" for values the standard does not list.
[[nodiscard]] std::string_view tpAbortReasonName(TpAbortReason reason) noexcept;

/// A frame to put on the bus, always 8 bytes from our address: the receiver's CTS,
/// EndOfMsgAck or Abort (TP.CM, priority 7, to the originator); the sender's RTS, BAM, Abort
/// (TP.CM) and data packets (TP.DT) (transport_sender.hpp).
struct TpFrame {
  std::uint32_t canId{};  ///< 29-bit identifier
  std::uint8_t length{};  ///< always TP_FRAME_LENGTH
  std::array<std::uint8_t, TP_FRAME_LENGTH> data{};
  friend bool operator==(const TpFrame&, const TpFrame&) = default;
};

/// A reassembled message. `data` points into the receiver's buffer: valid until the next
/// call into the receiver; copy it to keep it.
struct TpMessage {
  std::uint32_t pgn{};
  std::uint8_t source{};
  std::uint8_t destination{};  ///< our address, or GLOBAL_ADDRESS (0xFF) for BAM
  std::span<const std::uint8_t> data;
  std::int64_t completedNs{};  ///< time of the last packet
  bool broadcast{};            ///< received by BAM
};

/// How a session ended, or why a frame had no effect.
enum class TpEventKind : std::uint8_t {
  Completed,        ///< all packets arrived; completed() came just before
  Aborted,          ///< the originator sent an Abort (reason: the originator's)
  AbortSent,        ///< we ended a running RTS/CTS session with an Abort (reason: ours)
  Timeout,          ///< a deadline passed; for RTS/CTS we sent Abort reason 3
  SessionReplaced,  ///< a new BAM, or a new RTS for the same PGN, from the same source
  Dropped,          ///< a running BAM ended for a protocol error (nothing can be sent)
  Refused,          ///< an RTS or BAM was not accepted (RTS: we sent an Abort with the reason)
  Ignored,          ///< a TP frame for us that changed nothing (reason says why)
};
inline constexpr std::size_t TP_EVENT_KIND_COUNT = 8;

/// "Completed", "Timeout", ... for logs.
[[nodiscard]] std::string_view tpEventKindName(TpEventKind kind) noexcept;

/// One session outcome or ignored frame, for counters and logs.
struct TpEvent {
  TpEventKind kind{};
  std::uint8_t source{};       ///< originator address
  std::uint8_t destination{};  ///< our address, or GLOBAL_ADDRESS for BAM
  std::uint32_t pgn{};         ///< PGN of the message (of the frame's session if known, else 0)
  TpAbortReason reason{};      ///< None for Completed and SessionReplaced
  friend bool operator==(const TpEvent&, const TpEvent&) = default;
};

/// Where the receiver puts its output. Called synchronously from onFrame() and poll();
/// the sink must not call back into the receiver.
/// Why virtual: one indirect call per output, no std::function and no allocation.
class TpSink {
 public:
  virtual ~TpSink() = default;
  /// A CTS, EndOfMsgAck or Abort to transmit now.
  virtual void send(const TpFrame& frame) noexcept = 0;
  /// A message reassembled completely; its size equals the announced size.
  virtual void completed(const TpMessage& message) noexcept = 0;
  /// A session outcome or an ignored frame.
  virtual void event(const TpEvent& event) noexcept = 0;
};

struct TpReceiverConfig {
  /// Our J1939 address: RTS/CTS sessions addressed to it are answered. NULL_ADDRESS (0xFE)
  /// or GLOBAL_ADDRESS receives BAM only.
  std::uint8_t ownAddress{NULL_ADDRESS};
  /// Our limit of packets per CTS, 1..255; a CTS asks for min(remaining packets, this,
  /// the RTS's limit in byte 4).
  std::uint8_t maxPacketsPerCts{TP_NO_PACKET_LIMIT};
  /// Sessions receiving at the same time (BAM and RTS/CTS together); each owns a
  /// 1785-byte buffer allocated at construction.
  std::size_t maxSessions{8};
  /// RTS/CTS sessions kept waiting with CTS(0) (repeated every Th) while all buffers are
  /// busy; beyond that an RTS gets Abort reason 1.
  std::size_t maxHeldSessions{4};
};

/// What happened since construction. At any time:
/// sessionsStarted == sessionsCompleted + sessionsAbortedByPeer + sessionsAbortedByUs +
///   sessionsTimedOut + sessionsReplaced + sessionsDropped + activeSessions().
struct TpCounters {
  std::uint64_t sessionsStarted{};        ///< BAM and RTS accepted (receiving or held)
  std::uint64_t sessionsCompleted{};
  std::uint64_t sessionsAbortedByPeer{};  ///< Abort from the originator
  std::uint64_t sessionsAbortedByUs{};    ///< AbortSent: bad or duplicate sequence, unexpected packet
  std::uint64_t sessionsTimedOut{};
  std::uint64_t sessionsReplaced{};
  std::uint64_t sessionsDropped{};        ///< BAM ended by a protocol error
  std::uint64_t announcementsRefused{};   ///< RTS or BAM not accepted
  std::uint64_t framesIgnored{};          ///< TP frames for us without effect
  std::uint64_t framesNotForUs{};         ///< TP frames to other addresses or from our own
  std::uint64_t holdsSent{};              ///< CTS(0) frames sent
  std::uint64_t abortsSent{};             ///< Abort frames sent, any reason
  friend bool operator==(const TpCounters&, const TpCounters&) = default;
};

/// Receives J1939-21 transport sessions on one CAN bus for one own address: any number of
/// BAM (one per source) and RTS/CTS sessions (one per source, addressed to us), up to
/// maxSessions at a time. Time is passed in; call poll() at nextDeadlineNs() (or on any
/// timer) so deadlines fire without frames. onFrame() applies passed deadlines first, so
/// the result does not depend on how often poll() runs. A frame at or after a deadline is
/// late.
///
/// @note not thread-safe: one thread feeds one receiver. Real-time safe after construction:
///       noexcept, no allocation, O(maxSessions + maxHeldSessions) per TP frame, O(1) for
///       other frames.
class TpReceiver {
 public:
  /// Allocates maxSessions x 1785 bytes of buffer, once (caps the totals at 2 sessions per
  /// source address).
  explicit TpReceiver(const TpReceiverConfig& config);

  /// One received extended CAN frame (29-bit `canId`; higher bits ignored). Frames other
  /// than TP.CM and TP.DT return at once; TP frames to other addresses are only counted.
  void onFrame(std::uint32_t canId, std::span<const std::uint8_t> data, std::int64_t nowNs,
               TpSink& sink) noexcept;

  /// Applies every deadline at or before `nowNs`: timeouts (Abort reason 3 for RTS/CTS)
  /// and the CTS(0) repeat of held sessions; then gives freed buffers to held sessions.
  void poll(std::int64_t nowNs, TpSink& sink) noexcept;

  /// The earliest deadline of any session; empty when no session is open.
  [[nodiscard]] std::optional<std::int64_t> nextDeadlineNs() const noexcept;

  /// Our address changed (J1939-81 address claim): RTS/CTS sessions to the new address are
  /// answered from now on (NULL_ADDRESS or GLOBAL_ADDRESS: BAM only). An RTS/CTS session
  /// running to the old address no longer gets its packets and ends by timeout (its Abort
  /// goes out from the new address); BAM sessions go on.
  void setOwnAddress(std::uint8_t address) noexcept;

  /// Sessions receiving or held.
  [[nodiscard]] std::size_t activeSessions() const noexcept { return m_activeSessions; }
  [[nodiscard]] const TpCounters& counters() const noexcept { return m_counters; }
  [[nodiscard]] const TpReceiverConfig& config() const noexcept { return m_config; }

 private:
  enum class State : std::uint8_t { Idle, Receiving, Held };
  struct Session {
    std::int64_t deadlineNs{};
    std::uint64_t holdTicket{};  ///< order of arrival among held sessions
    std::uint32_t pgn{};
    std::uint16_t size{};
    std::uint16_t nextPacket{};  ///< 1..packets; packets + 1 once complete
    std::uint16_t windowEnd{};   ///< last packet of the current CTS window (RTS/CTS)
    std::uint16_t buffer{};      ///< index into the buffer pool while Receiving
    std::uint8_t source{};
    std::uint8_t packets{};
    std::uint8_t originatorLimit{};  ///< RTS byte 4, packets per CTS
    bool broadcast{};
    State state{State::Idle};
  };

  void handleControl(std::uint8_t source, bool broadcast, std::span<const std::uint8_t> data,
                     std::int64_t nowNs, TpSink& sink) noexcept;
  void handleRts(std::uint8_t source, std::span<const std::uint8_t> data, std::uint32_t pgn,
                 std::int64_t nowNs, TpSink& sink) noexcept;
  void handleBam(std::uint8_t source, std::span<const std::uint8_t> data, std::uint32_t pgn,
                 std::int64_t nowNs, TpSink& sink) noexcept;
  void handleAbort(std::uint8_t source, std::span<const std::uint8_t> data, std::uint32_t pgn,
                   TpSink& sink) noexcept;
  void handleData(std::uint8_t source, bool broadcast, std::span<const std::uint8_t> data,
                  std::int64_t nowNs, TpSink& sink) noexcept;
  void acceptPacket(Session& session, std::span<const std::uint8_t> data, std::int64_t nowNs,
                    TpSink& sink) noexcept;
  void complete(Session& session, std::int64_t nowNs, TpSink& sink) noexcept;
  void expire(std::int64_t nowNs, TpSink& sink) noexcept;
  void promoteHeld(std::int64_t nowNs, TpSink& sink) noexcept;

  Session* find(std::uint8_t source, bool broadcast) noexcept;
  Session* openSession(std::uint8_t source, bool broadcast, State state) noexcept;
  void closeSession(Session& session) noexcept;
  void finish(Session& session, TpEventKind kind, TpAbortReason reason, TpSink& sink) noexcept;
  void sendCts(Session& session, std::int64_t nowNs, TpSink& sink) noexcept;
  void sendHold(Session& session, std::int64_t nowNs, TpSink& sink) noexcept;
  void sendAbort(std::uint8_t destination, std::uint32_t pgn, TpAbortReason reason,
                 TpSink& sink) noexcept;
  void sendControl(std::uint8_t destination, const std::array<std::uint8_t, TP_FRAME_LENGTH>& data,
                   TpSink& sink) noexcept;
  void ignore(std::uint8_t source, bool broadcast, std::uint32_t pgn, TpAbortReason reason,
              TpSink& sink) noexcept;
  void refuse(std::uint8_t source, bool broadcast, std::uint32_t pgn, TpAbortReason reason,
              TpSink& sink) noexcept;
  [[nodiscard]] std::uint8_t destinationOf(bool broadcast) const noexcept;
  [[nodiscard]] std::span<std::uint8_t> bufferOf(const Session& session) noexcept;

  static constexpr std::uint16_t NO_SESSION = 0xFFFF;
  static constexpr std::size_t SESSION_KEYS = 512;  ///< (source, broadcast) pairs

  TpReceiverConfig m_config;
  bool m_acceptsDirected{};
  std::vector<Session> m_sessions;          ///< maxSessions + maxHeldSessions records
  std::vector<std::uint8_t> m_buffers;      ///< maxSessions x TP_MAX_MESSAGE_SIZE
  std::vector<std::uint16_t> m_freeBuffers; ///< stack; capacity reserved at construction
  std::array<std::uint16_t, SESSION_KEYS> m_sessionIndex{};
  std::size_t m_activeSessions{};
  std::size_t m_heldSessions{};
  std::uint64_t m_nextHoldTicket{};
  TpCounters m_counters;
};

}  // namespace openvcu::j1939
