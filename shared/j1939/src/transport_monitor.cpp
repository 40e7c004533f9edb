#include "openvcu/j1939/transport_monitor.hpp"

#include "tp_layout.hpp"

#include <algorithm>
#include <limits>

namespace openvcu::j1939 {
namespace {

using namespace tp;

constexpr std::uint8_t ABORT_ROLE_ORIGINATOR = 0;

constexpr std::size_t keyOf(std::uint8_t source, std::uint8_t destination) noexcept {
  return static_cast<std::size_t>(source) * 256 + destination;
}

constexpr std::uint8_t saturatingIncrement(std::uint8_t value) noexcept {
  return value == std::numeric_limits<std::uint8_t>::max() ? value : static_cast<std::uint8_t>(value + 1);
}

}  // namespace

std::string_view tpOutcomeName(TpOutcome outcome) noexcept {
  switch (outcome) {
    case TpOutcome::Completed: return "Completed";
    case TpOutcome::Aborted: return "Aborted";
    case TpOutcome::TimedOut: return "TimedOut";
    case TpOutcome::Replaced: return "Replaced";
    case TpOutcome::ProtocolError: return "ProtocolError";
    case TpOutcome::Incomplete: return "Incomplete";
    case TpOutcome::Refused: return "Refused";
  }
  return "Unknown";
}

std::string_view tpTimerName(TpTimer timer) noexcept {
  switch (timer) {
    case TpTimer::None: return "";
    case TpTimer::T1: return "T1";
    case TpTimer::T2: return "T2";
    case TpTimer::T3: return "T3";
    case TpTimer::T4: return "T4";
  }
  return "";
}

std::string_view tpSideName(TpSide side) noexcept {
  switch (side) {
    case TpSide::None: return "";
    case TpSide::Originator: return "originator";
    case TpSide::Responder: return "responder";
  }
  return "";
}

std::string_view tpErrorText(TpError error) noexcept {
  switch (error) {
    case TpError::None: return "";
    case TpError::BadSequence: return "bad sequence number";
    case TpError::DuplicateSequence: return "duplicate sequence number";
    case TpError::OutsideWindow: return "packet outside the CTS window";
    case TpError::SizeMismatch: return "size mismatch";
    case TpError::CtsWhileTransferring: return "CTS while packets were still due";
    case TpError::BadCts: return "CTS for packets that do not follow";
    case TpError::EarlyEndOfMsgAck: return "EndOfMsgAck before all packets";
    case TpError::BadAnnouncement: return "invalid announcement";
    case TpError::PoolFull: return "session pool full";
  }
  return "";
}

TpMonitor::TpMonitor(const TpMonitorConfig& config) : m_config(config) {
  m_config.maxSessions = std::min<std::size_t>(m_config.maxSessions, NO_SESSION);
  m_sessions.resize(m_config.maxSessions);
  m_buffers.resize(m_config.maxSessions * TP_MAX_MESSAGE_SIZE);
  m_free.reserve(m_config.maxSessions);
  m_open.reserve(m_config.maxSessions);
  for (std::size_t i = m_config.maxSessions; i > 0; --i) m_free.push_back(static_cast<std::uint16_t>(i - 1));
  m_index.assign(SESSION_KEYS, NO_SESSION);
}

void TpMonitor::onFrame(std::uint32_t canId, std::span<const std::uint8_t> data, std::int64_t nowNs,
                        TpMonitorSink& sink) noexcept {
  const Id id = Id::fromCanId(canId);
  const std::uint32_t pgn = id.pgn();
  if (pgn != PGN_TP_CM && pgn != PGN_TP_DT) return;
  poll(nowNs, sink);
  if (pgn == PGN_TP_CM) {
    handleControl(id.sourceAddress, id.pduSpecific, data, nowNs, sink);
  } else {
    handleData(id.sourceAddress, id.pduSpecific, data, nowNs, sink);
  }
}

void TpMonitor::poll(std::int64_t nowNs, TpMonitorSink& sink) noexcept {
  for (;;) {
    Session* due = nullptr;
    for (const std::uint16_t index : m_open) {
      Session& session = m_sessions[index];
      if (session.deadlineNs <= nowNs && (due == nullptr || session.deadlineNs < due->deadlineNs)) due = &session;
    }
    if (due == nullptr) return;
    TpSessionEnd timedOut;
    timedOut.outcome = TpOutcome::TimedOut;
    timedOut.timer = due->timer;
    end(*due, timedOut, due->deadlineNs, sink);
  }
}

void TpMonitor::finish(std::int64_t endNs, TpMonitorSink& sink) noexcept {
  poll(endNs, sink);
  while (!m_open.empty()) endWith(m_sessions[m_open.front()], TpOutcome::Incomplete, endNs, sink);
}

std::optional<std::int64_t> TpMonitor::nextDeadlineNs() const noexcept {
  std::optional<std::int64_t> earliest;
  for (const std::uint16_t index : m_open) {
    const std::int64_t deadline = m_sessions[index].deadlineNs;
    if (!earliest || deadline < *earliest) earliest = deadline;
  }
  return earliest;
}

void TpMonitor::handleControl(std::uint8_t source, std::uint8_t destination, std::span<const std::uint8_t> data,
                              std::int64_t nowNs, TpMonitorSink& sink) noexcept {
  if (data.size() < TP_FRAME_LENGTH) {  // every TP.CM has 8 bytes: nothing to read safely
    ++m_counters.orphanFrames;
    return;
  }
  switch (data[CONTROL]) {
    case TP_CM_BAM:
    case TP_CM_RTS:
      announce(source, destination, data, data[CONTROL] == TP_CM_BAM, nowNs, sink);
      return;
    case TP_CM_CTS:
    case TP_CM_END_OF_MSG_ACK: {
      // From the responder to the originator: the session is (destination, source).
      Session* session = destination == GLOBAL_ADDRESS ? nullptr : find(destination, source);
      if (session == nullptr) {
        ++m_counters.orphanFrames;
        return;
      }
      if (data[CONTROL] == TP_CM_CTS) {
        handleCts(*session, data, nowNs, sink);
      } else {
        handleEndOfMsgAck(*session, data, nowNs, sink);
      }
      return;
    }
    case TP_CM_ABORT: {
      // Either side may abort: the role bits say which (J1939-21 2022); older senders
      // leave them 11b, then the originator's session is tried first.
      Session* asOriginator = destination == GLOBAL_ADDRESS ? nullptr : find(source, destination);
      Session* asResponder = destination == GLOBAL_ADDRESS ? nullptr : find(destination, source);
      const std::uint8_t role = data[ABORT_ROLE] & ABORT_ROLE_MASK;
      Session* session = nullptr;
      TpSide side = TpSide::None;
      if (role == TP_ABORT_ROLE_RESPONDER && asResponder != nullptr) {
        session = asResponder;
        side = TpSide::Responder;
      } else if (role == ABORT_ROLE_ORIGINATOR && asOriginator != nullptr) {
        session = asOriginator;
        side = TpSide::Originator;
      } else if (asOriginator != nullptr) {
        session = asOriginator;
        side = TpSide::Originator;
      } else if (asResponder != nullptr) {
        session = asResponder;
        side = TpSide::Responder;
      }
      if (session == nullptr) {
        ++m_counters.orphanFrames;
        return;
      }
      TpSessionEnd aborted;
      aborted.outcome = TpOutcome::Aborted;
      aborted.abortedBy = side;
      aborted.abortReason = static_cast<TpAbortReason>(data[ABORT_REASON]);
      end(*session, aborted, nowNs, sink);
      return;
    }
    default:
      ++m_counters.orphanFrames;
      return;
  }
}

void TpMonitor::announce(std::uint8_t source, std::uint8_t destination, std::span<const std::uint8_t> data,
                         bool broadcast, std::int64_t nowNs, TpMonitorSink& sink) noexcept {
  // A new announcement for the same pair ends the old session, valid or not.
  if (Session* existing = find(source, destination)) endWith(*existing, TpOutcome::Replaced, nowNs, sink);

  TpSessionInfo info;
  info.pgn = pgnField(data);
  info.source = source;
  info.destination = destination;
  info.broadcast = broadcast;
  const std::size_t size = sizeField(data);
  info.size = static_cast<std::uint16_t>(size);
  info.packets = data[PACKET_COUNT];
  info.startNs = nowNs;
  info.endNs = nowNs;

  TpError error = TpError::None;
  if (size < TP_MIN_MESSAGE_SIZE || size > TP_MAX_MESSAGE_SIZE || info.packets != packetsFor(size) ||
      info.pgn > PGN_MASK || broadcast != (destination == GLOBAL_ADDRESS)) {
    error = TpError::BadAnnouncement;
  } else if (m_free.empty()) {
    error = TpError::PoolFull;
  }
  if (error != TpError::None) {
    ++m_counters.refused;
    TpSessionEnd refused;
    refused.session = info;
    refused.outcome = TpOutcome::Refused;
    refused.error = error;
    sink.ended(refused);
    return;
  }

  const std::uint16_t index = m_free.back();
  m_free.pop_back();
  Session& session = m_sessions[index];
  session = Session{};
  session.info = info;
  session.nextPacket = 1;
  session.openIndex = static_cast<std::uint16_t>(m_open.size());
  m_open.push_back(index);
  m_index[keyOf(source, destination)] = index;
  ++m_counters.started;
  if (broadcast) {
    ++m_counters.bam;
    session.state = State::BamData;
    setDeadline(session, nowNs, TP_T1_NS, TpTimer::T1);
  } else {
    ++m_counters.rtsCts;
    session.state = State::AwaitCts;
    setDeadline(session, nowNs, TP_T3_NS, TpTimer::T3);
  }
}

void TpMonitor::handleCts(Session& session, std::span<const std::uint8_t> data, std::int64_t nowNs,
                          TpMonitorSink& sink) noexcept {
  if (session.state == State::WindowData && session.windowStarted) {
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, TpError::CtsWhileTransferring);
    return;
  }
  const std::uint8_t count = data[CTS_COUNT];
  const std::uint16_t next = data[CTS_NEXT];
  if (count == 0) {  // hold: the responder keeps the session open without data
    session.info.holds = saturatingIncrement(session.info.holds);
    session.state = State::Held;
    setDeadline(session, nowNs, TP_T4_NS, TpTimer::T4);
    return;
  }
  // The next packet, or earlier ones again (a retransmission request); never a gap.
  if (next == 0 || next > session.info.packets || next > session.nextPacket) {
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, TpError::BadCts);
    return;
  }
  session.nextPacket = next;
  session.windowEnd = static_cast<std::uint16_t>(std::min<unsigned>(next + count - 1u, session.info.packets));
  session.info.windows = saturatingIncrement(session.info.windows);
  session.windowStarted = false;
  session.state = State::WindowData;
  setDeadline(session, nowNs, TP_T2_NS, TpTimer::T2);
}

void TpMonitor::handleEndOfMsgAck(Session& session, std::span<const std::uint8_t> data, std::int64_t nowNs,
                                  TpMonitorSink& sink) noexcept {
  if (session.state != State::AwaitAck) {
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, TpError::EarlyEndOfMsgAck);
    return;
  }
  if (sizeField(data) != session.info.size || data[PACKET_COUNT] != session.info.packets) {
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, TpError::SizeMismatch);
    return;
  }
  endWith(session, TpOutcome::Completed, nowNs, sink);
}

void TpMonitor::handleData(std::uint8_t source, std::uint8_t destination, std::span<const std::uint8_t> data,
                           std::int64_t nowNs, TpMonitorSink& sink) noexcept {
  Session* found = find(source, destination);
  if (found == nullptr) {
    ++m_counters.orphanFrames;
    return;
  }
  Session& session = *found;
  if (data.empty()) {
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, TpError::SizeMismatch);
    return;
  }
  const std::uint16_t sequence = data[0];
  // CAN can deliver a frame twice (an error in the last bit of EOF makes the sender
  // repeat it): the previous packet again changes nothing.
  if (sequence != 0 && sequence + 1 == session.nextPacket) {
    ++m_counters.repeatedPackets;
    return;
  }
  const bool receiving = session.state == State::BamData || session.state == State::WindowData;
  if (!receiving) {
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, TpError::OutsideWindow);
    return;
  }
  if (sequence != session.nextPacket) {
    TpError error = TpError::BadSequence;
    if (sequence != 0 && sequence < session.nextPacket) {
      error = TpError::DuplicateSequence;
    } else if (session.state == State::WindowData && sequence > session.windowEnd) {
      error = TpError::OutsideWindow;
    }
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, error);
    return;
  }

  const std::size_t offset = (session.nextPacket - 1u) * TP_BYTES_PER_PACKET;
  const std::size_t count = std::min(TP_BYTES_PER_PACKET, session.info.size - offset);
  if (data.size() < 1 + count) {  // a short last packet may omit its padding, no more
    endWith(session, TpOutcome::ProtocolError, nowNs, sink, TpError::SizeMismatch);
    return;
  }
  std::copy_n(data.begin() + 1, count, bufferOf(session).begin() + static_cast<std::ptrdiff_t>(offset));
  session.info.packetsReceived =
      std::max(session.info.packetsReceived, static_cast<std::uint8_t>(session.nextPacket));
  ++session.nextPacket;
  session.windowStarted = true;

  // After a retransmitted window the rest may have arrived before: then all are in.
  const bool windowDone = session.state == State::WindowData && session.nextPacket > session.windowEnd;
  if (windowDone && session.info.packetsReceived == session.info.packets) {
    session.nextPacket = static_cast<std::uint16_t>(session.info.packets + 1u);
  }
  if (session.nextPacket > session.info.packets) {
    if (!session.delivered) {
      session.delivered = true;
      TpMonitoredMessage message;
      message.session = session.info;
      message.session.endNs = nowNs;
      message.data = bufferOf(session).first(session.info.size);
      sink.completed(message);
    }
    if (session.info.broadcast) {
      endWith(session, TpOutcome::Completed, nowNs, sink);
    } else {
      session.state = State::AwaitAck;
      setDeadline(session, nowNs, TP_T3_NS, TpTimer::T3);
    }
  } else if (windowDone) {
    session.state = State::AwaitCts;
    setDeadline(session, nowNs, TP_T3_NS, TpTimer::T3);
  } else {
    setDeadline(session, nowNs, TP_T1_NS, TpTimer::T1);
  }
}

void TpMonitor::setDeadline(Session& session, std::int64_t nowNs, std::int64_t delayNs, TpTimer timer) noexcept {
  session.deadlineNs = after(nowNs, delayNs);
  session.timer = timer;
}

void TpMonitor::endWith(Session& session, TpOutcome outcome, std::int64_t nowNs, TpMonitorSink& sink,
                        TpError error) noexcept {
  TpSessionEnd ended;
  ended.outcome = outcome;
  ended.error = error;
  end(session, ended, nowNs, sink);
}

void TpMonitor::end(Session& session, TpSessionEnd ended, std::int64_t nowNs, TpMonitorSink& sink) noexcept {
  const auto index = static_cast<std::uint16_t>(&session - m_sessions.data());
  // Swap-remove from the open list.
  const std::uint16_t last = m_open.back();
  m_open[session.openIndex] = last;
  m_sessions[last].openIndex = session.openIndex;
  m_open.pop_back();
  m_free.push_back(index);
  m_index[keyOf(session.info.source, session.info.destination)] = NO_SESSION;
  session.state = State::Idle;

  switch (ended.outcome) {
    case TpOutcome::Completed: ++m_counters.completed; break;
    case TpOutcome::Aborted: ++m_counters.aborted; break;
    case TpOutcome::TimedOut: ++m_counters.timedOut; break;
    case TpOutcome::Replaced: ++m_counters.replaced; break;
    case TpOutcome::ProtocolError: ++m_counters.protocolErrors; break;
    case TpOutcome::Incomplete: ++m_counters.incomplete; break;
    case TpOutcome::Refused: ++m_counters.refused; break;
  }
  ended.session = session.info;
  ended.session.endNs = nowNs;
  sink.ended(ended);
}

TpMonitor::Session* TpMonitor::find(std::uint8_t source, std::uint8_t destination) noexcept {
  const std::uint16_t index = m_index[keyOf(source, destination)];
  return index == NO_SESSION ? nullptr : &m_sessions[index];
}

std::span<std::uint8_t> TpMonitor::bufferOf(const Session& session) noexcept {
  const auto index = static_cast<std::size_t>(&session - m_sessions.data());
  return {m_buffers.data() + index * TP_MAX_MESSAGE_SIZE, TP_MAX_MESSAGE_SIZE};
}

}  // namespace openvcu::j1939
