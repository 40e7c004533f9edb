#pragma once
// SAE J1939-21 transport protocol seen from a bus monitor (design note:
// docs/design/j1939-transport.md, "Passive monitoring"): every BAM and RTS/CTS session on
// one bus is followed, whoever sends it to whomever, without ever sending a frame. The
// monitor reassembles each message, watches the responder's CTS (CTS(0) holds),
// EndOfMsgAck and Aborts from either side, applies the J1939-21 timers, and reports every
// session's end with its outcome. TpReceiver (transport.hpp) is the active counterpart
// that answers RTS/CTS for one own address.
//
// Sessions are keyed by (originator, destination); destination 0xFF is a BAM. TP.DT from
// the originator and TP.CM from the responder (CTS, EndOfMsgAck) find the session by that
// key; an Abort from either side does too.
//
//   RTS 0x20 -> 0x21, PGN 0xFEEB, 20 bytes, 3 packets, 2 per CTS:
//     0x1CEC2120  10 14 00 03 02 EB FE 00   RTS          (awaiting CTS, T3)
//     0x1CEC2021  11 02 01 FF FF EB FE 00   CTS 2 from 1 (awaiting packet 1, T2)
//     0x1CEB2120  01 .. / 02 ..             TP.DT        (T1 between, then T3)
//     0x1CEC2021  11 00 FF FF FF EB FE 00   CTS(0) hold  (T4)
//     0x1CEC2021  11 01 03 FF FF EB FE 00   CTS 1 from 3
//     0x1CEB2120  03 ..                     -> completed(message: 20 bytes)
//     0x1CEC2021  13 14 00 03 FF EB FE 00   EndOfMsgAck  -> ended(Completed)
//
// A completed RTS/CTS message is handed on at its last TP.DT (the data are complete);
// the session ends at the EndOfMsgAck (Completed), or TimedOut (T3) if none comes.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/transport.hpp"

namespace openvcu::j1939 {

/// How a monitored session ended.
enum class TpOutcome : std::uint8_t {
  Completed,      ///< BAM: the last packet arrived; RTS/CTS: the EndOfMsgAck arrived
  Aborted,        ///< an Abort from the originator or the responder (abortedBy, abortReason)
  TimedOut,       ///< a J1939-21 timer ran out (timer)
  Replaced,       ///< a new BAM / RTS for the same (originator, destination) before the end
  ProtocolError,  ///< a frame broke the protocol (error)
  Incomplete,     ///< still open at finish() (end of the log)
  Refused,        ///< an announcement not followed: invalid (error) or the pool was full
};
inline constexpr std::size_t TP_OUTCOME_COUNT = 7;

/// The J1939-21 timer that ran out (TpOutcome::TimedOut).
enum class TpTimer : std::uint8_t {
  None,
  T1,  ///< 750 ms between TP.DT packets (BAM and inside a CTS window)
  T2,  ///< 1250 ms from a CTS to its first TP.DT
  T3,  ///< 1250 ms from the RTS or a window's last TP.DT to the CTS / EndOfMsgAck
  T4,  ///< 1050 ms from a CTS(0) hold to the next CTS
};

/// Who sent an Abort.
enum class TpSide : std::uint8_t { None, Originator, Responder };

/// What broke the protocol (TpOutcome::ProtocolError and Refused).
enum class TpError : std::uint8_t {
  None,
  BadSequence,          ///< a TP.DT ahead of the next expected packet
  DuplicateSequence,    ///< a TP.DT older than the previous packet (the previous one again is tolerated)
  OutsideWindow,        ///< a TP.DT while no CTS window is open, or past the window
  SizeMismatch,         ///< EndOfMsgAck size/packets differ from the RTS, or a TP.DT too short
  CtsWhileTransferring, ///< a CTS while packets of the previous window are still due
  BadCts,               ///< a CTS asking for a packet past the message or skipping packets
  EarlyEndOfMsgAck,     ///< an EndOfMsgAck before all packets
  BadAnnouncement,      ///< size < 9 or > 1785, packets != ceil(size / 7), PGN > 18 bits, RTS to global
  PoolFull,             ///< maxSessions sessions were open
};

/// "Completed", "TimedOut", ...
[[nodiscard]] std::string_view tpOutcomeName(TpOutcome outcome) noexcept;
/// "T1", "T2", "T3", "T4" ("" for None).
[[nodiscard]] std::string_view tpTimerName(TpTimer timer) noexcept;
/// "originator", "responder" ("" for None).
[[nodiscard]] std::string_view tpSideName(TpSide side) noexcept;
/// "bad sequence number", "packet outside the CTS window", ... ("" for None).
[[nodiscard]] std::string_view tpErrorText(TpError error) noexcept;

/// One session as the monitor saw it.
struct TpSessionInfo {
  std::uint32_t pgn{};
  std::uint8_t source{};       ///< originator
  std::uint8_t destination{};  ///< responder, or GLOBAL_ADDRESS (0xFF) for BAM
  bool broadcast{};
  std::uint16_t size{};        ///< announced bytes
  std::uint8_t packets{};      ///< announced packets
  std::uint8_t packetsReceived{};  ///< distinct packets taken (retransmissions not counted twice)
  std::uint8_t windows{};      ///< CTS windows granted (CTS with count > 0), saturating at 255
  std::uint8_t holds{};        ///< CTS(0) holds seen, saturating at 255
  std::int64_t startNs{};      ///< the announcement (BAM / RTS)
  std::int64_t endNs{};        ///< the frame that ended it, the deadline that passed, or finish()'s time
};

/// How and when a session ended.
struct TpSessionEnd {
  TpSessionInfo session;
  TpOutcome outcome{};
  TpTimer timer{TpTimer::None};          ///< TimedOut
  TpSide abortedBy{TpSide::None};        ///< Aborted
  TpAbortReason abortReason{TpAbortReason::None};  ///< Aborted: Abort byte 1 as sent (any value)
  TpError error{TpError::None};          ///< ProtocolError, Refused
};

/// A reassembled message; `data` is valid during the callback only.
struct TpMonitoredMessage {
  TpSessionInfo session;  ///< endNs: the last TP.DT
  std::span<const std::uint8_t> data;
};

/// Receives what the monitor sees, synchronously from onFrame(), poll() and finish().
/// Must not call back into the monitor.
/// Why virtual: one indirect call per output, no std::function and no allocation.
class TpMonitorSink {
 public:
  virtual ~TpMonitorSink() = default;
  /// All packets of a message arrived (size == announced size); once per session: packets
  /// retransmitted after it (a CTS asking for them again) are not handed on again.
  virtual void completed(const TpMonitoredMessage& message) noexcept = 0;
  /// A session ended (every session that started ends exactly once) or an announcement was refused.
  virtual void ended(const TpSessionEnd& end) noexcept = 0;
};

struct TpMonitorConfig {
  /// Sessions open at the same time; each owns a 1785-byte buffer allocated at construction.
  std::size_t maxSessions{256};
};

/// What the monitor saw since construction. At any time:
/// started == completed + aborted + timedOut + replaced + protocolErrors + incomplete + openSessions().
struct TpMonitorCounters {
  std::uint64_t started{};          ///< BAM and RTS followed
  std::uint64_t bam{};
  std::uint64_t rtsCts{};
  std::uint64_t completed{};
  std::uint64_t aborted{};
  std::uint64_t timedOut{};
  std::uint64_t replaced{};
  std::uint64_t protocolErrors{};
  std::uint64_t incomplete{};
  std::uint64_t refused{};          ///< announcements not followed (invalid or pool full)
  std::uint64_t repeatedPackets{};  ///< the previous TP.DT again (a CAN-level repeat), tolerated
  std::uint64_t orphanFrames{};     ///< TP.DT, CTS, EndOfMsgAck or Abort matching no open session
  friend bool operator==(const TpMonitorCounters&, const TpMonitorCounters&) = default;
};

/// Follows the J1939-21 transport sessions of one CAN bus passively.
/// Time is passed in; onFrame() applies passed deadlines first (a frame at or after a
/// deadline is late), so results do not depend on how often poll() runs.
///
/// @note not thread-safe: one thread feeds one monitor. After construction: noexcept, no
///       allocation, O(open sessions) per TP frame, O(1) for other frames.
class TpMonitor {
 public:
  /// Allocates maxSessions x 1785 bytes of buffer and a 64K-entry session index, once.
  explicit TpMonitor(const TpMonitorConfig& config = {});

  /// One frame of the bus (29-bit `canId`; standard frames must not be passed). Frames
  /// other than TP.CM / TP.DT return at once.
  void onFrame(std::uint32_t canId, std::span<const std::uint8_t> data, std::int64_t nowNs,
               TpMonitorSink& sink) noexcept;

  /// Ends every session whose deadline is at or before `nowNs` (TimedOut), earliest first.
  void poll(std::int64_t nowNs, TpMonitorSink& sink) noexcept;

  /// poll(endNs), then ends the sessions still open as Incomplete at `endNs`.
  void finish(std::int64_t endNs, TpMonitorSink& sink) noexcept;

  /// The earliest deadline of any open session; empty when none is open.
  [[nodiscard]] std::optional<std::int64_t> nextDeadlineNs() const noexcept;

  [[nodiscard]] std::size_t openSessions() const noexcept { return m_open.size(); }
  [[nodiscard]] const TpMonitorCounters& counters() const noexcept { return m_counters; }
  [[nodiscard]] const TpMonitorConfig& config() const noexcept { return m_config; }

 private:
  enum class State : std::uint8_t {
    Idle,
    BamData,     ///< BAM: packets due, T1
    AwaitCts,    ///< RTS sent or a window done: CTS / EndOfMsgAck due, T3
    Held,        ///< CTS(0) seen: the next CTS due, T4
    WindowData,  ///< a CTS window open: packets due, T2 before the first, T1 between
    AwaitAck,    ///< all packets in: EndOfMsgAck due, T3
  };
  struct Session {
    TpSessionInfo info;
    std::int64_t deadlineNs{};
    std::uint16_t nextPacket{};  ///< 1..packets; packets + 1 once all arrived
    std::uint16_t windowEnd{};   ///< last packet of the open CTS window
    std::uint16_t openIndex{};   ///< position in m_open
    TpTimer timer{TpTimer::None};
    State state{State::Idle};
    bool windowStarted{};        ///< a TP.DT of the open window arrived
    bool delivered{};            ///< completed() was called (a retransmission does not call it again)
  };

  void handleControl(std::uint8_t source, std::uint8_t destination, std::span<const std::uint8_t> data,
                     std::int64_t nowNs, TpMonitorSink& sink) noexcept;
  void announce(std::uint8_t source, std::uint8_t destination, std::span<const std::uint8_t> data,
                bool broadcast, std::int64_t nowNs, TpMonitorSink& sink) noexcept;
  void handleCts(Session& session, std::span<const std::uint8_t> data, std::int64_t nowNs,
                 TpMonitorSink& sink) noexcept;
  void handleEndOfMsgAck(Session& session, std::span<const std::uint8_t> data, std::int64_t nowNs,
                         TpMonitorSink& sink) noexcept;
  void handleData(std::uint8_t source, std::uint8_t destination, std::span<const std::uint8_t> data,
                  std::int64_t nowNs, TpMonitorSink& sink) noexcept;
  void setDeadline(Session& session, std::int64_t nowNs, std::int64_t delayNs, TpTimer timer) noexcept;
  void end(Session& session, TpSessionEnd end, std::int64_t nowNs, TpMonitorSink& sink) noexcept;
  void endWith(Session& session, TpOutcome outcome, std::int64_t nowNs, TpMonitorSink& sink,
               TpError error = TpError::None) noexcept;

  Session* find(std::uint8_t source, std::uint8_t destination) noexcept;
  [[nodiscard]] std::span<std::uint8_t> bufferOf(const Session& session) noexcept;

  static constexpr std::uint16_t NO_SESSION = 0xFFFF;
  static constexpr std::size_t SESSION_KEYS = 256 * 256;  ///< (originator, destination)

  TpMonitorConfig m_config;
  std::vector<Session> m_sessions;       ///< maxSessions records; record i owns buffer i
  std::vector<std::uint8_t> m_buffers;   ///< maxSessions x TP_MAX_MESSAGE_SIZE
  std::vector<std::uint16_t> m_free;     ///< idle record indices (stack, capacity reserved)
  std::vector<std::uint16_t> m_open;     ///< open record indices (capacity reserved)
  std::vector<std::uint16_t> m_index;    ///< SESSION_KEYS entries: record index or NO_SESSION
  TpMonitorCounters m_counters;
};

}  // namespace openvcu::j1939
