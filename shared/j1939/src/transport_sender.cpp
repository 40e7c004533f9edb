#include "openvcu/j1939/transport_sender.hpp"

#include "tp_layout.hpp"

#include <algorithm>
#include <cassert>
#include <limits>

namespace openvcu::j1939 {
namespace {

using namespace tp;

constexpr std::uint8_t PADDING = 0xFF;  // J1939-21: unused bytes of the last TP.DT
constexpr std::uint8_t MAX_PRIORITY = 7;
// Abort byte 2: bits 7..2 reserved (1), bits 1..0 the role of the sender (J1939-21 2022).
constexpr std::uint8_t ABORT_ROLE_BYTE = 0xFC | TP_ABORT_ROLE_ORIGINATOR;
// One running session per destination: 0..253 and 255 (BAM).
constexpr std::size_t MAX_SESSIONS = TP_MAX_PACKETS;
// Keeps record indices below NO_SESSION; 4096 x 1785 bytes is already 7 MB.
constexpr std::size_t MAX_QUEUE_CAPACITY = 4096;

// RTS or BAM: control, size, packets, byte 4 (RTS: packets per CTS; BAM: reserved), PGN.
constexpr ControlData announcement(std::uint8_t control, std::uint16_t size, std::uint8_t packets,
                                   std::uint8_t byte4, std::uint32_t pgn) noexcept {
  return ControlData{control, byteOf(size, 0),  byteOf(size, 8),  packets,
                     byte4,   byteOf(pgn, 0),   byteOf(pgn, 8),   byteOf(pgn, 16)};
}

}  // namespace

std::string_view tpSendStatusName(TpSendStatus status) noexcept {
  switch (status) {
    case TpSendStatus::Started: return "Started";
    case TpSendStatus::Queued: return "Queued";
    case TpSendStatus::RefusedNoAddress: return "RefusedNoAddress";
    case TpSendStatus::RefusedSize: return "RefusedSize";
    case TpSendStatus::RefusedPgn: return "RefusedPgn";
    case TpSendStatus::RefusedPriority: return "RefusedPriority";
    case TpSendStatus::RefusedDestination: return "RefusedDestination";
    case TpSendStatus::RefusedQueueFull: return "RefusedQueueFull";
  }
  return "Unknown";
}

std::string_view tpSendOutcomeName(TpSendOutcome outcome) noexcept {
  switch (outcome) {
    case TpSendOutcome::Completed: return "Completed";
    case TpSendOutcome::AbortedByPeer: return "AbortedByPeer";
    case TpSendOutcome::AbortSent: return "AbortSent";
    case TpSendOutcome::TimedOut: return "TimedOut";
    case TpSendOutcome::AddressChanged: return "AddressChanged";
  }
  return "Unknown";
}

TpSender::TpSender(const TpSenderConfig& config)
    : m_config(config), m_ownAddress(config.ownAddress) {
  assert(config.maxSessions >= 1 && config.maxPacketsPerCts >= 1);
  m_config.maxSessions = std::clamp<std::size_t>(m_config.maxSessions, 1, MAX_SESSIONS);
  m_config.queueCapacity = std::min(m_config.queueCapacity, MAX_QUEUE_CAPACITY);
  m_config.maxPacketsPerCts = std::max<std::uint8_t>(m_config.maxPacketsPerCts, 1);
  m_config.bamPacketGapNs =
      std::clamp(m_config.bamPacketGapNs, TP_BAM_MIN_GAP_NS, TP_BAM_MAX_GAP_NS);
  m_config.rtsPacketGapNs = std::max<std::int64_t>(m_config.rtsPacketGapNs, 0);

  const std::size_t records = m_config.maxSessions + m_config.queueCapacity;
  m_sessions.resize(records);
  m_buffers.resize(records * TP_MAX_MESSAGE_SIZE);
  m_running.fill(NO_SESSION);
}

TpSendStatus TpSender::send(std::uint32_t pgn, std::uint8_t destination, std::uint8_t priority,
                            std::span<const std::uint8_t> data, std::int64_t nowNs,
                            TpSendSink& sink) noexcept {
  expire(nowNs, sink);  // may free the destination
  const TpSendStatus status = check(pgn, destination, priority, data.size());
  if (status == TpSendStatus::RefusedNoAddress) {
    ++m_counters.refusedNoAddress;
    return status;
  }
  if (status != TpSendStatus::Started) {
    ++m_counters.refusedInvalid;
    return status;
  }
  // Queued messages are never startable after a call returns (every session end starts
  // them), so a free destination has no older message waiting for it.
  const bool startNow = canStart(destination);
  if (!startNow && m_queuedMessages >= m_config.queueCapacity) {
    ++m_counters.refusedQueueFull;
    return TpSendStatus::RefusedQueueFull;
  }

  // Records = maxSessions + queueCapacity, and neither limit is reached: one is free.
  const auto free = std::find_if(m_sessions.begin(), m_sessions.end(),
                                 [](const Session& session) { return session.state == State::Free; });
  assert(free != m_sessions.end());
  if (free == m_sessions.end()) return TpSendStatus::RefusedQueueFull;
  Session& session = *free;
  session = Session{};
  session.pgn = pgn;
  session.size = static_cast<std::uint16_t>(data.size());
  session.packets = static_cast<std::uint8_t>(packetsFor(data.size()));
  session.destination = destination;
  session.priority = priority;
  std::copy(data.begin(), data.end(), bufferOf(session).begin());

  if (startNow) {
    start(session, nowNs, sink);
    return TpSendStatus::Started;
  }
  session.state = State::Queued;
  session.ticket = m_nextTicket++;
  ++m_queuedMessages;
  ++m_counters.messagesQueued;
  return TpSendStatus::Queued;
}

void TpSender::onFrame(std::uint32_t canId, std::span<const std::uint8_t> data, std::int64_t nowNs,
                       TpSendSink& sink) noexcept {
  const Id id = Id::fromCanId(canId);
  if (id.pgn() != PGN_TP_CM) return;  // TP.DT and the rest are never for an originator

  expire(nowNs, sink);
  const std::uint8_t source = id.sourceAddress;
  if (m_ownAddress >= NULL_ADDRESS || id.pduSpecific != m_ownAddress || source >= NULL_ADDRESS ||
      data.empty()) {
    return;
  }
  const std::uint8_t control = data[CONTROL];
  if (control != TP_CM_CTS && control != TP_CM_END_OF_MSG_ACK && control != TP_CM_ABORT) {
    return;  // RTS and BAM are for the receiver
  }
  const std::uint16_t index = m_running[source];
  if (data.size() != TP_FRAME_LENGTH || index == NO_SESSION ||
      pgnField(data) != m_sessions[index].pgn) {
    // Nothing to act on: no session with that node, or an answer about another PGN (the
    // running session continues under its own timers).
    ++m_counters.framesIgnored;
    return;
  }
  Session& session = m_sessions[index];
  switch (control) {
    case TP_CM_CTS:
      handleCts(session, data, nowNs, sink);
      break;
    case TP_CM_END_OF_MSG_ACK:
      handleEndOfMsgAck(session, data, sink);
      break;
    default:  // TP_CM_ABORT
      // Role 00: the peer aborts a session it originates, to us: our receiver's business.
      if ((data[ABORT_ROLE] & ABORT_ROLE_MASK) == TP_ABORT_ROLE_ORIGINATOR) {
        ++m_counters.framesIgnored;
        return;
      }
      finish(session, TpSendOutcome::AbortedByPeer, static_cast<TpAbortReason>(data[ABORT_REASON]),
             sink);
      break;
  }
  startQueued(nowNs, sink);
}

void TpSender::poll(std::int64_t nowNs, TpSendSink& sink) noexcept { expire(nowNs, sink); }

void TpSender::setOwnAddress(std::uint8_t address, std::int64_t nowNs, TpSendSink& sink) noexcept {
  if (address == m_ownAddress) return;
  // The change is effective at once: nothing more goes out from the old address, not even
  // packets that were due.
  for (Session& session : m_sessions) {
    if (session.state != State::Free && session.state != State::Queued) {
      finish(session, TpSendOutcome::AddressChanged, TpAbortReason::None, sink);
    }
  }
  m_ownAddress = address;
  // Without an address nothing may start; a message to our new address would go to ourselves.
  const bool canTransmit = address < NULL_ADDRESS;
  for (Session& session : m_sessions) {
    if (session.state == State::Queued && (!canTransmit || session.destination == address)) {
      finish(session, TpSendOutcome::AddressChanged, TpAbortReason::None, sink);
    }
  }
  startQueued(nowNs, sink);
}

std::optional<std::int64_t> TpSender::nextDeadlineNs() const noexcept {
  std::optional<std::int64_t> earliest;
  for (const Session& session : m_sessions) {
    if (session.state == State::Free || session.state == State::Queued) continue;
    if (!earliest || session.deadlineNs < *earliest) earliest = session.deadlineNs;
  }
  return earliest;
}

void TpSender::handleCts(Session& session, std::span<const std::uint8_t> data, std::int64_t nowNs,
                         TpSendSink& sink) noexcept {
  if (session.state == State::SendingWindow) {  // J1939-21 abort reason 4
    abortSession(session, TpAbortReason::CtsWhileTransferring, TpSendOutcome::AbortSent, sink);
    return;
  }
  const std::size_t count = data[CTS_COUNT];
  const std::size_t next = data[CTS_NEXT];
  if (count == 0) {  // hold: the receiver repeats CTS(0) within Th; T4 from each one
    ++m_counters.holdsReceived;
    session.state = State::Holding;
    session.deadlineNs = after(nowNs, TP_T4_NS);
    return;
  }
  // Asking for more than the RTS allowed, or for packets the message does not have.
  if (count > m_config.maxPacketsPerCts || next == 0 || next + count - 1 > session.packets) {
    abortSession(session, TpAbortReason::Other, TpSendOutcome::AbortSent, sink);
    return;
  }
  // J1939-82 (TP originator tests): an Abort when the next packet number is below that of
  // the previous CTS: those packets were acknowledged by that CTS.
  if (next < session.windowStart) {
    abortSession(session, TpAbortReason::DuplicateSequenceNumber, TpSendOutcome::AbortSent, sink);
    return;
  }
  const std::size_t expected = session.windowEnd + 1u;
  if (next > expected) {  // skips packets never sent
    abortSession(session, TpAbortReason::BadSequenceNumber, TpSendOutcome::AbortSent, sink);
    return;
  }
  if (next < expected) {  // retransmission request: packets of the last window again
    ++m_counters.retransmitRequests;
    if (++session.retransmitRequests > m_config.maxRetransmitRequests) {
      abortSession(session, TpAbortReason::RetransmitLimit, TpSendOutcome::AbortSent, sink);
      return;
    }
  }
  session.windowStart = static_cast<std::uint16_t>(next);
  session.windowEnd = static_cast<std::uint16_t>(next + count - 1);
  session.nextPacket = static_cast<std::uint16_t>(next);
  session.state = State::SendingWindow;
  sendWindowPackets(session, nowNs, sink);
}

void TpSender::handleEndOfMsgAck(Session& session, std::span<const std::uint8_t> data,
                                 TpSendSink& sink) noexcept {
  const std::size_t size = static_cast<std::size_t>(data[SIZE_LOW]) |
                           (static_cast<std::size_t>(data[SIZE_HIGH]) << 8);
  // Early (packets still to send) or about another message: the receiver is confused.
  const bool allSent = session.state != State::SendingWindow && session.windowEnd == session.packets;
  if (!allSent || size != session.size || data[PACKET_COUNT] != session.packets) {
    abortSession(session, TpAbortReason::Other, TpSendOutcome::AbortSent, sink);
    return;
  }
  finish(session, TpSendOutcome::Completed, TpAbortReason::None, sink);
}

void TpSender::start(Session& session, std::int64_t nowNs, TpSendSink& sink) noexcept {
  m_running[session.destination] =
      static_cast<std::uint16_t>(std::distance(m_sessions.data(), &session));
  ++m_activeSessions;
  ++m_counters.sessionsStarted;
  session.nextPacket = 1;
  session.windowStart = 1;
  session.windowEnd = 0;
  session.retransmitRequests = 0;
  if (session.destination == GLOBAL_ADDRESS) {
    session.state = State::Broadcasting;
    session.deadlineNs = after(nowNs, m_config.bamPacketGapNs);
    sendControl(session,
                announcement(TP_CM_BAM, session.size, session.packets, RESERVED, session.pgn), sink);
  } else {
    session.state = State::WaitingCts;
    session.deadlineNs = after(nowNs, TP_T3_NS);
    sendControl(session,
                announcement(TP_CM_RTS, session.size, session.packets, m_config.maxPacketsPerCts,
                             session.pgn),
                sink);
  }
}

void TpSender::startQueued(std::int64_t nowNs, TpSendSink& sink) noexcept {
  if (m_ownAddress >= NULL_ADDRESS) return;
  while (m_queuedMessages > 0 && m_activeSessions < m_config.maxSessions) {
    // The oldest message whose destination is free: FIFO per destination.
    Session* oldest = nullptr;
    for (Session& session : m_sessions) {
      if (session.state != State::Queued || m_running[session.destination] != NO_SESSION) continue;
      if (oldest == nullptr || session.ticket < oldest->ticket) oldest = &session;
    }
    if (oldest == nullptr) return;
    --m_queuedMessages;
    ++m_counters.messagesStartedFromQueue;
    start(*oldest, nowNs, sink);
  }
}

void TpSender::expire(std::int64_t nowNs, TpSendSink& sink) noexcept {
  bool ended = false;
  for (Session& session : m_sessions) {
    if (session.state == State::Free || session.state == State::Queued ||
        session.deadlineNs > nowNs) {
      continue;
    }
    switch (session.state) {
      case State::Broadcasting:
        sendPacket(session, sink);
        if (session.nextPacket > session.packets) {
          finish(session, TpSendOutcome::Completed, TpAbortReason::None, sink);
          ended = true;
        } else {
          session.deadlineNs = after(nowNs, m_config.bamPacketGapNs);
        }
        break;
      case State::SendingWindow:
        sendWindowPackets(session, nowNs, sink);
        break;
      default:  // WaitingCts, Holding, WaitingAck: T3 or T4 passed
        abortSession(session, TpAbortReason::Timeout, TpSendOutcome::TimedOut, sink);
        ended = true;
        break;
    }
  }
  if (ended) startQueued(nowNs, sink);
}

// Without a gap the whole window goes out now; with one, one packet per call.
void TpSender::sendWindowPackets(Session& session, std::int64_t nowNs, TpSendSink& sink) noexcept {
  do {
    sendPacket(session, sink);
  } while (m_config.rtsPacketGapNs == 0 && session.nextPacket <= session.windowEnd);

  if (session.nextPacket <= session.windowEnd) {
    session.deadlineNs = after(nowNs, m_config.rtsPacketGapNs);
    return;
  }
  session.state = session.windowEnd == session.packets ? State::WaitingAck : State::WaitingCts;
  session.deadlineNs = after(nowNs, TP_T3_NS);
}

void TpSender::sendPacket(Session& session, TpSendSink& sink) noexcept {
  const std::size_t offset = (session.nextPacket - 1u) * TP_BYTES_PER_PACKET;
  const std::size_t count = std::min(TP_BYTES_PER_PACKET, session.size - offset);
  const std::span<const std::uint8_t> bytes = bufferOf(session).subspan(offset, count);
  TpFrame frame;
  frame.canId = Id::fromPgn(PGN_TP_DT, session.priority, m_ownAddress, session.destination).toCanId();
  frame.length = static_cast<std::uint8_t>(TP_FRAME_LENGTH);
  frame.data.fill(PADDING);
  frame.data[0] = static_cast<std::uint8_t>(session.nextPacket);
  std::copy(bytes.begin(), bytes.end(), frame.data.begin() + 1);
  ++session.nextPacket;
  sink.send(frame);
}

void TpSender::abortSession(Session& session, TpAbortReason reason, TpSendOutcome outcome,
                            TpSendSink& sink) noexcept {
  const ControlData abort{TP_CM_ABORT,     static_cast<std::uint8_t>(reason),
                          ABORT_ROLE_BYTE, RESERVED,
                          RESERVED,        byteOf(session.pgn, 0),
                          byteOf(session.pgn, 8), byteOf(session.pgn, 16)};
  ++m_counters.abortsSent;
  sendControl(session, abort, sink);
  finish(session, outcome, reason, sink);
}

void TpSender::finish(Session& session, TpSendOutcome outcome, TpAbortReason reason,
                      TpSendSink& sink) noexcept {
  const TpSendResult result{session.pgn, session.destination, outcome, reason};
  if (session.state == State::Queued) {
    assert(outcome == TpSendOutcome::AddressChanged);
    --m_queuedMessages;
    ++m_counters.queuedDroppedByAddressChange;
  } else {
    switch (outcome) {
      case TpSendOutcome::Completed: ++m_counters.sessionsCompleted; break;
      case TpSendOutcome::AbortedByPeer: ++m_counters.sessionsAbortedByPeer; break;
      case TpSendOutcome::AbortSent: ++m_counters.sessionsAbortedByUs; break;
      case TpSendOutcome::TimedOut: ++m_counters.sessionsTimedOut; break;
      case TpSendOutcome::AddressChanged: ++m_counters.sessionsEndedByAddressChange; break;
    }
    m_running[session.destination] = NO_SESSION;
    --m_activeSessions;
  }
  session.state = State::Free;
  sink.finished(result);
}

void TpSender::sendControl(const Session& session, const ControlData& data,
                           TpSendSink& sink) noexcept {
  TpFrame frame;
  frame.canId = Id::fromPgn(PGN_TP_CM, session.priority, m_ownAddress, session.destination).toCanId();
  frame.length = static_cast<std::uint8_t>(TP_FRAME_LENGTH);
  frame.data = data;
  sink.send(frame);
}

// Started for a message that may be sent, else the reason to refuse it.
TpSendStatus TpSender::check(std::uint32_t pgn, std::uint8_t destination, std::uint8_t priority,
                             std::size_t size) const noexcept {
  if (m_ownAddress >= NULL_ADDRESS) return TpSendStatus::RefusedNoAddress;
  if (size < TP_MIN_MESSAGE_SIZE || size > TP_MAX_MESSAGE_SIZE) return TpSendStatus::RefusedSize;
  if (pgn > PGN_MASK) return TpSendStatus::RefusedPgn;
  if (priority > MAX_PRIORITY) return TpSendStatus::RefusedPriority;
  if (destination == NULL_ADDRESS || destination == m_ownAddress) {
    return TpSendStatus::RefusedDestination;
  }
  return TpSendStatus::Started;
}

bool TpSender::canStart(std::uint8_t destination) const noexcept {
  return m_running[destination] == NO_SESSION && m_activeSessions < m_config.maxSessions;
}

std::span<std::uint8_t> TpSender::bufferOf(const Session& session) noexcept {
  const auto index = static_cast<std::size_t>(&session - m_sessions.data());
  return std::span<std::uint8_t>(m_buffers).subspan(index * TP_MAX_MESSAGE_SIZE,
                                                    TP_MAX_MESSAGE_SIZE);
}

}  // namespace openvcu::j1939
