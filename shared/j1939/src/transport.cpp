#include "openvcu/j1939/transport.hpp"

#include "tp_layout.hpp"

#include <algorithm>
#include <cassert>
#include <limits>

namespace openvcu::j1939 {
namespace {

using namespace tp;

// Abort byte 2: bits 7..2 reserved (1), bits 1..0 the role of the sender (J1939-21 2022).
constexpr std::uint8_t ABORT_ROLE_BYTE = 0xFC | TP_ABORT_ROLE_RESPONDER;
// Addresses 0..253 may originate a session; 254 (null) and 255 (global) may not.
constexpr std::size_t SOURCE_ADDRESSES = NULL_ADDRESS;

// A CTS granting `count` packets from `nextPacket` on (count 0 holds the session open).
constexpr ControlData clearToSend(std::uint8_t count, std::uint8_t nextPacket, std::uint32_t pgn) noexcept {
  return ControlData{TP_CM_CTS, count, nextPacket, RESERVED, RESERVED, byteOf(pgn, 0), byteOf(pgn, 8), byteOf(pgn, 16)};
}

static_assert(packetsFor(TP_MIN_MESSAGE_SIZE) == 2);

// Reason to refuse an RTS or BAM announcing `size` bytes in `packets` packets, or None.
constexpr TpAbortReason checkAnnouncement(std::size_t size, std::size_t packets,
                                          std::uint32_t pgn) noexcept {
  if (size > TP_MAX_MESSAGE_SIZE) return TpAbortReason::MessageTooLarge;
  if (size < TP_MIN_MESSAGE_SIZE || packets != packetsFor(size) || pgn > PGN_MASK) {
    return TpAbortReason::Other;
  }
  return TpAbortReason::None;
}

constexpr std::size_t keyOf(std::uint8_t source, bool broadcast) noexcept {
  return static_cast<std::size_t>(source) * 2 + (broadcast ? 1 : 0);
}

}  // namespace

std::string_view tpAbortReasonName(TpAbortReason reason) noexcept {
  switch (reason) {
    case TpAbortReason::None: return "None";
    case TpAbortReason::AlreadyInSession: return "AlreadyInSession";
    case TpAbortReason::ResourcesNeeded: return "ResourcesNeeded";
    case TpAbortReason::Timeout: return "Timeout";
    case TpAbortReason::CtsWhileTransferring: return "CtsWhileTransferring";
    case TpAbortReason::RetransmitLimit: return "RetransmitLimit";
    case TpAbortReason::UnexpectedDataPacket: return "UnexpectedDataPacket";
    case TpAbortReason::BadSequenceNumber: return "BadSequenceNumber";
    case TpAbortReason::DuplicateSequenceNumber: return "DuplicateSequenceNumber";
    case TpAbortReason::MessageTooLarge: return "MessageTooLarge";
    case TpAbortReason::Other: return "Other";
  }
  return "Unknown";
}

std::string_view tpEventKindName(TpEventKind kind) noexcept {
  switch (kind) {
    case TpEventKind::Completed: return "Completed";
    case TpEventKind::Aborted: return "Aborted";
    case TpEventKind::AbortSent: return "AbortSent";
    case TpEventKind::Timeout: return "Timeout";
    case TpEventKind::SessionReplaced: return "SessionReplaced";
    case TpEventKind::Dropped: return "Dropped";
    case TpEventKind::Refused: return "Refused";
    case TpEventKind::Ignored: return "Ignored";
  }
  return "Unknown";
}

TpReceiver::TpReceiver(const TpReceiverConfig& config) : m_config(config) {
  assert(config.maxPacketsPerCts >= 1);
  m_config.maxPacketsPerCts = std::max<std::uint8_t>(m_config.maxPacketsPerCts, 1);
  // One BAM and one RTS/CTS session per source address is all the protocol allows.
  m_config.maxSessions = std::min(m_config.maxSessions, 2 * SOURCE_ADDRESSES);
  m_config.maxHeldSessions = std::min(m_config.maxHeldSessions, SOURCE_ADDRESSES);
  if (m_config.maxSessions == 0) m_config.maxHeldSessions = 0;  // nothing would free a buffer
  m_acceptsDirected = m_config.ownAddress < NULL_ADDRESS;

  m_sessions.resize(m_config.maxSessions + m_config.maxHeldSessions);
  m_buffers.resize(m_config.maxSessions * TP_MAX_MESSAGE_SIZE);
  m_freeBuffers.reserve(m_config.maxSessions);
  for (std::size_t i = m_config.maxSessions; i > 0; --i) {
    m_freeBuffers.push_back(static_cast<std::uint16_t>(i - 1));
  }
  m_sessionIndex.fill(NO_SESSION);
}

void TpReceiver::setOwnAddress(std::uint8_t address) noexcept {
  m_config.ownAddress = address;
  m_acceptsDirected = address < NULL_ADDRESS;
}

void TpReceiver::onFrame(std::uint32_t canId, std::span<const std::uint8_t> data,
                         std::int64_t nowNs, TpSink& sink) noexcept {
  const Id id = Id::fromCanId(canId);
  const std::uint32_t pgn = id.pgn();
  if (pgn != PGN_TP_CM && pgn != PGN_TP_DT) return;

  expire(nowNs, sink);
  const std::uint8_t source = id.sourceAddress;
  const bool broadcast = id.pduSpecific == GLOBAL_ADDRESS;
  const bool toUs = broadcast || (m_acceptsDirected && id.pduSpecific == m_config.ownAddress);
  if (!toUs || source == m_config.ownAddress) {
    ++m_counters.framesNotForUs;
    return;
  }
  if (source >= NULL_ADDRESS || data.size() > TP_FRAME_LENGTH) {
    ignore(source, broadcast, 0, TpAbortReason::Other, sink);
    return;
  }
  if (pgn == PGN_TP_CM) {
    handleControl(source, broadcast, data, nowNs, sink);
  } else {
    handleData(source, broadcast, data, nowNs, sink);
  }
  promoteHeld(nowNs, sink);
}

void TpReceiver::poll(std::int64_t nowNs, TpSink& sink) noexcept { expire(nowNs, sink); }

std::optional<std::int64_t> TpReceiver::nextDeadlineNs() const noexcept {
  std::optional<std::int64_t> earliest;
  for (const Session& session : m_sessions) {
    if (session.state == State::Idle) continue;
    if (!earliest || session.deadlineNs < *earliest) earliest = session.deadlineNs;
  }
  return earliest;
}

void TpReceiver::handleControl(std::uint8_t source, bool broadcast,
                               std::span<const std::uint8_t> data, std::int64_t nowNs,
                               TpSink& sink) noexcept {
  if (data.size() != TP_FRAME_LENGTH) {
    ignore(source, broadcast, 0, TpAbortReason::Other, sink);
    return;
  }
  const std::uint32_t pgn = pgnField(data);
  switch (data[CONTROL]) {
    case TP_CM_RTS:
      if (broadcast) break;  // RTS/CTS needs a destination that can answer
      handleRts(source, data, pgn, nowNs, sink);
      return;
    case TP_CM_BAM:
      if (!broadcast) break;  // J1939-21: BAM goes to the global address
      handleBam(source, data, pgn, nowNs, sink);
      return;
    case TP_CM_ABORT:
      if (broadcast) break;  // a BAM cannot be aborted
      handleAbort(source, data, pgn, sink);
      return;
    default:  // CTS and EndOfMsgAck are for originators; we never originate
      break;
  }
  ignore(source, broadcast, pgn, TpAbortReason::Other, sink);
}

void TpReceiver::handleRts(std::uint8_t source, std::span<const std::uint8_t> data,
                           std::uint32_t pgn, std::int64_t nowNs, TpSink& sink) noexcept {
  if (Session* existing = find(source, false)) {
    if (existing->pgn != pgn) {
      // One RTS/CTS session per source -> destination pair: the running one continues.
      sendAbort(source, pgn, TpAbortReason::AlreadyInSession, sink);
      refuse(source, false, pgn, TpAbortReason::AlreadyInSession, sink);
      return;
    }
    // J1939-21: the most recent RTS for the same PGN is acted on, the old one dropped
    // without an Abort.
    finish(*existing, TpEventKind::SessionReplaced, TpAbortReason::None, sink);
  }

  const std::size_t size = static_cast<std::size_t>(data[SIZE_LOW]) |
                           (static_cast<std::size_t>(data[SIZE_HIGH]) << 8);
  const std::uint8_t packets = data[PACKET_COUNT];
  TpAbortReason reason = checkAnnouncement(size, packets, pgn);
  State state = State::Receiving;
  if (reason == TpAbortReason::None && m_freeBuffers.empty()) {
    if (m_heldSessions < m_config.maxHeldSessions) {
      state = State::Held;
    } else {
      reason = TpAbortReason::AlreadyInSession;
    }
  }
  if (reason != TpAbortReason::None) {
    sendAbort(source, pgn, reason, sink);
    refuse(source, false, pgn, reason, sink);
    return;
  }

  Session& session = *openSession(source, false, state);
  session.pgn = pgn;
  session.size = static_cast<std::uint16_t>(size);
  session.packets = packets;
  // 0 is no valid limit (byte 4 was reserved, 0xFF, before the limit existed): no limit.
  session.originatorLimit = data[PACKET_LIMIT] == 0 ? TP_NO_PACKET_LIMIT : data[PACKET_LIMIT];
  ++m_counters.sessionsStarted;
  if (state == State::Receiving) {
    sendCts(session, nowNs, sink);
  } else {
    sendHold(session, nowNs, sink);
  }
}

void TpReceiver::handleBam(std::uint8_t source, std::span<const std::uint8_t> data,
                           std::uint32_t pgn, std::int64_t nowNs, TpSink& sink) noexcept {
  // One BAM per source: a new announcement ends the old transfer, valid or not.
  if (Session* existing = find(source, true)) {
    finish(*existing, TpEventKind::SessionReplaced, TpAbortReason::None, sink);
  }
  const std::size_t size = static_cast<std::size_t>(data[SIZE_LOW]) |
                           (static_cast<std::size_t>(data[SIZE_HIGH]) << 8);
  const std::uint8_t packets = data[PACKET_COUNT];
  TpAbortReason reason = checkAnnouncement(size, packets, pgn);
  if (reason == TpAbortReason::None && m_freeBuffers.empty()) {
    reason = TpAbortReason::ResourcesNeeded;
  }
  if (reason != TpAbortReason::None) {
    refuse(source, true, pgn, reason, sink);
    return;
  }

  Session& session = *openSession(source, true, State::Receiving);
  session.pgn = pgn;
  session.size = static_cast<std::uint16_t>(size);
  session.packets = packets;
  session.deadlineNs = after(nowNs, TP_T1_NS);
  ++m_counters.sessionsStarted;
}

void TpReceiver::handleAbort(std::uint8_t source, std::span<const std::uint8_t> data,
                             std::uint32_t pgn, TpSink& sink) noexcept {
  Session* session = find(source, false);
  if (session == nullptr || session->pgn != pgn) {
    ignore(source, false, pgn, TpAbortReason::Other, sink);
    return;
  }
  finish(*session, TpEventKind::Aborted, static_cast<TpAbortReason>(data[ABORT_REASON]), sink);
}

void TpReceiver::handleData(std::uint8_t source, bool broadcast,
                            std::span<const std::uint8_t> data, std::int64_t nowNs,
                            TpSink& sink) noexcept {
  Session* session = find(source, broadcast);
  if (session == nullptr) {
    ignore(source, broadcast, 0, TpAbortReason::UnexpectedDataPacket, sink);
    return;
  }
  if (data.empty()) {
    ignore(source, broadcast, session->pgn, TpAbortReason::Other, sink);
    return;
  }
  if (session->state == State::Held) {  // no CTS asked for data yet
    sendAbort(source, session->pgn, TpAbortReason::UnexpectedDataPacket, sink);
    finish(*session, TpEventKind::AbortSent, TpAbortReason::UnexpectedDataPacket, sink);
    return;
  }

  const std::uint16_t sequence = data[0];
  if (sequence == session->nextPacket) {
    acceptPacket(*session, data, nowNs, sink);
    return;
  }
  // CAN can deliver a frame twice (an error in the last bit of EOF makes the sender
  // repeat a frame receivers already took): the previous packet again is harmless.
  if (sequence != 0 && sequence + 1 == session->nextPacket) {
    ignore(source, broadcast, session->pgn, TpAbortReason::DuplicateSequenceNumber, sink);
    return;
  }
  const TpAbortReason reason = sequence != 0 && sequence < session->nextPacket
                                   ? TpAbortReason::DuplicateSequenceNumber
                                   : TpAbortReason::BadSequenceNumber;
  if (broadcast) {
    finish(*session, TpEventKind::Dropped, reason, sink);
  } else {
    sendAbort(source, session->pgn, reason, sink);
    finish(*session, TpEventKind::AbortSent, reason, sink);
  }
}

void TpReceiver::acceptPacket(Session& session, std::span<const std::uint8_t> data,
                              std::int64_t nowNs, TpSink& sink) noexcept {
  const std::size_t offset = (session.nextPacket - 1u) * TP_BYTES_PER_PACKET;
  const std::size_t count = std::min(TP_BYTES_PER_PACKET, session.size - offset);
  if (data.size() < 1 + count) {  // a short last packet may omit its padding, no more
    ignore(session.source, session.broadcast, session.pgn, TpAbortReason::Other, sink);
    return;
  }
  std::copy_n(data.begin() + 1, count, bufferOf(session).begin() + static_cast<std::ptrdiff_t>(offset));
  ++session.nextPacket;
  if (session.nextPacket > session.packets) {
    complete(session, nowNs, sink);
  } else if (!session.broadcast && session.nextPacket > session.windowEnd) {
    sendCts(session, nowNs, sink);
  } else {
    session.deadlineNs = after(nowNs, TP_T1_NS);
  }
}

void TpReceiver::complete(Session& session, std::int64_t nowNs, TpSink& sink) noexcept {
  if (!session.broadcast) {
    const ControlData ack{TP_CM_END_OF_MSG_ACK,     byteOf(session.size, 0),
                          byteOf(session.size, 8),  session.packets,
                          RESERVED,                 byteOf(session.pgn, 0),
                          byteOf(session.pgn, 8),   byteOf(session.pgn, 16)};
    sendControl(session.source, ack, sink);
  }
  TpMessage message;
  message.pgn = session.pgn;
  message.source = session.source;
  message.destination = destinationOf(session.broadcast);
  message.data = bufferOf(session).first(session.size);
  message.completedNs = nowNs;
  message.broadcast = session.broadcast;
  sink.completed(message);
  finish(session, TpEventKind::Completed, TpAbortReason::None, sink);
}

void TpReceiver::expire(std::int64_t nowNs, TpSink& sink) noexcept {
  for (Session& session : m_sessions) {
    if (session.state != State::Receiving || session.deadlineNs > nowNs) continue;
    if (!session.broadcast) sendAbort(session.source, session.pgn, TpAbortReason::Timeout, sink);
    finish(session, TpEventKind::Timeout, TpAbortReason::Timeout, sink);
  }
  // Buffers freed by timeouts go to held sessions first: they get a CTS, not another CTS(0).
  promoteHeld(nowNs, sink);
  for (Session& session : m_sessions) {
    if (session.state == State::Held && session.deadlineNs <= nowNs) sendHold(session, nowNs, sink);
  }
}

void TpReceiver::promoteHeld(std::int64_t nowNs, TpSink& sink) noexcept {
  while (!m_freeBuffers.empty() && m_heldSessions > 0) {
    Session* oldest = nullptr;
    for (Session& session : m_sessions) {
      if (session.state != State::Held) continue;
      if (oldest == nullptr || session.holdTicket < oldest->holdTicket) oldest = &session;
    }
    assert(oldest != nullptr);
    if (oldest == nullptr) return;
    --m_heldSessions;
    oldest->state = State::Receiving;
    oldest->buffer = m_freeBuffers.back();
    m_freeBuffers.pop_back();
    sendCts(*oldest, nowNs, sink);
  }
}

TpReceiver::Session* TpReceiver::find(std::uint8_t source, bool broadcast) noexcept {
  const std::uint16_t index = m_sessionIndex[keyOf(source, broadcast)];
  return index == NO_SESSION ? nullptr : &m_sessions[index];
}

// Precondition: no session for (source, broadcast); a free buffer for Receiving, a free
// hold place for Held. Then an idle record exists, as records = buffers + hold places.
TpReceiver::Session* TpReceiver::openSession(std::uint8_t source, bool broadcast,
                                             State state) noexcept {
  const auto idle = std::find_if(m_sessions.begin(), m_sessions.end(),
                                 [](const Session& session) { return session.state == State::Idle; });
  assert(idle != m_sessions.end());
  Session& session = *idle;
  session = Session{};
  session.source = source;
  session.broadcast = broadcast;
  session.state = state;
  session.nextPacket = 1;
  if (state == State::Receiving) {
    session.buffer = m_freeBuffers.back();
    m_freeBuffers.pop_back();
  } else {
    ++m_heldSessions;
    session.holdTicket = m_nextHoldTicket++;
  }
  m_sessionIndex[keyOf(source, broadcast)] =
      static_cast<std::uint16_t>(std::distance(m_sessions.begin(), idle));
  ++m_activeSessions;
  return &session;
}

void TpReceiver::closeSession(Session& session) noexcept {
  if (session.state == State::Receiving) {
    m_freeBuffers.push_back(session.buffer);  // within the reserved capacity
  } else if (session.state == State::Held) {
    --m_heldSessions;
  }
  m_sessionIndex[keyOf(session.source, session.broadcast)] = NO_SESSION;
  session.state = State::Idle;
  --m_activeSessions;
}

void TpReceiver::finish(Session& session, TpEventKind kind, TpAbortReason reason,
                        TpSink& sink) noexcept {
  const TpEvent event{kind, session.source, destinationOf(session.broadcast), session.pgn,
                      reason};
  switch (kind) {
    case TpEventKind::Completed: ++m_counters.sessionsCompleted; break;
    case TpEventKind::Aborted: ++m_counters.sessionsAbortedByPeer; break;
    case TpEventKind::AbortSent: ++m_counters.sessionsAbortedByUs; break;
    case TpEventKind::Timeout: ++m_counters.sessionsTimedOut; break;
    case TpEventKind::SessionReplaced: ++m_counters.sessionsReplaced; break;
    case TpEventKind::Dropped: ++m_counters.sessionsDropped; break;
    case TpEventKind::Refused:
    case TpEventKind::Ignored: assert(false && "not a session outcome"); break;
  }
  closeSession(session);
  sink.event(event);
}

void TpReceiver::sendCts(Session& session, std::int64_t nowNs, TpSink& sink) noexcept {
  const std::size_t remaining = session.packets - session.nextPacket + 1u;
  const std::size_t count = std::min({remaining, static_cast<std::size_t>(m_config.maxPacketsPerCts),
                                      static_cast<std::size_t>(session.originatorLimit)});
  session.windowEnd = static_cast<std::uint16_t>(session.nextPacket + count - 1);
  session.deadlineNs = after(nowNs, TP_T2_NS);
  sendControl(session.source,
              clearToSend(static_cast<std::uint8_t>(count), static_cast<std::uint8_t>(session.nextPacket), session.pgn),
              sink);
}

void TpReceiver::sendHold(Session& session, std::int64_t nowNs, TpSink& sink) noexcept {
  session.deadlineNs = after(nowNs, TP_TH_NS);
  ++m_counters.holdsSent;
  sendControl(session.source, clearToSend(0, static_cast<std::uint8_t>(session.nextPacket), session.pgn), sink);
}

void TpReceiver::sendAbort(std::uint8_t destination, std::uint32_t pgn, TpAbortReason reason,
                           TpSink& sink) noexcept {
  const ControlData abort{TP_CM_ABORT,      static_cast<std::uint8_t>(reason),
                          ABORT_ROLE_BYTE,  RESERVED,
                          RESERVED,         byteOf(pgn, 0),
                          byteOf(pgn, 8),   byteOf(pgn, 16)};
  ++m_counters.abortsSent;
  sendControl(destination, abort, sink);
}

void TpReceiver::sendControl(std::uint8_t destination, const ControlData& data,
                             TpSink& sink) noexcept {
  TpFrame frame;
  frame.canId =
      Id::fromPgn(PGN_TP_CM, TP_CM_PRIORITY, m_config.ownAddress, destination).toCanId();
  frame.length = static_cast<std::uint8_t>(TP_FRAME_LENGTH);
  frame.data = data;
  sink.send(frame);
}

void TpReceiver::ignore(std::uint8_t source, bool broadcast, std::uint32_t pgn,
                        TpAbortReason reason, TpSink& sink) noexcept {
  ++m_counters.framesIgnored;
  sink.event(TpEvent{TpEventKind::Ignored, source, destinationOf(broadcast), pgn, reason});
}

void TpReceiver::refuse(std::uint8_t source, bool broadcast, std::uint32_t pgn,
                        TpAbortReason reason, TpSink& sink) noexcept {
  ++m_counters.announcementsRefused;
  sink.event(TpEvent{TpEventKind::Refused, source, destinationOf(broadcast), pgn, reason});
}

std::uint8_t TpReceiver::destinationOf(bool broadcast) const noexcept {
  return broadcast ? GLOBAL_ADDRESS : m_config.ownAddress;
}

std::span<std::uint8_t> TpReceiver::bufferOf(const Session& session) noexcept {
  return std::span<std::uint8_t>(m_buffers).subspan(
      static_cast<std::size_t>(session.buffer) * TP_MAX_MESSAGE_SIZE, TP_MAX_MESSAGE_SIZE);
}

}  // namespace openvcu::j1939
