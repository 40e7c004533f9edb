// TpMonitor: passive J1939-21 session monitoring (issue 21), every outcome with its figures.
#include "openvcu/j1939/transport_monitor.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

using namespace openvcu::j1939;

template <>
struct doctest::StringMaker<TpOutcome> {
  static doctest::String convert(TpOutcome outcome) {
    const std::string_view name = tpOutcomeName(outcome);
    return {name.data(), static_cast<doctest::String::size_type>(name.size())};
  }
};
template <>
struct doctest::StringMaker<TpTimer> {
  static doctest::String convert(TpTimer timer) {
    const std::string_view name = tpTimerName(timer);
    return name.empty() ? "None" : doctest::String{name.data(), static_cast<doctest::String::size_type>(name.size())};
  }
};
template <>
struct doctest::StringMaker<TpError> {
  static doctest::String convert(TpError error) {
    const std::string_view text = tpErrorText(error);
    return text.empty() ? "None" : doctest::String{text.data(), static_cast<doctest::String::size_type>(text.size())};
  }
};

namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::uint8_t ENGINE = 0x00;
constexpr std::uint8_t BRAKES = 0x0B;
constexpr std::uint8_t GATEWAY = 0x20;
constexpr std::uint8_t VCU = 0x21;
constexpr std::uint32_t PGN_DM1_TEST = 0xFECA;       // 65226
constexpr std::uint32_t PGN_COMPONENT_ID = 0xFEEB;   // 65259
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START_NS = 10'000 * MS;
constexpr std::int64_t GAP_NS = 50 * MS;

std::uint32_t cmId(std::uint8_t source, std::uint8_t destination) {
  return 0x1CEC0000u | (static_cast<std::uint32_t>(destination) << 8) | source;
}
std::uint32_t dtId(std::uint8_t source, std::uint8_t destination) {
  return 0x1CEB0000u | (static_cast<std::uint32_t>(destination) << 8) | source;
}

Bytes control(std::uint8_t code, std::uint8_t b1, std::uint8_t b2, std::uint8_t b3, std::uint8_t b4,
              std::uint32_t pgn) {
  return {code, b1, b2, b3, b4, static_cast<std::uint8_t>(pgn & 0xFF), static_cast<std::uint8_t>((pgn >> 8) & 0xFF),
          static_cast<std::uint8_t>((pgn >> 16) & 0xFF)};
}
std::uint8_t lowByte(std::uint16_t value) { return static_cast<std::uint8_t>(value & 0xFF); }
std::uint8_t highByte(std::uint16_t value) { return static_cast<std::uint8_t>(value >> 8); }

Bytes bam(std::uint16_t size, std::uint8_t packets, std::uint32_t pgn) {
  return control(TP_CM_BAM, lowByte(size), highByte(size), packets, 0xFF, pgn);
}
Bytes rts(std::uint16_t size, std::uint8_t packets, std::uint8_t perCts, std::uint32_t pgn) {
  return control(TP_CM_RTS, lowByte(size), highByte(size), packets, perCts, pgn);
}
Bytes cts(std::uint8_t count, std::uint8_t next, std::uint32_t pgn) {
  return control(TP_CM_CTS, count, next, 0xFF, 0xFF, pgn);
}
Bytes endOfMsgAck(std::uint16_t size, std::uint8_t packets, std::uint32_t pgn) {
  return control(TP_CM_END_OF_MSG_ACK, lowByte(size), highByte(size), packets, 0xFF, pgn);
}
Bytes abortFrame(TpAbortReason reason, std::uint8_t role, std::uint32_t pgn) {
  return control(TP_CM_ABORT, static_cast<std::uint8_t>(reason), static_cast<std::uint8_t>(0xFC | role), 0xFF, 0xFF,
                 pgn);
}

// Message bytes 0..size-1 hold (seed + i) & 0xFF.
Bytes payload(std::size_t size, std::uint8_t seed) {
  Bytes bytes(size);
  for (std::size_t i = 0; i < size; ++i) bytes[i] = static_cast<std::uint8_t>(seed + i);
  return bytes;
}
// TP.DT packet `sequence` (1-based) of `message`, padded with FF.
Bytes packet(const Bytes& message, std::uint8_t sequence) {
  Bytes frame(8, 0xFF);
  frame[0] = sequence;
  const std::size_t offset = (sequence - 1u) * 7u;
  for (std::size_t i = 0; i < 7 && offset + i < message.size(); ++i) frame[1 + i] = message[offset + i];
  return frame;
}

struct Recorder final : TpMonitorSink {
  struct Message {
    TpSessionInfo session;
    Bytes data;
  };
  std::vector<Message> messages;
  std::vector<TpSessionEnd> ends;
  void completed(const TpMonitoredMessage& message) noexcept override {
    messages.push_back({message.session, Bytes(message.data.begin(), message.data.end())});
  }
  void ended(const TpSessionEnd& end) noexcept override { ends.push_back(end); }
};

struct Bus {
  TpMonitor sut;
  Recorder out;
  std::int64_t now{START_NS};
  explicit Bus(TpMonitorConfig config = {}) : sut(config) {}
  void send(std::uint32_t id, const Bytes& data, std::int64_t gapNs = GAP_NS) {
    now += gapNs;
    sut.onFrame(id, data, now, out);
  }
};

}  // namespace

TEST_CASE("monitor reassembles a BAM and reports it completed with its figures") {
  Bus bus;
  const Bytes message = payload(20, 0x40);
  bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 3, PGN_DM1_TEST), 0);
  const std::int64_t startNs = bus.now;
  for (std::uint8_t sequence = 1; sequence <= 3; ++sequence) bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, sequence));

  REQUIRE(bus.out.messages.size() == 1);
  CHECK(bus.out.messages[0].data == message);
  CHECK(bus.out.messages[0].session.pgn == PGN_DM1_TEST);
  CHECK(bus.out.messages[0].session.broadcast);
  REQUIRE(bus.out.ends.size() == 1);
  const TpSessionEnd& end = bus.out.ends[0];
  CHECK(end.outcome == TpOutcome::Completed);
  CHECK(end.session.source == ENGINE);
  CHECK(end.session.destination == GLOBAL_ADDRESS);
  CHECK(end.session.size == 20);
  CHECK(end.session.packets == 3);
  CHECK(end.session.packetsReceived == 3);
  CHECK(end.session.startNs == startNs);
  CHECK(end.session.endNs == startNs + 3 * GAP_NS);
  CHECK(bus.sut.openSessions() == 0);
  CHECK(bus.sut.counters().bam == 1);
  CHECK(bus.sut.counters().completed == 1);
}

TEST_CASE("monitor follows RTS/CTS over two CTS windows and a hold to the EndOfMsgAck") {
  Bus bus;
  const Bytes message = payload(20, 0x10);
  bus.send(cmId(GATEWAY, VCU), rts(20, 3, 2, PGN_COMPONENT_ID), 0);
  const std::int64_t startNs = bus.now;
  bus.send(cmId(VCU, GATEWAY), cts(2, 1, PGN_COMPONENT_ID));
  bus.send(dtId(GATEWAY, VCU), packet(message, 1));
  bus.send(dtId(GATEWAY, VCU), packet(message, 2));
  bus.send(cmId(VCU, GATEWAY), cts(0, 0xFF, PGN_COMPONENT_ID));
  CHECK(bus.sut.nextDeadlineNs() == bus.now + TP_T4_NS);  // held: T4
  bus.send(cmId(VCU, GATEWAY), cts(1, 3, PGN_COMPONENT_ID), 900 * MS);  // within T4 (1050 ms)
  CHECK(bus.sut.nextDeadlineNs() == bus.now + TP_T2_NS);  // CTS -> first packet: T2
  bus.send(dtId(GATEWAY, VCU), packet(message, 3));

  REQUIRE(bus.out.messages.size() == 1);
  CHECK(bus.out.messages[0].data == message);
  CHECK(bus.out.messages[0].session.destination == VCU);
  CHECK(bus.out.ends.empty());  // the EndOfMsgAck is still due
  CHECK(bus.sut.nextDeadlineNs() == bus.now + TP_T3_NS);
  bus.send(cmId(VCU, GATEWAY), endOfMsgAck(20, 3, PGN_COMPONENT_ID));

  REQUIRE(bus.out.ends.size() == 1);
  const TpSessionEnd& end = bus.out.ends[0];
  CHECK(end.outcome == TpOutcome::Completed);
  CHECK(end.session.windows == 2);
  CHECK(end.session.holds == 1);
  CHECK(end.session.packetsReceived == 3);
  CHECK(end.session.startNs == startNs);
  CHECK(end.session.endNs == bus.now);
  CHECK(bus.sut.counters().rtsCts == 1);
}

TEST_CASE("monitor keeps interleaved BAM and RTS/CTS sessions of different sources apart") {
  Bus bus;
  const Bytes broadcast = payload(10, 0xA0);
  const Bytes directed = payload(16, 0x01);
  bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(10, 2, PGN_DM1_TEST), 0);
  bus.send(cmId(GATEWAY, VCU), rts(16, 3, 0xFF, PGN_COMPONENT_ID));
  bus.send(cmId(VCU, GATEWAY), cts(3, 1, PGN_COMPONENT_ID));
  bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(broadcast, 1));
  bus.send(dtId(GATEWAY, VCU), packet(directed, 1));
  bus.send(dtId(GATEWAY, VCU), packet(directed, 2));
  bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(broadcast, 2));
  bus.send(dtId(GATEWAY, VCU), packet(directed, 3));
  bus.send(cmId(VCU, GATEWAY), endOfMsgAck(16, 3, PGN_COMPONENT_ID));

  REQUIRE(bus.out.messages.size() == 2);
  CHECK(bus.out.messages[0].session.source == ENGINE);
  CHECK(bus.out.messages[0].data == broadcast);
  CHECK(bus.out.messages[1].session.source == GATEWAY);
  CHECK(bus.out.messages[1].data == directed);
  REQUIRE(bus.out.ends.size() == 2);
  CHECK(bus.out.ends[0].outcome == TpOutcome::Completed);
  CHECK(bus.out.ends[1].outcome == TpOutcome::Completed);
  CHECK(bus.sut.counters().started == 2);
}

TEST_CASE("monitor reports an abort by the responder and one by the originator with their reasons") {
  Bus bus;
  const Bytes message = payload(20, 0);
  bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID), 0);
  bus.send(cmId(VCU, GATEWAY), abortFrame(TpAbortReason::AlreadyInSession, TP_ABORT_ROLE_RESPONDER, PGN_COMPONENT_ID));
  bus.send(cmId(BRAKES, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID));
  bus.send(cmId(VCU, BRAKES), cts(3, 1, PGN_COMPONENT_ID));
  bus.send(dtId(BRAKES, VCU), packet(message, 1));
  bus.send(cmId(BRAKES, VCU), abortFrame(TpAbortReason::ResourcesNeeded, 0, PGN_COMPONENT_ID));

  REQUIRE(bus.out.ends.size() == 2);
  CHECK(bus.out.ends[0].outcome == TpOutcome::Aborted);
  CHECK(bus.out.ends[0].abortedBy == TpSide::Responder);
  CHECK(bus.out.ends[0].abortReason == TpAbortReason::AlreadyInSession);
  CHECK(bus.out.ends[0].session.source == GATEWAY);
  CHECK(bus.out.ends[0].session.packetsReceived == 0);
  CHECK(bus.out.ends[1].outcome == TpOutcome::Aborted);
  CHECK(bus.out.ends[1].abortedBy == TpSide::Originator);
  CHECK(bus.out.ends[1].abortReason == TpAbortReason::ResourcesNeeded);
  CHECK(bus.out.ends[1].session.source == BRAKES);
  CHECK(bus.out.ends[1].session.packetsReceived == 1);
  CHECK(bus.out.messages.empty());
  CHECK(bus.sut.counters().aborted == 2);
}

TEST_CASE("monitor times out each J1939-21 timer at its deadline") {
  const Bytes message = payload(20, 0);
  SUBCASE("T1: BAM packets stop") {
    Bus bus;
    bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 3, PGN_DM1_TEST), 0);
    bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 1));
    const std::int64_t lastNs = bus.now;
    bus.sut.poll(lastNs + TP_T1_NS - 1, bus.out);
    CHECK(bus.out.ends.empty());
    bus.sut.poll(lastNs + TP_T1_NS, bus.out);
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].outcome == TpOutcome::TimedOut);
    CHECK(bus.out.ends[0].timer == TpTimer::T1);
    CHECK(bus.out.ends[0].session.endNs == lastNs + TP_T1_NS);
    CHECK(bus.out.ends[0].session.packetsReceived == 1);
  }
  SUBCASE("T2: no packet after a CTS") {
    Bus bus;
    bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID), 0);
    bus.send(cmId(VCU, GATEWAY), cts(3, 1, PGN_COMPONENT_ID));
    const std::int64_t ctsNs = bus.now;
    bus.send(0x18FEF100, Bytes(8, 0), TP_T2_NS);  // a frame of another PGN applies no deadline
    CHECK(bus.out.ends.empty());
    bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 3, PGN_DM1_TEST), 0);  // any TP frame does
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].timer == TpTimer::T2);
    CHECK(bus.out.ends[0].session.endNs == ctsNs + TP_T2_NS);
  }
  SUBCASE("T1: RTS/CTS packets stop inside a window") {
    Bus bus;
    bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID), 0);
    bus.send(cmId(VCU, GATEWAY), cts(3, 1, PGN_COMPONENT_ID));
    bus.send(dtId(GATEWAY, VCU), packet(message, 1));
    const std::int64_t lastNs = bus.now;
    bus.sut.poll(lastNs + TP_T1_NS, bus.out);
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].timer == TpTimer::T1);
  }
  SUBCASE("T3: no CTS after the RTS") {
    Bus bus;
    bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID), 0);
    const std::int64_t rtsNs = bus.now;
    bus.sut.poll(rtsNs + TP_T3_NS, bus.out);
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].timer == TpTimer::T3);
    CHECK(bus.out.ends[0].session.endNs == rtsNs + TP_T3_NS);
  }
  SUBCASE("T3: no EndOfMsgAck after the last packet (the message was still handed on)") {
    Bus bus;
    bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID), 0);
    bus.send(cmId(VCU, GATEWAY), cts(3, 1, PGN_COMPONENT_ID));
    for (std::uint8_t sequence = 1; sequence <= 3; ++sequence) bus.send(dtId(GATEWAY, VCU), packet(message, sequence));
    bus.sut.poll(bus.now + TP_T3_NS, bus.out);
    CHECK(bus.out.messages.size() == 1);
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].timer == TpTimer::T3);
    CHECK(bus.out.ends[0].session.packetsReceived == 3);
  }
  SUBCASE("T4: a hold not followed by a CTS") {
    Bus bus;
    bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID), 0);
    bus.send(cmId(VCU, GATEWAY), cts(0, 0xFF, PGN_COMPONENT_ID));
    const std::int64_t holdNs = bus.now;
    bus.sut.poll(holdNs + TP_T4_NS - 1, bus.out);
    CHECK(bus.out.ends.empty());
    bus.sut.poll(holdNs + TP_T4_NS, bus.out);
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].timer == TpTimer::T4);
    CHECK(bus.out.ends[0].session.holds == 1);
  }
}

TEST_CASE("monitor ends a session with a protocol error on a bad or duplicate sequence") {
  const Bytes message = payload(30, 0);  // 5 packets
  SUBCASE("a packet skipped") {
    Bus bus;
    bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(30, 5, PGN_DM1_TEST), 0);
    bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 1));
    bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 3));
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].outcome == TpOutcome::ProtocolError);
    CHECK(bus.out.ends[0].error == TpError::BadSequence);
    CHECK(bus.out.ends[0].session.packetsReceived == 1);
  }
  SUBCASE("the previous packet again is tolerated, an older one is not") {
    Bus bus;
    bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(30, 5, PGN_DM1_TEST), 0);
    bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 1));
    bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 2));
    bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 2));
    CHECK(bus.out.ends.empty());
    CHECK(bus.sut.counters().repeatedPackets == 1);
    bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 1));
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].error == TpError::DuplicateSequence);
  }
  SUBCASE("a packet past the CTS window") {
    Bus bus;
    bus.send(cmId(GATEWAY, VCU), rts(30, 5, 2, PGN_COMPONENT_ID), 0);
    bus.send(cmId(VCU, GATEWAY), cts(2, 1, PGN_COMPONENT_ID));
    bus.send(dtId(GATEWAY, VCU), packet(message, 1));
    bus.send(dtId(GATEWAY, VCU), packet(message, 2));
    bus.send(dtId(GATEWAY, VCU), packet(message, 3));  // no CTS for it yet
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].outcome == TpOutcome::ProtocolError);
    CHECK(bus.out.ends[0].error == TpError::OutsideWindow);
  }
  SUBCASE("an EndOfMsgAck with another size") {
    Bus bus;
    const Bytes small = payload(9, 0);
    bus.send(cmId(GATEWAY, VCU), rts(9, 2, 0xFF, PGN_COMPONENT_ID), 0);
    bus.send(cmId(VCU, GATEWAY), cts(2, 1, PGN_COMPONENT_ID));
    bus.send(dtId(GATEWAY, VCU), packet(small, 1));
    bus.send(dtId(GATEWAY, VCU), packet(small, 2));
    bus.send(cmId(VCU, GATEWAY), endOfMsgAck(10, 2, PGN_COMPONENT_ID));
    REQUIRE(bus.out.ends.size() == 1);
    CHECK(bus.out.ends[0].error == TpError::SizeMismatch);
  }
}

TEST_CASE("monitor reports a new announcement before the end as replacing the old session") {
  Bus bus;
  const Bytes message = payload(20, 0);
  bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 3, PGN_DM1_TEST), 0);
  bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 1));
  bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 3, PGN_DM1_TEST));
  REQUIRE(bus.out.ends.size() == 1);
  CHECK(bus.out.ends[0].outcome == TpOutcome::Replaced);
  CHECK(bus.sut.openSessions() == 1);
}

TEST_CASE("monitor reports a truncated session as incomplete at finish") {
  Bus bus;
  const Bytes message = payload(20, 0);
  bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 3, PGN_DM1_TEST), 0);
  bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 1));
  bus.send(dtId(ENGINE, GLOBAL_ADDRESS), packet(message, 2));
  const std::int64_t endNs = bus.now + 10 * MS;
  bus.sut.finish(endNs, bus.out);
  REQUIRE(bus.out.ends.size() == 1);
  CHECK(bus.out.ends[0].outcome == TpOutcome::Incomplete);
  CHECK(bus.out.ends[0].session.packetsReceived == 2);
  CHECK(bus.out.ends[0].session.packets == 3);
  CHECK(bus.out.ends[0].session.endNs == endNs);
  CHECK(bus.sut.counters().incomplete == 1);
}

TEST_CASE("monitor refuses invalid announcements and those beyond a full pool, and says so") {
  Bus bus(TpMonitorConfig{1});
  bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 4, PGN_DM1_TEST), 0);  // 20 bytes need 3 packets
  bus.send(cmId(ENGINE, GLOBAL_ADDRESS), bam(20, 3, PGN_DM1_TEST));
  bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID));
  REQUIRE(bus.out.ends.size() == 2);
  CHECK(bus.out.ends[0].outcome == TpOutcome::Refused);
  CHECK(bus.out.ends[0].error == TpError::BadAnnouncement);
  CHECK(bus.out.ends[1].outcome == TpOutcome::Refused);
  CHECK(bus.out.ends[1].error == TpError::PoolFull);
  CHECK(bus.out.ends[1].session.source == GATEWAY);
  CHECK(bus.sut.counters().refused == 2);
  CHECK(bus.sut.counters().started == 1);
}

TEST_CASE("monitor follows a retransmission request and hands the message on once") {
  Bus bus;
  const Bytes message = payload(20, 0x30);
  Bytes corrupted = packet(message, 2);
  corrupted[3] ^= 0xFF;
  bus.send(cmId(GATEWAY, VCU), rts(20, 3, 0xFF, PGN_COMPONENT_ID), 0);
  bus.send(cmId(VCU, GATEWAY), cts(3, 1, PGN_COMPONENT_ID));
  bus.send(dtId(GATEWAY, VCU), packet(message, 1));
  bus.send(dtId(GATEWAY, VCU), corrupted);
  bus.send(dtId(GATEWAY, VCU), packet(message, 3));
  bus.send(cmId(VCU, GATEWAY), cts(1, 2, PGN_COMPONENT_ID));  // packet 2 again
  bus.send(dtId(GATEWAY, VCU), packet(message, 2));
  bus.send(cmId(VCU, GATEWAY), endOfMsgAck(20, 3, PGN_COMPONENT_ID));

  REQUIRE(bus.out.messages.size() == 1);  // at the first time all packets were in
  REQUIRE(bus.out.ends.size() == 1);
  CHECK(bus.out.ends[0].outcome == TpOutcome::Completed);
  CHECK(bus.out.ends[0].session.windows == 2);
}
