#include "openvcu/j1939/transport.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <vector>

using namespace openvcu::j1939;

// Failure messages name the kind and reason instead of "{?}".
template <>
struct doctest::StringMaker<TpEventKind> {
  static doctest::String convert(TpEventKind kind) {
    const std::string_view name = tpEventKindName(kind);
    return {name.data(), static_cast<doctest::String::size_type>(name.size())};
  }
};
template <>
struct doctest::StringMaker<TpAbortReason> {
  static doctest::String convert(TpAbortReason reason) {
    const std::string_view name = tpAbortReasonName(reason);
    return {name.data(), static_cast<doctest::String::size_type>(name.size())};
  }
};
template <>
struct doctest::StringMaker<TpFrame> {
  static doctest::String convert(const TpFrame& frame) {
    char text[64];
    std::snprintf(text, sizeof text, "%08X [%u] %02X %02X %02X %02X %02X %02X %02X %02X",
                  static_cast<unsigned>(frame.canId), static_cast<unsigned>(frame.length),
                  frame.data[0], frame.data[1], frame.data[2], frame.data[3], frame.data[4],
                  frame.data[5], frame.data[6], frame.data[7]);
    return text;
  }
};

namespace {

using Bytes = std::vector<std::uint8_t>;
using FrameData = std::array<std::uint8_t, TP_FRAME_LENGTH>;

constexpr std::uint8_t VCU_ADDRESS = 0x21;        // us
constexpr std::uint8_t ORIGINATOR_ADDRESS = 0x20;  // sends RTS to us
constexpr std::uint8_t BAM_SOURCE_ADDRESS = 0x10;
constexpr std::uint8_t OTHER_NODE_ADDRESS = 0x30;
constexpr std::uint8_t THIRD_NODE_ADDRESS = 0x40;
constexpr std::uint32_t PGN_COMPONENT_ID = 0xFEEB;  // 65259, a typical RTS/CTS payload
constexpr std::uint32_t PGN_VEHICLE_ID = 0xFEEC;    // 65260
constexpr std::uint32_t PGN_DM1_BROADCAST = 0xFECA; // 65226

// 29-bit identifiers of the examples (priority 7).
constexpr std::uint32_t BAM_CM_ID = 0x1CECFF10;      // TP.CM from 0x10 to global
constexpr std::uint32_t BAM_DT_ID = 0x1CEBFF10;      // TP.DT from 0x10 to global
constexpr std::uint32_t RTS_CM_ID = 0x1CEC2120;      // TP.CM from 0x20 to us
constexpr std::uint32_t RTS_DT_ID = 0x1CEB2120;      // TP.DT from 0x20 to us
constexpr std::uint32_t REPLY_TO_ORIGINATOR = 0x1CEC2021;  // our TP.CM to 0x20
constexpr std::uint32_t OTHER_CM_ID = 0x1CEC2130;    // TP.CM from 0x30 to us
constexpr std::uint32_t OTHER_DT_ID = 0x1CEB2130;    // TP.DT from 0x30 to us
constexpr std::uint32_t REPLY_TO_OTHER = 0x1CEC3021; // our TP.CM to 0x30

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START_NS = 1'000 * MS;
constexpr std::int64_t PACKET_GAP_NS = 50 * MS;  // a typical BAM packet spacing

constexpr TpReceiverConfig VCU_CONFIG{VCU_ADDRESS, TP_NO_PACKET_LIMIT, 8, 4};

struct ReceivedMessage {
  std::uint32_t pgn{};
  std::uint8_t source{};
  std::uint8_t destination{};
  Bytes data;
  std::int64_t completedNs{};
  bool broadcast{};
};

struct RecordingSink final : TpSink {
  std::vector<TpFrame> frames;
  std::vector<ReceivedMessage> messages;
  std::vector<TpEvent> events;

  void send(const TpFrame& frame) noexcept override { frames.push_back(frame); }
  void completed(const TpMessage& message) noexcept override {
    messages.push_back({message.pgn, message.source, message.destination,
                        Bytes(message.data.begin(), message.data.end()), message.completedNs,
                        message.broadcast});
  }
  void event(const TpEvent& event) noexcept override { events.push_back(event); }

  [[nodiscard]] std::size_t count(TpEventKind kind) const {
    return static_cast<std::size_t>(std::count_if(
        events.begin(), events.end(), [kind](const TpEvent& event) { return event.kind == kind; }));
  }
};

// 1, 2, 3, ... `size` bytes: every byte tells its position.
Bytes countingPayload(std::size_t size) {
  Bytes payload(size);
  for (std::size_t i = 0; i < size; ++i) payload[i] = static_cast<std::uint8_t>(i + 1);
  return payload;
}

constexpr std::uint8_t lowByte(std::size_t value) { return static_cast<std::uint8_t>(value & 0xFF); }
constexpr std::uint8_t highByte(std::size_t value) {
  return static_cast<std::uint8_t>((value >> 8) & 0xFF);
}
constexpr std::uint8_t pgnByte(std::uint32_t pgn, unsigned index) {
  return static_cast<std::uint8_t>((pgn >> (8 * index)) & 0xFF);
}

std::uint8_t packetsOf(std::size_t size) {
  return static_cast<std::uint8_t>((size + TP_BYTES_PER_PACKET - 1) / TP_BYTES_PER_PACKET);
}

FrameData rts(std::size_t size, std::uint32_t pgn, std::uint8_t limit = TP_NO_PACKET_LIMIT) {
  return {TP_CM_RTS, lowByte(size),    highByte(size),   packetsOf(size),
          limit,     pgnByte(pgn, 0), pgnByte(pgn, 1), pgnByte(pgn, 2)};
}

FrameData bam(std::size_t size, std::uint32_t pgn) {
  return {TP_CM_BAM, lowByte(size),    highByte(size),   packetsOf(size),
          0xFF,      pgnByte(pgn, 0), pgnByte(pgn, 1), pgnByte(pgn, 2)};
}

FrameData abortFrom(TpAbortReason reason, std::uint32_t pgn) {
  return {TP_CM_ABORT, static_cast<std::uint8_t>(reason), 0xFC, 0xFF, 0xFF,
          pgnByte(pgn, 0), pgnByte(pgn, 1), pgnByte(pgn, 2)};
}

// Packet `sequence` (1-based) of `payload`, the last one padded with 0xFF.
FrameData packet(const Bytes& payload, std::size_t sequence) {
  FrameData data;
  data.fill(0xFF);
  data[0] = static_cast<std::uint8_t>(sequence);
  const std::size_t offset = (sequence - 1) * TP_BYTES_PER_PACKET;
  for (std::size_t i = 0; i < TP_BYTES_PER_PACKET && offset + i < payload.size(); ++i) {
    data[1 + i] = payload[offset + i];
  }
  return data;
}

TpFrame expectedFrame(std::uint32_t canId, const FrameData& data) {
  return TpFrame{canId, static_cast<std::uint8_t>(TP_FRAME_LENGTH), data};
}

TpFrame expectedCts(std::uint32_t canId, std::uint8_t count, std::uint8_t next,
                    std::uint32_t pgn) {
  return expectedFrame(canId, {TP_CM_CTS, count, next, 0xFF, 0xFF, pgnByte(pgn, 0),
                               pgnByte(pgn, 1), pgnByte(pgn, 2)});
}

TpFrame expectedAbort(std::uint32_t canId, TpAbortReason reason, std::uint32_t pgn) {
  // byte 2: reserved bits 1, role 01 = responder
  return expectedFrame(canId, {TP_CM_ABORT, static_cast<std::uint8_t>(reason), 0xFD, 0xFF, 0xFF,
                               pgnByte(pgn, 0), pgnByte(pgn, 1), pgnByte(pgn, 2)});
}

TpFrame expectedEndOfMsgAck(std::uint32_t canId, std::size_t size, std::uint32_t pgn) {
  return expectedFrame(canId, {TP_CM_END_OF_MSG_ACK, lowByte(size), highByte(size),
                               packetsOf(size), 0xFF, pgnByte(pgn, 0), pgnByte(pgn, 1),
                               pgnByte(pgn, 2)});
}

// Sends packets first..last of `payload`, PACKET_GAP_NS apart, starting at `nowNs`;
// returns the time of the last one.
std::int64_t sendPackets(TpReceiver& receiver, RecordingSink& sink, std::uint32_t dataId,
                         const Bytes& payload, std::size_t first, std::size_t last,
                         std::int64_t nowNs) {
  for (std::size_t sequence = first; sequence <= last; ++sequence) {
    if (sequence != first) nowNs += PACKET_GAP_NS;
    receiver.onFrame(dataId, packet(payload, sequence), nowNs, sink);
  }
  return nowNs;
}

void checkCountersBalance(const TpReceiver& receiver) {
  const TpCounters& counters = receiver.counters();
  CHECK(counters.sessionsStarted ==
        counters.sessionsCompleted + counters.sessionsAbortedByPeer +
            counters.sessionsAbortedByUs + counters.sessionsTimedOut +
            counters.sessionsReplaced + counters.sessionsDropped + receiver.activeSessions());
}

/// A receiver with the VCU's configuration and the sink that records what it does.
struct VcuReceiver {
  TpReceiver sut{VCU_CONFIG};
  RecordingSink sink;
};

}  // namespace

TEST_CASE_FIXTURE(VcuReceiver, "BAM of three packets is reassembled into the announced 20 bytes") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(BAM_CM_ID, FrameData{0x20, 0x14, 0x00, 0x03, 0xFF, 0xCA, 0xFE, 0x00}, START_NS, sink);
  sut.onFrame(BAM_DT_ID, FrameData{0x01, 1, 2, 3, 4, 5, 6, 7}, START_NS + 50 * MS, sink);
  sut.onFrame(BAM_DT_ID, FrameData{0x02, 8, 9, 10, 11, 12, 13, 14}, START_NS + 100 * MS, sink);
  sut.onFrame(BAM_DT_ID, FrameData{0x03, 15, 16, 17, 18, 19, 20, 0xFF}, START_NS + 150 * MS, sink);

  CHECK(sink.frames.empty());  // BAM is never answered
  REQUIRE(sink.messages.size() == 1);
  const ReceivedMessage& message = sink.messages.front();
  CHECK(message.pgn == PGN_DM1_BROADCAST);
  CHECK(message.source == BAM_SOURCE_ADDRESS);
  CHECK(message.destination == GLOBAL_ADDRESS);
  CHECK(message.broadcast);
  CHECK(message.data == payload);
  CHECK(message.completedNs == START_NS + 150 * MS);
  REQUIRE(sink.events.size() == 1);
  CHECK(sink.events.front() == TpEvent{TpEventKind::Completed, BAM_SOURCE_ADDRESS,
                                       GLOBAL_ADDRESS, PGN_DM1_BROADCAST, TpAbortReason::None});
  CHECK(sut.activeSessions() == 0);
  CHECK(sut.counters().sessionsStarted == 1);
  CHECK(sut.counters().sessionsCompleted == 1);
}

TEST_CASE_FIXTURE(VcuReceiver, "RTS to us is answered with a CTS for all packets and the transfer with an EndOfMsgAck") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(RTS_CM_ID, FrameData{0x10, 0x14, 0x00, 0x03, 0xFF, 0xEB, 0xFE, 0x00}, START_NS, sink);

  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == TpFrame{REPLY_TO_ORIGINATOR, 8,
                                  {0x11, 0x03, 0x01, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}});

  const std::int64_t lastNs = sendPackets(sut, sink, RTS_DT_ID, payload, 1, 3, START_NS + 10 * MS);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == TpFrame{REPLY_TO_ORIGINATOR, 8,
                                  {0x13, 0x14, 0x00, 0x03, 0xFF, 0xEB, 0xFE, 0x00}});
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].pgn == PGN_COMPONENT_ID);
  CHECK(sink.messages[0].source == ORIGINATOR_ADDRESS);
  CHECK(sink.messages[0].destination == VCU_ADDRESS);
  CHECK_FALSE(sink.messages[0].broadcast);
  CHECK(sink.messages[0].data == payload);
  CHECK(sink.messages[0].completedNs == lastNs);
  CHECK(sink.count(TpEventKind::Completed) == 1);
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
}

TEST_CASE("a receive window smaller than the message takes one CTS per window") {
  constexpr std::uint8_t WINDOW = 2;
  TpReceiver sut({VCU_ADDRESS, WINDOW, 8, 4});
  RecordingSink sink;
  const Bytes payload = countingPayload(33);  // 5 packets

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == expectedCts(REPLY_TO_ORIGINATOR, 2, 1, PGN_COMPONENT_ID));

  std::int64_t nowNs = sendPackets(sut, sink, RTS_DT_ID, payload, 1, 2, START_NS + 10 * MS);
  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == expectedCts(REPLY_TO_ORIGINATOR, 2, 3, PGN_COMPONENT_ID));

  nowNs = sendPackets(sut, sink, RTS_DT_ID, payload, 3, 4, nowNs + 10 * MS);
  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[2] == expectedCts(REPLY_TO_ORIGINATOR, 1, 5, PGN_COMPONENT_ID));

  sendPackets(sut, sink, RTS_DT_ID, payload, 5, 5, nowNs + 10 * MS);
  REQUIRE(sink.frames.size() == 4);
  CHECK(sink.frames[3] == expectedEndOfMsgAck(REPLY_TO_ORIGINATOR, 33, PGN_COMPONENT_ID));
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == payload);
}

TEST_CASE("the originator's packet limit in the RTS caps each CTS") {
  constexpr std::uint8_t ORIGINATOR_LIMIT = 3;
  TpReceiver sut(VCU_CONFIG);  // no limit of our own
  RecordingSink sink;
  const Bytes payload = countingPayload(35);  // 5 packets

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID, ORIGINATOR_LIMIT), START_NS, sink);
  const std::int64_t nowNs = sendPackets(sut, sink, RTS_DT_ID, payload, 1, 3, START_NS + MS);
  sendPackets(sut, sink, RTS_DT_ID, payload, 4, 5, nowNs + MS);

  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[0] == expectedCts(REPLY_TO_ORIGINATOR, 3, 1, PGN_COMPONENT_ID));
  CHECK(sink.frames[1] == expectedCts(REPLY_TO_ORIGINATOR, 2, 4, PGN_COMPONENT_ID));
  CHECK(sink.frames[2] == expectedEndOfMsgAck(REPLY_TO_ORIGINATOR, 35, PGN_COMPONENT_ID));
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == payload);
}

TEST_CASE_FIXTURE(VcuReceiver, "an RTS whose packet limit byte is 0 is served as if it had no limit") {
  sut.onFrame(RTS_CM_ID, rts(20, PGN_COMPONENT_ID, 0), START_NS, sink);

  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == expectedCts(REPLY_TO_ORIGINATOR, 3, 1, PGN_COMPONENT_ID));
}

TEST_CASE_FIXTURE(VcuReceiver, "a BAM from 0x10 and an RTS/CTS transfer from 0x20 interleaved both complete") {
  const Bytes broadcastPayload = countingPayload(26);  // 4 packets
  Bytes directedPayload = countingPayload(30);         // 5 packets
  std::reverse(directedPayload.begin(), directedPayload.end());

  std::int64_t nowNs = START_NS;
  sut.onFrame(BAM_CM_ID, bam(broadcastPayload.size(), PGN_DM1_BROADCAST), nowNs, sink);
  sut.onFrame(RTS_CM_ID, rts(directedPayload.size(), PGN_COMPONENT_ID), nowNs += MS, sink);
  for (std::size_t sequence = 1; sequence <= 5; ++sequence) {
    if (sequence <= 4) {
      sut.onFrame(BAM_DT_ID, packet(broadcastPayload, sequence), nowNs += 20 * MS, sink);
    }
    sut.onFrame(RTS_DT_ID, packet(directedPayload, sequence), nowNs += 20 * MS, sink);
  }

  REQUIRE(sink.messages.size() == 2);
  CHECK(sink.messages[0].source == BAM_SOURCE_ADDRESS);
  CHECK(sink.messages[0].data == broadcastPayload);
  CHECK(sink.messages[1].source == ORIGINATOR_ADDRESS);
  CHECK(sink.messages[1].data == directedPayload);
  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[0] == expectedCts(REPLY_TO_ORIGINATOR, 5, 1, PGN_COMPONENT_ID));
  CHECK(sink.frames[1] == expectedEndOfMsgAck(REPLY_TO_ORIGINATOR, 30, PGN_COMPONENT_ID));
  CHECK(sink.count(TpEventKind::Completed) == 2);
  CHECK(sink.count(TpEventKind::Ignored) == 0);
}

TEST_CASE_FIXTURE(VcuReceiver, "a BAM and an RTS/CTS transfer from the same source run side by side") {
  const Bytes broadcastPayload = countingPayload(14);
  const Bytes directedPayload = countingPayload(9);
  constexpr std::uint32_t SAME_SOURCE_BAM_CM = 0x1CECFF20;
  constexpr std::uint32_t SAME_SOURCE_BAM_DT = 0x1CEBFF20;

  sut.onFrame(SAME_SOURCE_BAM_CM, bam(broadcastPayload.size(), PGN_DM1_BROADCAST), START_NS, sink);
  sut.onFrame(RTS_CM_ID, rts(directedPayload.size(), PGN_COMPONENT_ID), START_NS + MS, sink);
  sut.onFrame(SAME_SOURCE_BAM_DT, packet(broadcastPayload, 1), START_NS + 2 * MS, sink);
  sut.onFrame(RTS_DT_ID, packet(directedPayload, 1), START_NS + 3 * MS, sink);
  sut.onFrame(SAME_SOURCE_BAM_DT, packet(broadcastPayload, 2), START_NS + 4 * MS, sink);
  sut.onFrame(RTS_DT_ID, packet(directedPayload, 2), START_NS + 5 * MS, sink);

  REQUIRE(sink.messages.size() == 2);
  CHECK(sink.messages[0].broadcast);
  CHECK(sink.messages[0].data == broadcastPayload);
  CHECK_FALSE(sink.messages[1].broadcast);
  CHECK(sink.messages[1].data == directedPayload);
}

TEST_CASE_FIXTURE(VcuReceiver, "an Abort from the originator ends the session without an EndOfMsgAck") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 1), START_NS + MS, sink);
  sut.onFrame(RTS_CM_ID, abortFrom(TpAbortReason::ResourcesNeeded, PGN_COMPONENT_ID),
              START_NS + 2 * MS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 2), START_NS + 3 * MS, sink);

  CHECK(sink.frames.size() == 1);  // the CTS only
  CHECK(sink.messages.empty());
  REQUIRE(sink.events.size() == 2);
  CHECK(sink.events[0] == TpEvent{TpEventKind::Aborted, ORIGINATOR_ADDRESS, VCU_ADDRESS,
                                  PGN_COMPONENT_ID, TpAbortReason::ResourcesNeeded});
  CHECK(sink.events[1].kind == TpEventKind::Ignored);
  CHECK(sink.events[1].reason == TpAbortReason::UnexpectedDataPacket);
  CHECK(sut.counters().sessionsAbortedByPeer == 1);
  CHECK(sut.activeSessions() == 0);
}

TEST_CASE_FIXTURE(VcuReceiver, "an Abort naming another PGN leaves the session running") {
  const Bytes payload = countingPayload(9);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_CM_ID, abortFrom(TpAbortReason::Timeout, PGN_VEHICLE_ID), START_NS + MS, sink);
  sendPackets(sut, sink, RTS_DT_ID, payload, 1, 2, START_NS + 2 * MS);

  CHECK(sink.count(TpEventKind::Ignored) == 1);
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == payload);
}

TEST_CASE_FIXTURE(VcuReceiver, "a packet out of sequence makes us abort with reason bad sequence number") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 2), START_NS + MS, sink);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == TpFrame{REPLY_TO_ORIGINATOR, 8,
                                  {0xFF, 0x07, 0xFD, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}});
  REQUIRE(sink.events.size() == 1);
  CHECK(sink.events[0] == TpEvent{TpEventKind::AbortSent, ORIGINATOR_ADDRESS, VCU_ADDRESS,
                                  PGN_COMPONENT_ID, TpAbortReason::BadSequenceNumber});
  CHECK(sut.counters().sessionsAbortedByUs == 1);
  CHECK(sut.activeSessions() == 0);
}

TEST_CASE_FIXTURE(VcuReceiver, "sequence number 0 is a bad sequence number") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 1), START_NS + MS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 0), START_NS + 2 * MS, sink);

  REQUIRE_FALSE(sink.frames.empty());
  CHECK(sink.frames.back() ==
        expectedAbort(REPLY_TO_ORIGINATOR, TpAbortReason::BadSequenceNumber, PGN_COMPONENT_ID));
}

TEST_CASE_FIXTURE(VcuReceiver, "the previous packet received again is ignored and the transfer completes") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 1), START_NS + 1 * MS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 1), START_NS + 2 * MS, sink);
  sendPackets(sut, sink, RTS_DT_ID, payload, 2, 3, START_NS + 3 * MS);

  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == payload);
  CHECK(sink.count(TpEventKind::Ignored) == 1);
  CHECK(sink.events[0].reason == TpAbortReason::DuplicateSequenceNumber);
  CHECK(sink.frames.back() == expectedEndOfMsgAck(REPLY_TO_ORIGINATOR, 20, PGN_COMPONENT_ID));
}

TEST_CASE_FIXTURE(VcuReceiver, "an older packet received again makes us abort with reason duplicate sequence number") {
  const Bytes payload = countingPayload(30);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sendPackets(sut, sink, RTS_DT_ID, payload, 1, 3, START_NS + MS);
  sut.onFrame(RTS_DT_ID, packet(payload, 1), START_NS + 500 * MS, sink);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == expectedAbort(REPLY_TO_ORIGINATOR,
                                        TpAbortReason::DuplicateSequenceNumber, PGN_COMPONENT_ID));
  CHECK(sink.count(TpEventKind::AbortSent) == 1);
}

TEST_CASE_FIXTURE(VcuReceiver, "a BAM packet out of sequence drops the BAM without sending anything") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(BAM_CM_ID, bam(payload.size(), PGN_DM1_BROADCAST), START_NS, sink);
  sut.onFrame(BAM_DT_ID, packet(payload, 1), START_NS + PACKET_GAP_NS, sink);
  sut.onFrame(BAM_DT_ID, packet(payload, 3), START_NS + 2 * PACKET_GAP_NS, sink);

  CHECK(sink.frames.empty());
  REQUIRE(sink.events.size() == 1);
  CHECK(sink.events[0] == TpEvent{TpEventKind::Dropped, BAM_SOURCE_ADDRESS, GLOBAL_ADDRESS,
                                  PGN_DM1_BROADCAST, TpAbortReason::BadSequenceNumber});
  CHECK(sut.counters().sessionsDropped == 1);
}

TEST_CASE_FIXTURE(VcuReceiver, "a BAM without a packet for T1 times out silently") {
  const Bytes payload = countingPayload(20);
  const std::int64_t packetNs = START_NS + PACKET_GAP_NS;

  sut.onFrame(BAM_CM_ID, bam(payload.size(), PGN_DM1_BROADCAST), START_NS, sink);
  sut.onFrame(BAM_DT_ID, packet(payload, 1), packetNs, sink);
  CHECK(sut.nextDeadlineNs() == packetNs + TP_T1_NS);

  sut.poll(packetNs + TP_T1_NS - 1, sink);
  CHECK(sink.events.empty());

  sut.poll(packetNs + TP_T1_NS, sink);
  CHECK(sink.frames.empty());
  REQUIRE(sink.events.size() == 1);
  CHECK(sink.events[0] == TpEvent{TpEventKind::Timeout, BAM_SOURCE_ADDRESS, GLOBAL_ADDRESS,
                                  PGN_DM1_BROADCAST, TpAbortReason::Timeout});
  CHECK(sut.counters().sessionsTimedOut == 1);
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
}

TEST_CASE_FIXTURE(VcuReceiver, "a BAM whose first packet does not come within T1 times out") {
  sut.onFrame(BAM_CM_ID, bam(20, PGN_DM1_BROADCAST), START_NS, sink);
  CHECK(sut.nextDeadlineNs() == START_NS + TP_T1_NS);
  sut.poll(START_NS + TP_T1_NS, sink);

  CHECK(sink.count(TpEventKind::Timeout) == 1);
}

TEST_CASE_FIXTURE(VcuReceiver, "an RTS/CTS transfer without a packet for T1 is aborted with reason timeout") {
  const Bytes payload = countingPayload(20);
  const std::int64_t packetNs = START_NS + 10 * MS;

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 1), packetNs, sink);
  CHECK(sut.nextDeadlineNs() == packetNs + TP_T1_NS);
  sut.poll(packetNs + TP_T1_NS - 1, sink);
  CHECK(sink.frames.size() == 1);

  sut.poll(packetNs + TP_T1_NS, sink);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == TpFrame{REPLY_TO_ORIGINATOR, 8,
                                  {0xFF, 0x03, 0xFD, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}});
  REQUIRE(sink.events.size() == 1);
  CHECK(sink.events[0] == TpEvent{TpEventKind::Timeout, ORIGINATOR_ADDRESS, VCU_ADDRESS,
                                  PGN_COMPONENT_ID, TpAbortReason::Timeout});
}

TEST_CASE_FIXTURE(VcuReceiver, "no packet within T2 after our CTS aborts with reason timeout") {
  sut.onFrame(RTS_CM_ID, rts(20, PGN_COMPONENT_ID), START_NS, sink);
  CHECK(sut.nextDeadlineNs() == START_NS + TP_T2_NS);
  sut.poll(START_NS + TP_T1_NS, sink);  // T1 does not apply before the first packet
  CHECK(sink.frames.size() == 1);

  sut.poll(START_NS + TP_T2_NS, sink);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] ==
        expectedAbort(REPLY_TO_ORIGINATOR, TpAbortReason::Timeout, PGN_COMPONENT_ID));
}

TEST_CASE("T2 runs again after each CTS of a later window") {
  TpReceiver sut({VCU_ADDRESS, 2, 8, 4});
  RecordingSink sink;
  const Bytes payload = countingPayload(30);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  const std::int64_t windowEndNs = sendPackets(sut, sink, RTS_DT_ID, payload, 1, 2, START_NS + MS);

  CHECK(sut.nextDeadlineNs() == windowEndNs + TP_T2_NS);
}

TEST_CASE_FIXTURE(VcuReceiver, "a packet that comes after its deadline is judged after the timeout") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(BAM_CM_ID, bam(payload.size(), PGN_DM1_BROADCAST), START_NS, sink);
  sut.onFrame(BAM_DT_ID, packet(payload, 1), START_NS + TP_T1_NS, sink);  // no poll() before

  REQUIRE(sink.events.size() == 2);
  CHECK(sink.events[0].kind == TpEventKind::Timeout);
  CHECK(sink.events[1].kind == TpEventKind::Ignored);
  CHECK(sink.events[1].reason == TpAbortReason::UnexpectedDataPacket);
}

TEST_CASE("an RTS while every buffer is busy is held with CTS(0) repeated every Th, then served") {
  TpReceiver sut({VCU_ADDRESS, TP_NO_PACKET_LIMIT, 1, 1});
  RecordingSink sink;
  const Bytes firstPayload = countingPayload(20);
  const Bytes heldPayload = countingPayload(9);
  const TpFrame hold = expectedCts(REPLY_TO_OTHER, 0, 1, PGN_VEHICLE_ID);

  sut.onFrame(RTS_CM_ID, rts(firstPayload.size(), PGN_COMPONENT_ID), START_NS, sink);
  const std::int64_t heldNs = START_NS + 10 * MS;
  sut.onFrame(OTHER_CM_ID, rts(heldPayload.size(), PGN_VEHICLE_ID), heldNs, sink);
  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == hold);
  CHECK(sut.nextDeadlineNs() == heldNs + TP_TH_NS);

  sut.poll(heldNs + TP_TH_NS - 1, sink);
  CHECK(sink.frames.size() == 2);
  sut.poll(heldNs + TP_TH_NS, sink);
  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[2] == hold);

  SUBCASE("a third RTS finds no place and is refused with reason already in session") {
    constexpr std::uint32_t THIRD_CM_ID = 0x1CEC2140;
    constexpr std::uint32_t REPLY_TO_THIRD = 0x1CEC4021;
    sut.onFrame(THIRD_CM_ID, rts(9, PGN_VEHICLE_ID), heldNs + TP_TH_NS + MS, sink);

    REQUIRE(sink.frames.size() == 4);
    CHECK(sink.frames[3] ==
          expectedAbort(REPLY_TO_THIRD, TpAbortReason::AlreadyInSession, PGN_VEHICLE_ID));
    CHECK(sink.events.back() == TpEvent{TpEventKind::Refused, THIRD_NODE_ADDRESS, VCU_ADDRESS,
                                        PGN_VEHICLE_ID, TpAbortReason::AlreadyInSession});
  }

  SUBCASE("the held session gets the buffer when the first transfer completes") {
    const std::int64_t lastNs =
        sendPackets(sut, sink, RTS_DT_ID, firstPayload, 1, 3, heldNs + TP_TH_NS + MS);
    REQUIRE(sink.frames.size() == 5);
    CHECK(sink.frames[3] ==
          expectedEndOfMsgAck(REPLY_TO_ORIGINATOR, firstPayload.size(), PGN_COMPONENT_ID));
    CHECK(sink.frames[4] == expectedCts(REPLY_TO_OTHER, 2, 1, PGN_VEHICLE_ID));
    CHECK(sut.nextDeadlineNs() == lastNs + TP_T2_NS);

    sendPackets(sut, sink, OTHER_DT_ID, heldPayload, 1, 2, lastNs + MS);
    REQUIRE(sink.messages.size() == 2);
    CHECK(sink.messages[1].source == OTHER_NODE_ADDRESS);
    CHECK(sink.messages[1].data == heldPayload);
    CHECK(sut.counters().holdsSent == 2);
  }

  SUBCASE("the held session gets the buffer when the first transfer times out") {
    const std::int64_t timeoutNs = START_NS + TP_T2_NS;
    sut.poll(timeoutNs, sink);
    REQUIRE(sink.frames.size() == 5);
    CHECK(sink.frames[3] ==
          expectedAbort(REPLY_TO_ORIGINATOR, TpAbortReason::Timeout, PGN_COMPONENT_ID));
    CHECK(sink.frames[4] == expectedCts(REPLY_TO_OTHER, 2, 1, PGN_VEHICLE_ID));
  }

  SUBCASE("a packet while held is unexpected and aborts the held session") {
    sut.onFrame(OTHER_DT_ID, packet(heldPayload, 1), heldNs + TP_TH_NS + MS, sink);
    REQUIRE(sink.frames.size() == 4);
    CHECK(sink.frames[3] ==
          expectedAbort(REPLY_TO_OTHER, TpAbortReason::UnexpectedDataPacket, PGN_VEHICLE_ID));
  }

  SUBCASE("the originator may abort a held session") {
    sut.onFrame(OTHER_CM_ID, abortFrom(TpAbortReason::Timeout, PGN_VEHICLE_ID),
                heldNs + TP_TH_NS + MS, sink);
    CHECK(sink.count(TpEventKind::Aborted) == 1);
    CHECK(sut.activeSessions() == 1);
  }
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuReceiver, "an RTS addressed to another node is not answered") {
  constexpr std::uint32_t RTS_TO_OTHER = 0x1CEC3020;  // from 0x20 to 0x30
  constexpr std::uint32_t DT_TO_OTHER = 0x1CEB3020;
  const Bytes payload = countingPayload(9);

  sut.onFrame(RTS_TO_OTHER, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(DT_TO_OTHER, packet(payload, 1), START_NS + MS, sink);
  sut.onFrame(DT_TO_OTHER, packet(payload, 2), START_NS + 2 * MS, sink);

  CHECK(sink.frames.empty());
  CHECK(sink.events.empty());
  CHECK(sink.messages.empty());
  CHECK(sut.counters().framesNotForUs == 3);
  CHECK(sut.activeSessions() == 0);
}

TEST_CASE_FIXTURE(VcuReceiver, "our own CTS looped back by the bus is not taken for a frame to us") {
  sut.onFrame(RTS_CM_ID, rts(20, PGN_COMPONENT_ID), START_NS, sink);
  const TpFrame cts = sink.frames.at(0);
  sut.onFrame(cts.canId, cts.data, START_NS + MS, sink);

  CHECK(sink.frames.size() == 1);
  CHECK(sink.events.empty());
  CHECK(sut.counters().framesNotForUs == 1);
}

TEST_CASE_FIXTURE(VcuReceiver, "an RTS to the global address or a BAM to one address is ignored") {
  constexpr std::uint32_t RTS_TO_GLOBAL = 0x1CECFF20;

  sut.onFrame(RTS_TO_GLOBAL, rts(20, PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_CM_ID, bam(20, PGN_COMPONENT_ID), START_NS, sink);

  CHECK(sink.frames.empty());
  CHECK(sink.count(TpEventKind::Ignored) == 2);
  CHECK(sut.activeSessions() == 0);
}

TEST_CASE_FIXTURE(VcuReceiver, "a new RTS for another PGN while a session runs is refused with reason already in session") {
  const Bytes payload = countingPayload(20);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_DT_ID, packet(payload, 1), START_NS + MS, sink);
  sut.onFrame(RTS_CM_ID, rts(40, PGN_VEHICLE_ID), START_NS + 2 * MS, sink);
  sendPackets(sut, sink, RTS_DT_ID, payload, 2, 3, START_NS + 3 * MS);

  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[1] == TpFrame{REPLY_TO_ORIGINATOR, 8,
                                  {0xFF, 0x01, 0xFD, 0xFF, 0xFF, 0xEC, 0xFE, 0x00}});
  CHECK(sink.frames[2] == expectedEndOfMsgAck(REPLY_TO_ORIGINATOR, 20, PGN_COMPONENT_ID));
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == payload);
  CHECK(sink.events[0] == TpEvent{TpEventKind::Refused, ORIGINATOR_ADDRESS, VCU_ADDRESS,
                                  PGN_VEHICLE_ID, TpAbortReason::AlreadyInSession});
}

TEST_CASE_FIXTURE(VcuReceiver, "a new RTS for the same PGN replaces the running session without an Abort") {
  const Bytes oldPayload = countingPayload(20);
  const Bytes newPayload = countingPayload(9);

  sut.onFrame(RTS_CM_ID, rts(oldPayload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(RTS_DT_ID, packet(oldPayload, 1), START_NS + MS, sink);
  sut.onFrame(RTS_CM_ID, rts(newPayload.size(), PGN_COMPONENT_ID), START_NS + 2 * MS, sink);
  sendPackets(sut, sink, RTS_DT_ID, newPayload, 1, 2, START_NS + 3 * MS);

  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[1] == expectedCts(REPLY_TO_ORIGINATOR, 2, 1, PGN_COMPONENT_ID));
  CHECK(sink.frames[2] == expectedEndOfMsgAck(REPLY_TO_ORIGINATOR, 9, PGN_COMPONENT_ID));
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == newPayload);
  CHECK(sink.events[0] == TpEvent{TpEventKind::SessionReplaced, ORIGINATOR_ADDRESS, VCU_ADDRESS,
                                  PGN_COMPONENT_ID, TpAbortReason::None});
  CHECK(sut.counters().sessionsReplaced == 1);
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuReceiver, "a new BAM from the same source replaces the old one") {
  const Bytes oldPayload = countingPayload(20);
  Bytes newPayload = countingPayload(14);
  std::fill(newPayload.begin(), newPayload.end(), std::uint8_t{0xA5});

  sut.onFrame(BAM_CM_ID, bam(oldPayload.size(), PGN_DM1_BROADCAST), START_NS, sink);
  sut.onFrame(BAM_DT_ID, packet(oldPayload, 1), START_NS + PACKET_GAP_NS, sink);
  sut.onFrame(BAM_CM_ID, bam(newPayload.size(), PGN_DM1_BROADCAST), START_NS + 2 * PACKET_GAP_NS,
              sink);
  sendPackets(sut, sink, BAM_DT_ID, newPayload, 1, 2, START_NS + 3 * PACKET_GAP_NS);

  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == newPayload);
  REQUIRE(sink.events.size() == 2);
  CHECK(sink.events[0] == TpEvent{TpEventKind::SessionReplaced, BAM_SOURCE_ADDRESS,
                                  GLOBAL_ADDRESS, PGN_DM1_BROADCAST, TpAbortReason::None});
  CHECK(sink.events[1].kind == TpEventKind::Completed);
}

TEST_CASE_FIXTURE(VcuReceiver, "an RTS announcing more than 1785 bytes is refused with reason 9") {
  sut.onFrame(RTS_CM_ID, FrameData{0x10, 0xFA, 0x06, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}, START_NS, sink);

  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == TpFrame{REPLY_TO_ORIGINATOR, 8,
                                  {0xFF, 0x09, 0xFD, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}});
  CHECK(sink.events[0] == TpEvent{TpEventKind::Refused, ORIGINATOR_ADDRESS, VCU_ADDRESS,
                                  PGN_COMPONENT_ID, TpAbortReason::MessageTooLarge});
  CHECK(sut.activeSessions() == 0);
  CHECK(sut.counters().announcementsRefused == 1);
}

TEST_CASE_FIXTURE(VcuReceiver, "an RTS whose size and packet count disagree is refused with reason 250") {
  FrameData wrongCount = rts(20, PGN_COMPONENT_ID);
  wrongCount[3] = 4;  // 20 bytes need 3 packets
  FrameData tooShort = rts(8, PGN_COMPONENT_ID);

  sut.onFrame(RTS_CM_ID, wrongCount, START_NS, sink);
  sut.onFrame(RTS_CM_ID, tooShort, START_NS + MS, sink);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[0] == expectedAbort(REPLY_TO_ORIGINATOR, TpAbortReason::Other, PGN_COMPONENT_ID));
  CHECK(sink.frames[1] == expectedAbort(REPLY_TO_ORIGINATOR, TpAbortReason::Other, PGN_COMPONENT_ID));
  CHECK(sut.activeSessions() == 0);
}

TEST_CASE_FIXTURE(VcuReceiver, "a BAM that is oversized or inconsistent is refused without a frame") {
  sut.onFrame(BAM_CM_ID, FrameData{0x20, 0xFA, 0x06, 0xFF, 0xFF, 0xCA, 0xFE, 0x00}, START_NS, sink);
  sut.onFrame(BAM_CM_ID, FrameData{0x20, 0x14, 0x00, 0x02, 0xFF, 0xCA, 0xFE, 0x00}, START_NS, sink);

  CHECK(sink.frames.empty());
  REQUIRE(sink.events.size() == 2);
  CHECK(sink.events[0].kind == TpEventKind::Refused);
  CHECK(sink.events[0].reason == TpAbortReason::MessageTooLarge);
  CHECK(sink.events[1].reason == TpAbortReason::Other);
  CHECK(sut.activeSessions() == 0);
}

TEST_CASE("a BAM finds no buffer while all are busy and is refused for resources") {
  TpReceiver sut({VCU_ADDRESS, TP_NO_PACKET_LIMIT, 1, 0});
  RecordingSink sink;
  constexpr std::uint32_t SECOND_BAM_CM_ID = 0x1CECFF11;

  sut.onFrame(BAM_CM_ID, bam(20, PGN_DM1_BROADCAST), START_NS, sink);
  sut.onFrame(SECOND_BAM_CM_ID, bam(20, PGN_DM1_BROADCAST), START_NS + MS, sink);
  sut.onFrame(RTS_CM_ID, rts(20, PGN_COMPONENT_ID), START_NS + 2 * MS, sink);

  REQUIRE(sink.events.size() == 2);
  CHECK(sink.events[0] == TpEvent{TpEventKind::Refused, 0x11, GLOBAL_ADDRESS, PGN_DM1_BROADCAST,
                                  TpAbortReason::ResourcesNeeded});
  REQUIRE(sink.frames.size() == 1);  // no hold places: the RTS is refused at once
  CHECK(sink.frames[0] ==
        expectedAbort(REPLY_TO_ORIGINATOR, TpAbortReason::AlreadyInSession, PGN_COMPONENT_ID));
}

TEST_CASE("the largest message, 1785 bytes in 255 packets, arrives in windows of 16") {
  constexpr std::uint8_t WINDOW = 16;
  TpReceiver sut({VCU_ADDRESS, WINDOW, 1, 0});
  RecordingSink sink;
  Bytes payload(TP_MAX_MESSAGE_SIZE);
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<std::uint8_t>(i * 7 + 3);

  sut.onFrame(RTS_CM_ID, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sendPackets(sut, sink, RTS_DT_ID, payload, 1, TP_MAX_PACKETS, START_NS + MS);

  constexpr std::size_t WINDOWS = (TP_MAX_PACKETS + WINDOW - 1) / WINDOW;  // 16
  REQUIRE(sink.frames.size() == WINDOWS + 1);
  CHECK(sink.frames[WINDOWS - 1] == expectedCts(REPLY_TO_ORIGINATOR, 15, 241, PGN_COMPONENT_ID));
  CHECK(sink.frames.back() == TpFrame{REPLY_TO_ORIGINATOR, 8,
                                      {0x13, 0xF9, 0x06, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}});
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == payload);
}

TEST_CASE_FIXTURE(VcuReceiver, "a last packet without its padding is accepted") {
  const Bytes payload = countingPayload(10);  // packet 2 carries 3 bytes
  const FrameData last = packet(payload, 2);

  sut.onFrame(BAM_CM_ID, bam(payload.size(), PGN_DM1_BROADCAST), START_NS, sink);
  sut.onFrame(BAM_DT_ID, packet(payload, 1), START_NS + MS, sink);
  sut.onFrame(BAM_DT_ID, std::span<const std::uint8_t>(last).first(4), START_NS + 2 * MS, sink);

  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].data == payload);
}

TEST_CASE_FIXTURE(VcuReceiver, "TP frames shorter than 8 bytes never crash and change nothing") {
  const Bytes payload = countingPayload(20);
  const FrameData announcement = rts(payload.size(), PGN_COMPONENT_ID);
  const FrameData broadcast = bam(payload.size(), PGN_DM1_BROADCAST);
  const FrameData abort = abortFrom(TpAbortReason::Timeout, PGN_COMPONENT_ID);
  const FrameData first = packet(payload, 1);

  sut.onFrame(RTS_CM_ID, announcement, START_NS, sink);
  sut.onFrame(BAM_CM_ID, broadcast, START_NS, sink);
  const std::size_t framesBefore = sink.frames.size();
  for (std::size_t length = 0; length < TP_FRAME_LENGTH; ++length) {
    CAPTURE(length);
    const std::int64_t nowNs = START_NS + static_cast<std::int64_t>(length + 1) * MS;
    sut.onFrame(RTS_CM_ID, std::span<const std::uint8_t>(announcement).first(length), nowNs, sink);
    sut.onFrame(RTS_CM_ID, std::span<const std::uint8_t>(abort).first(length), nowNs, sink);
    sut.onFrame(BAM_CM_ID, std::span<const std::uint8_t>(broadcast).first(length), nowNs, sink);
    sut.onFrame(RTS_DT_ID, std::span<const std::uint8_t>(first).first(length), nowNs, sink);
    sut.onFrame(BAM_DT_ID, std::span<const std::uint8_t>(first).first(length), nowNs, sink);
  }

  CHECK(sink.frames.size() == framesBefore);
  CHECK(sink.count(TpEventKind::Ignored) == 5 * TP_FRAME_LENGTH);
  CHECK(sut.activeSessions() == 2);
  sendPackets(sut, sink, RTS_DT_ID, payload, 1, 3, START_NS + 20 * MS);
  sendPackets(sut, sink, BAM_DT_ID, payload, 1, 3, START_NS + 30 * MS);
  CHECK(sink.messages.size() == 2);
}

TEST_CASE_FIXTURE(VcuReceiver, "frames longer than 8 bytes are ignored") {
  const std::array<std::uint8_t, 12> longRts{0x10, 0x14, 0x00, 0x03, 0xFF, 0xEB, 0xFE, 0x00,
                                             0, 0, 0, 0};

  sut.onFrame(RTS_CM_ID, longRts, START_NS, sink);

  CHECK(sink.frames.empty());
  CHECK(sink.count(TpEventKind::Ignored) == 1);
}

TEST_CASE_FIXTURE(VcuReceiver, "frames of other PGNs return without being counted") {
  constexpr std::uint32_t DM1_SINGLE_FRAME = 0x18FECA10;
  constexpr std::uint32_t DATA_PAGE_1_LOOKALIKE = 0x1DEC2120;  // PGN 0x1EC00, not TP.CM
  constexpr FrameData ANY{0x10, 0x14, 0x00, 0x03, 0xFF, 0xEB, 0xFE, 0x00};

  sut.onFrame(DM1_SINGLE_FRAME, ANY, START_NS, sink);
  sut.onFrame(DATA_PAGE_1_LOOKALIKE, ANY, START_NS, sink);

  CHECK(sink.frames.empty());
  CHECK(sink.events.empty());
  CHECK(sut.counters() == TpCounters{});
}

TEST_CASE_FIXTURE(VcuReceiver, "a packet for no session is ignored with reason unexpected data packet") {
  sut.onFrame(RTS_DT_ID, packet(countingPayload(9), 1), START_NS, sink);

  REQUIRE(sink.events.size() == 1);
  CHECK(sink.events[0] == TpEvent{TpEventKind::Ignored, ORIGINATOR_ADDRESS, VCU_ADDRESS, 0,
                                  TpAbortReason::UnexpectedDataPacket});
  CHECK(sink.frames.empty());
}

TEST_CASE_FIXTURE(VcuReceiver, "CTS and EndOfMsgAck sent to us are ignored because we never originate") {
  sut.onFrame(RTS_CM_ID, FrameData{0x11, 0x02, 0x01, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}, START_NS, sink);
  sut.onFrame(RTS_CM_ID, FrameData{0x13, 0x14, 0x00, 0x03, 0xFF, 0xEB, 0xFE, 0x00}, START_NS, sink);

  CHECK(sink.count(TpEventKind::Ignored) == 2);
  CHECK(sink.frames.empty());
}

TEST_CASE("a receiver without an address takes BAM only") {
  TpReceiver sut({NULL_ADDRESS, TP_NO_PACKET_LIMIT, 2, 1});
  RecordingSink sink;
  constexpr std::uint32_t RTS_TO_NULL = 0x1CECFE20;
  const Bytes payload = countingPayload(9);

  sut.onFrame(RTS_TO_NULL, rts(payload.size(), PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(BAM_CM_ID, bam(payload.size(), PGN_DM1_BROADCAST), START_NS, sink);
  sendPackets(sut, sink, BAM_DT_ID, payload, 1, 2, START_NS + MS);

  CHECK(sink.frames.empty());
  CHECK(sut.counters().framesNotForUs == 1);
  REQUIRE(sink.messages.size() == 1);
  CHECK(sink.messages[0].broadcast);
}

TEST_CASE("a receiver with no buffers refuses everything and holds nothing") {
  TpReceiver sut({VCU_ADDRESS, TP_NO_PACKET_LIMIT, 0, 4});
  RecordingSink sink;

  sut.onFrame(RTS_CM_ID, rts(20, PGN_COMPONENT_ID), START_NS, sink);
  sut.onFrame(BAM_CM_ID, bam(20, PGN_DM1_BROADCAST), START_NS, sink);

  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] ==
        expectedAbort(REPLY_TO_ORIGINATOR, TpAbortReason::AlreadyInSession, PGN_COMPONENT_ID));
  CHECK(sink.count(TpEventKind::Refused) == 2);
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
}

TEST_CASE_FIXTURE(VcuReceiver, "nextDeadlineNs is empty while no session is open and the earliest otherwise") {
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
  sut.onFrame(RTS_CM_ID, rts(20, PGN_COMPONENT_ID), START_NS, sink);          // T2
  sut.onFrame(BAM_CM_ID, bam(20, PGN_DM1_BROADCAST), START_NS + 100 * MS, sink);  // T1

  CHECK(sut.nextDeadlineNs() == START_NS + 100 * MS + TP_T1_NS);
}

TEST_CASE("abort reasons and event kinds have names for logs") {
  CHECK(tpAbortReasonName(TpAbortReason::BadSequenceNumber) == "BadSequenceNumber");
  CHECK(tpAbortReasonName(static_cast<TpAbortReason>(77)) == "Unknown");
  CHECK(tpEventKindName(TpEventKind::SessionReplaced) == "SessionReplaced");
}

// Random frames from a handful of addresses, biased towards TP identifiers, valid control
// bytes and small consistent sizes, mixed with packets that continue an announced transfer
// in order, so that sessions start, collide, complete and fail in every order. The oracle:
// a completed message always has the size most recently announced for its
// (source, kind, PGN), and every frame we send is a TP.CM from our address.
TEST_CASE("random TP frames never crash and never complete a message of another size than announced") {
  constexpr int FRAMES = 40'000;
  constexpr std::array<std::uint8_t, 6> SOURCES{0x10, 0x20, 0x30, VCU_ADDRESS, NULL_ADDRESS,
                                                GLOBAL_ADDRESS};
  constexpr std::array<std::uint8_t, 3> DESTINATIONS{VCU_ADDRESS, GLOBAL_ADDRESS, 0x30};
  constexpr std::array<std::uint8_t, 6> CONTROLS{TP_CM_RTS, TP_CM_BAM, TP_CM_ABORT, TP_CM_CTS,
                                                 TP_CM_END_OF_MSG_ACK, 0x42};
  constexpr std::array<std::uint32_t, 2> PGNS{PGN_DM1_BROADCAST, PGN_COMPONENT_ID};

  struct OracleSink final : TpSink {
    std::map<std::tuple<std::uint8_t, bool, std::uint32_t>, std::size_t> announced;
    std::int64_t nowNs{};
    int completions{};
    int broadcastCompletions{};
    int wrongSizes{};
    int wrongTimes{};
    int framesSent{};
    int badFrames{};
    void send(const TpFrame& frame) noexcept override {
      ++framesSent;
      const Id id = Id::fromCanId(frame.canId);
      if (frame.length != TP_FRAME_LENGTH || id.pgn() != PGN_TP_CM ||
          id.sourceAddress != VCU_ADDRESS || id.priority != TP_CM_PRIORITY) {
        ++badFrames;
      }
    }
    void completed(const TpMessage& message) noexcept override {
      ++completions;
      if (message.broadcast) ++broadcastCompletions;
      const auto it = announced.find({message.source, message.broadcast, message.pgn});
      if (it == announced.end() || it->second != message.data.size() ||
          message.data.size() < TP_MIN_MESSAGE_SIZE || message.data.size() > TP_MAX_MESSAGE_SIZE) {
        ++wrongSizes;
      }
      if (message.completedNs != nowNs) ++wrongTimes;
    }
    void event(const TpEvent&) noexcept override {}
  };

  std::uint64_t state = 0x5EED'1939;
  const auto next = [&state](std::uint32_t bound) {
    state = state * 6'364'136'223'846'793'005ull + 1'442'695'040'888'963'407ull;
    return static_cast<std::uint32_t>((state >> 33) % bound);
  };
  const auto pick = [&next](const auto& values) {
    return values[next(static_cast<std::uint32_t>(values.size()))];
  };
  const auto tpId = [](std::uint8_t pduFormat, std::uint8_t destination, std::uint8_t source) {
    return (7u << 26) | (static_cast<std::uint32_t>(pduFormat) << 16) |
           (static_cast<std::uint32_t>(destination) << 8) | source;
  };

  TpReceiver sut({VCU_ADDRESS, 3, 4, 2});
  OracleSink sink;
  sink.nowNs = START_NS;
  std::array<std::uint8_t, 12> data{};
  // (source, broadcast) of announcements sent -> (next packet, packets) of an orderly
  // originator.
  std::map<std::pair<std::uint8_t, bool>, std::pair<std::uint8_t, std::uint8_t>> transfers;

  for (int i = 0; i < FRAMES; ++i) {
    sink.nowNs += static_cast<std::int64_t>(next(120)) * MS;
    for (auto& byte : data) byte = static_cast<std::uint8_t>(next(256));
    const std::uint32_t mode = next(10);
    if (mode == 0) {
      sut.poll(sink.nowNs, sink);
      continue;
    }
    if (mode <= 6 && !transfers.empty()) {  // the next packet of a transfer, in order
      auto it = transfers.begin();
      std::advance(it, next(static_cast<std::uint32_t>(transfers.size())));
      const auto [source, broadcast] = it->first;
      auto& [nextPacket, packets] = it->second;
      data[0] = nextPacket++;
      if (nextPacket > packets) transfers.erase(it);
      sut.onFrame(tpId(0xEB, broadcast ? GLOBAL_ADDRESS : VCU_ADDRESS, source),
                  std::span<const std::uint8_t>(data).first(TP_FRAME_LENGTH), sink.nowNs, sink);
      continue;
    }

    const std::uint8_t source = next(4) == 0 ? static_cast<std::uint8_t>(next(256)) : pick(SOURCES);
    std::uint8_t destination =
        next(8) == 0 ? static_cast<std::uint8_t>(next(256)) : pick(DESTINATIONS);
    const std::uint8_t control =
        next(8) == 0 ? static_cast<std::uint8_t>(next(256)) : pick(CONTROLS);
    if (next(4) != 0 && control == TP_CM_RTS) destination = VCU_ADDRESS;
    if (next(4) != 0 && control == TP_CM_BAM) destination = GLOBAL_ADDRESS;
    const std::uint32_t roll = next(20);
    const std::uint8_t pduFormat =
        roll < 15 ? 0xEC : roll < 17 ? 0xEB : static_cast<std::uint8_t>(next(256));
    const bool dataPage = next(50) == 0;
    const std::uint32_t canId = (next(8) << 26) | (dataPage ? 1u << 24 : 0u) |
                                (static_cast<std::uint32_t>(pduFormat) << 16) |
                                (static_cast<std::uint32_t>(destination) << 8) | source;
    const std::size_t length = next(6) == 0 ? next(13) : TP_FRAME_LENGTH;

    if (pduFormat == 0xEC) {
      const std::size_t size = next(8) == 0 ? next(2'000) : 9 + next(30);
      const std::uint32_t pgn = next(8) == 0 ? next(1u << 24) : pick(PGNS);
      data[0] = control;
      data[1] = lowByte(size);
      data[2] = highByte(size);
      data[3] = next(5) == 0 ? static_cast<std::uint8_t>(next(256)) : packetsOf(size);
      for (unsigned b = 0; b < 3; ++b) data[5 + b] = pgnByte(pgn, b);
      // What the receiver takes for an announcement to us: 8 bytes on TP.CM (data page 0),
      // from a source that may originate, RTS to our address or BAM to global.
      const bool wellFormed = length == TP_FRAME_LENGTH && !dataPage && source < NULL_ADDRESS &&
                              source != VCU_ADDRESS;
      const bool rtsToUs = data[0] == TP_CM_RTS && destination == VCU_ADDRESS;
      const bool bamToAll = data[0] == TP_CM_BAM && destination == GLOBAL_ADDRESS;
      if (wellFormed && (rtsToUs || bamToAll)) {
        sink.announced[{source, bamToAll, pgn}] = size;
        transfers[{source, bamToAll}] = {1, data[3]};
      }
    } else if (pduFormat == 0xEB) {
      data[0] = static_cast<std::uint8_t>(next(6) == 0 ? next(256) : 1 + next(4));
    }
    sut.onFrame(canId, std::span<const std::uint8_t>(data).first(length), sink.nowNs, sink);
  }

  INFO("completions " << sink.completions << ", frames sent " << sink.framesSent);
  CHECK(sink.wrongSizes == 0);
  CHECK(sink.wrongTimes == 0);
  CHECK(sink.badFrames == 0);
  CHECK(sink.completions > 100);  // the test does reach completions, of both kinds
  CHECK(sink.broadcastCompletions > 10);
  CHECK(sink.completions - sink.broadcastCompletions > 10);
  CHECK(sink.framesSent > 1'000);
  checkCountersBalance(sut);
  CHECK(sut.activeSessions() <= 4 + 2);
}
