// TpSender (J1939-21 transport originator) with a set clock, issue 24.
#include "openvcu/j1939/transport_sender.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

using namespace openvcu::j1939;

// Failure messages name the values instead of "{?}".
template <>
struct doctest::StringMaker<TpSendStatus> {
  static doctest::String convert(TpSendStatus status) {
    const std::string_view name = tpSendStatusName(status);
    return {name.data(), static_cast<doctest::String::size_type>(name.size())};
  }
};
template <>
struct doctest::StringMaker<TpSendResult> {
  static doctest::String convert(const TpSendResult& result) {
    char text[96];
    std::snprintf(text, sizeof text, "{PGN %05X to %02X %s reason %u}",
                  static_cast<unsigned>(result.pgn), static_cast<unsigned>(result.destination),
                  std::string(tpSendOutcomeName(result.outcome)).c_str(),
                  static_cast<unsigned>(result.reason));
    return text;
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

constexpr std::uint8_t VCU_ADDRESS = 0x21;         // us, the originator
constexpr std::uint8_t PEER_ADDRESS = 0x20;        // receives by RTS/CTS
constexpr std::uint8_t OTHER_PEER_ADDRESS = 0x30;
constexpr std::uint8_t NEW_VCU_ADDRESS = 0x81;     // after a lost address claim
constexpr std::uint32_t PGN_COMPONENT_ID = 0xFEEB; // 65259
constexpr std::uint32_t PGN_VEHICLE_ID = 0xFEEC;   // 65260
constexpr std::uint32_t PGN_DM1 = 0xFECA;          // 65226
constexpr std::uint32_t PGN_DM2 = 0xFECB;          // 65227

// 29-bit identifiers (priority 7).
constexpr std::uint32_t BAM_CM_ID = 0x1CECFF21;       // our TP.CM to global
constexpr std::uint32_t BAM_DT_ID = 0x1CEBFF21;       // our TP.DT to global
constexpr std::uint32_t TO_PEER_CM_ID = 0x1CEC2021;   // our TP.CM to 0x20
constexpr std::uint32_t TO_PEER_DT_ID = 0x1CEB2021;   // our TP.DT to 0x20
constexpr std::uint32_t FROM_PEER_CM_ID = 0x1CEC2120; // 0x20's TP.CM to us
constexpr std::uint32_t TO_OTHER_CM_ID = 0x1CEC3021;  // our TP.CM to 0x30
constexpr std::uint32_t FROM_OTHER_CM_ID = 0x1CEC2130;
constexpr std::uint32_t NEW_TO_PEER_CM_ID = 0x1CEC2081;  // from our new address
constexpr std::uint32_t FROM_PEER_TO_NEW_CM_ID = 0x1CEC8120;
constexpr std::uint32_t FROM_PEER_TO_OTHER_CM_ID = 0x1CEC3020;  // 0x20 answers 0x30

constexpr std::uint8_t TP_PRIORITY = TP_CM_PRIORITY;
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START_NS = 1'000 * MS;
constexpr std::int64_t BAM_GAP_NS = 50 * MS;
constexpr std::uint8_t ROLE_RESPONDER_BYTE = 0xFD;
constexpr std::uint8_t ROLE_ORIGINATOR_BYTE = 0xFC;
constexpr std::uint8_t ROLE_LEGACY_BYTE = 0xFF;

constexpr TpSenderConfig VCU_CONFIG{.ownAddress = VCU_ADDRESS,
                                    .maxSessions = 4,
                                    .queueCapacity = 4,
                                    .maxPacketsPerCts = TP_NO_PACKET_LIMIT,
                                    .bamPacketGapNs = BAM_GAP_NS,
                                    .rtsPacketGapNs = 0,
                                    .maxRetransmitRequests = TP_MAX_RETRANSMIT_REQUESTS};

struct RecordingSink final : TpSendSink {
  std::vector<TpFrame> frames;
  std::vector<TpSendResult> results;
  void send(const TpFrame& frame) noexcept override { frames.push_back(frame); }
  void finished(const TpSendResult& result) noexcept override { results.push_back(result); }
};

// 1, 2, 3, ... `size` bytes: every byte tells its position.
Bytes countingPayload(std::size_t size) {
  Bytes payload(size);
  for (std::size_t i = 0; i < size; ++i) payload[i] = static_cast<std::uint8_t>(i + 1);
  return payload;
}

constexpr std::uint8_t byteAt(std::size_t value, unsigned index) {
  return static_cast<std::uint8_t>((value >> (8 * index)) & 0xFF);
}
std::uint8_t packetsOf(std::size_t size) {
  return static_cast<std::uint8_t>((size + TP_BYTES_PER_PACKET - 1) / TP_BYTES_PER_PACKET);
}

FrameData cts(std::uint8_t count, std::uint8_t next, std::uint32_t pgn = PGN_COMPONENT_ID) {
  return {TP_CM_CTS, count, next, 0xFF, 0xFF, byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)};
}
FrameData endOfMsgAck(std::size_t size, std::uint32_t pgn = PGN_COMPONENT_ID) {
  return {TP_CM_END_OF_MSG_ACK, byteAt(size, 0), byteAt(size, 1), packetsOf(size), 0xFF,
          byteAt(pgn, 0),       byteAt(pgn, 1),  byteAt(pgn, 2)};
}
FrameData abortFrom(TpAbortReason reason, std::uint32_t pgn = PGN_COMPONENT_ID,
                    std::uint8_t roleByte = ROLE_RESPONDER_BYTE) {
  return {TP_CM_ABORT, static_cast<std::uint8_t>(reason), roleByte, 0xFF, 0xFF,
          byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)};
}

TpFrame frameOf(std::uint32_t canId, const FrameData& data) {
  return TpFrame{canId, static_cast<std::uint8_t>(TP_FRAME_LENGTH), data};
}
TpFrame expectedRts(std::uint32_t canId, std::size_t size, std::uint32_t pgn,
                    std::uint8_t limit = TP_NO_PACKET_LIMIT) {
  return frameOf(canId, {TP_CM_RTS, byteAt(size, 0), byteAt(size, 1), packetsOf(size), limit,
                         byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)});
}
TpFrame expectedBam(std::size_t size, std::uint32_t pgn) {
  return frameOf(BAM_CM_ID, {TP_CM_BAM, byteAt(size, 0), byteAt(size, 1), packetsOf(size), 0xFF,
                             byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)});
}
// Our Abort: byte 2 reserved bits 1, role 00 = originator.
TpFrame expectedAbort(std::uint32_t canId, TpAbortReason reason, std::uint32_t pgn = PGN_COMPONENT_ID) {
  return frameOf(canId, {TP_CM_ABORT, static_cast<std::uint8_t>(reason), ROLE_ORIGINATOR_BYTE, 0xFF,
                         0xFF, byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)});
}
// Packet `sequence` (1-based) of `payload`, the last one padded with 0xFF.
TpFrame expectedPacket(std::uint32_t canId, const Bytes& payload, std::size_t sequence) {
  FrameData data;
  data.fill(0xFF);
  data[0] = static_cast<std::uint8_t>(sequence);
  const std::size_t offset = (sequence - 1) * TP_BYTES_PER_PACKET;
  for (std::size_t i = 0; i < TP_BYTES_PER_PACKET && offset + i < payload.size(); ++i) {
    data[1 + i] = payload[offset + i];
  }
  return frameOf(canId, data);
}

TpSendResult result(std::uint32_t pgn, std::uint8_t destination, TpSendOutcome outcome,
                    TpAbortReason reason = TpAbortReason::None) {
  return TpSendResult{pgn, destination, outcome, reason};
}

void checkCountersBalance(const TpSender& sender) {
  const TpSenderCounters& counters = sender.counters();
  CHECK(counters.sessionsStarted == counters.sessionsCompleted + counters.sessionsAbortedByPeer +
                                        counters.sessionsAbortedByUs + counters.sessionsTimedOut +
                                        counters.sessionsEndedByAddressChange +
                                        sender.activeSessions());
  CHECK(counters.messagesQueued == counters.messagesStartedFromQueue +
                                       counters.queuedDroppedByAddressChange +
                                       sender.queuedMessages());
}

/// A sender with the VCU's configuration and the sink that records what it does.
struct VcuSender {
  TpSender sut{VCU_CONFIG};
  RecordingSink sink;

  TpSendStatus sendTo(std::uint8_t destination, const Bytes& payload, std::int64_t nowNs,
                      std::uint32_t pgn = PGN_COMPONENT_ID) {
    return sut.send(pgn, destination, TP_PRIORITY, payload, nowNs, sink);
  }
  void fromPeer(const FrameData& data, std::int64_t nowNs, std::uint32_t canId = FROM_PEER_CM_ID) {
    sut.onFrame(canId, data, nowNs, sink);
  }
};

}  // namespace

// ---- BAM -----------------------------------------------------------------------------------

TEST_CASE_FIXTURE(VcuSender, "BAM of 20 bytes announces 3 packets and sends them 50 ms apart, the last padded") {
  const Bytes payload = countingPayload(20);

  REQUIRE(sendTo(GLOBAL_ADDRESS, payload, START_NS, PGN_DM1) == TpSendStatus::Started);

  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == frameOf(BAM_CM_ID, {0x20, 0x14, 0x00, 0x03, 0xFF, 0xCA, 0xFE, 0x00}));
  CHECK(sut.nextDeadlineNs() == START_NS + BAM_GAP_NS);

  sut.poll(START_NS + BAM_GAP_NS - 1, sink);  // not yet due
  CHECK(sink.frames.size() == 1);

  sut.poll(START_NS + BAM_GAP_NS, sink);
  sut.poll(START_NS + 2 * BAM_GAP_NS, sink);
  CHECK(sink.results.empty());
  sut.poll(START_NS + 3 * BAM_GAP_NS, sink);

  REQUIRE(sink.frames.size() == 4);
  CHECK(sink.frames[1] == frameOf(BAM_DT_ID, {0x01, 1, 2, 3, 4, 5, 6, 7}));
  CHECK(sink.frames[2] == frameOf(BAM_DT_ID, {0x02, 8, 9, 10, 11, 12, 13, 14}));
  CHECK(sink.frames[3] == frameOf(BAM_DT_ID, {0x03, 15, 16, 17, 18, 19, 20, 0xFF}));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] == result(PGN_DM1, GLOBAL_ADDRESS, TpSendOutcome::Completed));
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
  CHECK(sut.activeSessions() == 0);
  CHECK(sut.counters().sessionsCompleted == 1);
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuSender, "BAM of 9 bytes, the shortest, sends 2 packets with 5 bytes of padding") {
  const Bytes payload = countingPayload(TP_MIN_MESSAGE_SIZE);

  REQUIRE(sendTo(GLOBAL_ADDRESS, payload, START_NS, PGN_DM1) == TpSendStatus::Started);
  sut.poll(START_NS + BAM_GAP_NS, sink);
  sut.poll(START_NS + 2 * BAM_GAP_NS, sink);

  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[0] == frameOf(BAM_CM_ID, {0x20, 0x09, 0x00, 0x02, 0xFF, 0xCA, 0xFE, 0x00}));
  CHECK(sink.frames[1] == frameOf(BAM_DT_ID, {0x01, 1, 2, 3, 4, 5, 6, 7}));
  CHECK(sink.frames[2] == frameOf(BAM_DT_ID, {0x02, 8, 9, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0].outcome == TpSendOutcome::Completed);
}

TEST_CASE_FIXTURE(VcuSender, "BAM of 1785 bytes sends 255 packets, each 50 ms after the previous one") {
  Bytes payload(TP_MAX_MESSAGE_SIZE);
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<std::uint8_t>(i * 7 + 3);

  REQUIRE(sendTo(GLOBAL_ADDRESS, payload, START_NS, PGN_DM1) == TpSendStatus::Started);
  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == frameOf(BAM_CM_ID, {0x20, 0xF9, 0x06, 0xFF, 0xFF, 0xCA, 0xFE, 0x00}));

  // Drive by nextDeadlineNs() as a service would: every packet comes exactly one gap later.
  std::int64_t previousNs = START_NS;
  std::size_t packets = 0;
  while (const auto deadline = sut.nextDeadlineNs()) {
    CHECK(*deadline == previousNs + BAM_GAP_NS);
    sut.poll(*deadline, sink);
    previousNs = *deadline;
    ++packets;
    REQUIRE(packets <= TP_MAX_PACKETS);
  }
  CHECK(packets == TP_MAX_PACKETS);
  REQUIRE(sink.frames.size() == 1 + TP_MAX_PACKETS);
  for (std::size_t sequence = 1; sequence <= TP_MAX_PACKETS; ++sequence) {
    CHECK(sink.frames[sequence] == expectedPacket(BAM_DT_ID, payload, sequence));
  }
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] == result(PGN_DM1, GLOBAL_ADDRESS, TpSendOutcome::Completed));
  checkCountersBalance(sut);
}

TEST_CASE("the BAM packet gap is configurable within J1939-21's 50..200 ms") {
  const Bytes payload = countingPayload(20);
  RecordingSink sink;
  SUBCASE("100 ms is kept") {
    TpSender sut({.ownAddress = VCU_ADDRESS, .bamPacketGapNs = 100 * MS});
    CHECK(sut.send(PGN_DM1, GLOBAL_ADDRESS, TP_PRIORITY, payload, START_NS, sink) == TpSendStatus::Started);
    CHECK(sut.nextDeadlineNs() == START_NS + 100 * MS);
  }
  SUBCASE("10 ms is raised to 50 ms") {
    TpSender sut({.ownAddress = VCU_ADDRESS, .bamPacketGapNs = 10 * MS});
    CHECK(sut.config().bamPacketGapNs == TP_BAM_MIN_GAP_NS);
  }
  SUBCASE("1 s is lowered to 200 ms") {
    TpSender sut({.ownAddress = VCU_ADDRESS, .bamPacketGapNs = 1000 * MS});
    CHECK(sut.config().bamPacketGapNs == TP_BAM_MAX_GAP_NS);
  }
}

TEST_CASE_FIXTURE(VcuSender, "a late poll sends one BAM packet and keeps the full gap to the next") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(GLOBAL_ADDRESS, payload, START_NS, PGN_DM1) == TpSendStatus::Started);

  const std::int64_t lateNs = START_NS + 5 * BAM_GAP_NS;
  sut.poll(lateNs, sink);

  CHECK(sink.frames.size() == 2);  // the announcement and packet 1 only
  CHECK(sut.nextDeadlineNs() == lateNs + BAM_GAP_NS);
}

TEST_CASE_FIXTURE(VcuSender, "the session's priority goes into its TP.CM and TP.DT identifiers") {
  constexpr std::uint8_t PRIORITY_6 = 6;
  const Bytes payload = countingPayload(9);
  REQUIRE(sut.send(PGN_DM1, GLOBAL_ADDRESS, PRIORITY_6, payload, START_NS, sink) == TpSendStatus::Started);
  sut.poll(START_NS + BAM_GAP_NS, sink);
  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[0].canId == 0x18ECFF21u);
  CHECK(sink.frames[1].canId == 0x18EBFF21u);
}

// ---- RTS/CTS -------------------------------------------------------------------------------

TEST_CASE_FIXTURE(VcuSender, "RTS/CTS: one CTS for all packets gets them back to back and the EndOfMsgAck completes") {
  const Bytes payload = countingPayload(20);

  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  REQUIRE(sink.frames.size() == 1);
  CHECK(sink.frames[0] == frameOf(TO_PEER_CM_ID, {0x10, 0x14, 0x00, 0x03, 0xFF, 0xEB, 0xFE, 0x00}));
  CHECK(sut.nextDeadlineNs() == START_NS + TP_T3_NS);

  fromPeer({0x11, 0x03, 0x01, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}, START_NS + 10 * MS);

  REQUIRE(sink.frames.size() == 4);
  CHECK(sink.frames[1] == frameOf(TO_PEER_DT_ID, {0x01, 1, 2, 3, 4, 5, 6, 7}));
  CHECK(sink.frames[2] == frameOf(TO_PEER_DT_ID, {0x02, 8, 9, 10, 11, 12, 13, 14}));
  CHECK(sink.frames[3] == frameOf(TO_PEER_DT_ID, {0x03, 15, 16, 17, 18, 19, 20, 0xFF}));
  CHECK(sut.nextDeadlineNs() == START_NS + 10 * MS + TP_T3_NS);  // waiting for the EndOfMsgAck
  CHECK(sink.results.empty());

  fromPeer({0x13, 0x14, 0x00, 0x03, 0xFF, 0xEB, 0xFE, 0x00}, START_NS + 20 * MS);

  CHECK(sink.frames.size() == 4);
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] == result(PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::Completed));
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
  checkCountersBalance(sut);
}

TEST_CASE("RTS/CTS windows of 1..n packets: each CTS gets exactly the packets it asks for") {
  const Bytes payload = countingPayload(33);  // 5 packets
  constexpr std::uint8_t PACKETS = 5;
  for (std::uint8_t window = 1; window <= PACKETS; ++window) {
    CAPTURE(window);
    TpSenderConfig config = VCU_CONFIG;
    config.maxPacketsPerCts = window;
    TpSender sut(config);
    RecordingSink sink;
    REQUIRE(sut.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
            TpSendStatus::Started);
    REQUIRE(sink.frames.size() == 1);
    CHECK(sink.frames[0] == expectedRts(TO_PEER_CM_ID, payload.size(), PGN_COMPONENT_ID, window));

    std::int64_t nowNs = START_NS;
    std::size_t next = 1;
    while (next <= PACKETS) {
      const auto count = static_cast<std::uint8_t>(std::min<std::size_t>(window, PACKETS - next + 1));
      nowNs += 100 * MS;
      const std::size_t before = sink.frames.size();
      sut.onFrame(FROM_PEER_CM_ID, cts(count, static_cast<std::uint8_t>(next)), nowNs, sink);
      REQUIRE(sink.frames.size() == before + count);
      for (std::size_t i = 0; i < count; ++i) {
        CHECK(sink.frames[before + i] == expectedPacket(TO_PEER_DT_ID, payload, next + i));
      }
      CHECK(sut.nextDeadlineNs() == nowNs + TP_T3_NS);  // next CTS or the EndOfMsgAck
      next += count;
    }
    sut.onFrame(FROM_PEER_CM_ID, endOfMsgAck(payload.size()), nowNs + MS, sink);
    REQUIRE(sink.results.size() == 1);
    CHECK(sink.results[0].outcome == TpSendOutcome::Completed);
    CHECK(sut.counters().abortsSent == 0);
  }
}

TEST_CASE_FIXTURE(VcuSender, "CTS(0) holds the session: no packets, T4 from each hold, then a CTS resumes it") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);

  const std::int64_t holdNs = START_NS + 10 * MS;
  fromPeer(cts(0, 1), holdNs);
  CHECK(sink.frames.size() == 1);
  CHECK(sut.nextDeadlineNs() == holdNs + TP_T4_NS);

  const std::int64_t secondHoldNs = holdNs + TP_TH_NS;  // the receiver repeats it within Th
  fromPeer(cts(0, 1), secondHoldNs);
  CHECK(sut.nextDeadlineNs() == secondHoldNs + TP_T4_NS);
  sut.poll(holdNs + TP_T4_NS, sink);  // the first hold's T4 no longer counts
  CHECK(sink.frames.size() == 1);

  fromPeer(cts(3, 1), secondHoldNs + 400 * MS);
  CHECK(sink.frames.size() == 4);
  fromPeer(endOfMsgAck(payload.size()), secondHoldNs + 410 * MS);
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0].outcome == TpSendOutcome::Completed);
  CHECK(sut.counters().holdsReceived == 2);
}

TEST_CASE_FIXTURE(VcuSender, "a hold between windows resumes at the next packet") {
  const Bytes payload = countingPayload(33);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  fromPeer(cts(2, 1), START_NS + MS);
  fromPeer(cts(0, 3), START_NS + 2 * MS);
  fromPeer(cts(3, 3), START_NS + 500 * MS);
  REQUIRE(sink.frames.size() == 6);
  CHECK(sink.frames[3] == expectedPacket(TO_PEER_DT_ID, payload, 3));
  CHECK(sink.frames[5] == expectedPacket(TO_PEER_DT_ID, payload, 5));
  CHECK(sut.counters().retransmitRequests == 0);
}

TEST_CASE_FIXTURE(VcuSender, "a hold longer than T4 ends the session with Abort reason 3") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  const std::int64_t holdNs = START_NS + 10 * MS;
  fromPeer(cts(0, 1), holdNs);

  sut.poll(holdNs + TP_T4_NS - 1, sink);
  CHECK(sink.frames.size() == 1);
  sut.poll(holdNs + TP_T4_NS, sink);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Timeout));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] ==
        result(PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::TimedOut, TpAbortReason::Timeout));
  CHECK(sut.counters().sessionsTimedOut == 1);
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuSender, "no CTS within T3 after the RTS ends the session with Abort reason 3") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);

  sut.poll(START_NS + TP_T3_NS - 1, sink);
  CHECK(sink.frames.size() == 1);
  sut.poll(START_NS + TP_T3_NS, sink);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Timeout));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0].outcome == TpSendOutcome::TimedOut);
}

TEST_CASE_FIXTURE(VcuSender, "a CTS exactly at the T3 deadline is late: the timeout comes first") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);

  fromPeer(cts(3, 1), START_NS + TP_T3_NS);

  REQUIRE(sink.frames.size() == 2);  // RTS, Abort: no packets
  CHECK(sink.frames[1] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Timeout));
  CHECK(sut.counters().framesIgnored == 1);  // the CTS found no session
}

TEST_CASE_FIXTURE(VcuSender, "no CTS within T3 after a window's last packet ends the session with Abort 3") {
  const Bytes payload = countingPayload(33);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  const std::int64_t windowNs = START_NS + 10 * MS;
  fromPeer(cts(2, 1), windowNs);
  CHECK(sut.nextDeadlineNs() == windowNs + TP_T3_NS);

  sut.poll(windowNs + TP_T3_NS, sink);

  CHECK(sink.frames.back() == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Timeout));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0].outcome == TpSendOutcome::TimedOut);
}

TEST_CASE_FIXTURE(VcuSender, "no EndOfMsgAck within T3 after the last packet ends the session with Abort 3") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  const std::int64_t lastPacketNs = START_NS + 10 * MS;
  fromPeer(cts(3, 1), lastPacketNs);

  sut.poll(lastPacketNs + TP_T3_NS - 1, sink);
  CHECK(sink.results.empty());
  sut.poll(lastPacketNs + TP_T3_NS, sink);

  REQUIRE(sink.frames.size() == 5);
  CHECK(sink.frames[4] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Timeout));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] ==
        result(PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::TimedOut, TpAbortReason::Timeout));
}

TEST_CASE_FIXTURE(VcuSender, "a CTS for earlier packets of the last window gets them again (retransmission)") {
  const Bytes payload = countingPayload(33);  // 5 packets
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  fromPeer(cts(5, 1), START_NS + MS);
  REQUIRE(sink.frames.size() == 6);

  fromPeer(cts(2, 2), START_NS + 2 * MS);  // packets 2 and 3 again
  REQUIRE(sink.frames.size() == 8);
  CHECK(sink.frames[6] == expectedPacket(TO_PEER_DT_ID, payload, 2));
  CHECK(sink.frames[7] == expectedPacket(TO_PEER_DT_ID, payload, 3));

  fromPeer(cts(2, 4), START_NS + 3 * MS);  // then the rest again
  REQUIRE(sink.frames.size() == 10);
  CHECK(sink.frames[9] == expectedPacket(TO_PEER_DT_ID, payload, 5));

  fromPeer(endOfMsgAck(payload.size()), START_NS + 4 * MS);
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0].outcome == TpSendOutcome::Completed);
  CHECK(sut.counters().retransmitRequests == 1);
}

TEST_CASE_FIXTURE(VcuSender, "a third retransmission request gets Abort reason 5") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  fromPeer(cts(3, 1), START_NS + MS);
  fromPeer(cts(3, 1), START_NS + 2 * MS);
  fromPeer(cts(3, 1), START_NS + 3 * MS);
  CHECK(sink.frames.size() == 1 + 3 * 3);
  CHECK(sink.results.empty());

  fromPeer(cts(3, 1), START_NS + 4 * MS);

  CHECK(sink.frames.size() == 11);
  CHECK(sink.frames.back() == expectedAbort(TO_PEER_CM_ID, TpAbortReason::RetransmitLimit));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] == result(PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::AbortSent,
                                  TpAbortReason::RetransmitLimit));
  CHECK(sut.counters().retransmitRequests == 3);
}

TEST_CASE_FIXTURE(VcuSender, "a CTS the message cannot satisfy is answered with an Abort") {
  const Bytes payload = countingPayload(33);  // 5 packets
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  FrameData badCts{};
  TpAbortReason reason{};
  SUBCASE("next packet 0") {
    badCts = cts(1, 0);
    reason = TpAbortReason::Other;
  }
  SUBCASE("next packet beyond the message") {
    badCts = cts(1, 6);
    reason = TpAbortReason::Other;
  }
  SUBCASE("a window reaching beyond the message") {
    badCts = cts(5, 2);
    reason = TpAbortReason::Other;
  }
  SUBCASE("skipping packets never sent") {
    badCts = cts(2, 2);
    reason = TpAbortReason::BadSequenceNumber;
  }
  fromPeer(badCts, START_NS + MS);

  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == expectedAbort(TO_PEER_CM_ID, reason));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] == result(PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::AbortSent, reason));
  CHECK(sut.counters().sessionsAbortedByUs == 1);
  checkCountersBalance(sut);
}

TEST_CASE("a CTS asking for more packets than the RTS allowed is answered with Abort 250") {
  TpSenderConfig config = VCU_CONFIG;
  config.maxPacketsPerCts = 2;
  TpSender sut(config);
  RecordingSink sink;
  const Bytes payload = countingPayload(33);
  REQUIRE(sut.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
          TpSendStatus::Started);
  sut.onFrame(FROM_PEER_CM_ID, cts(3, 1), START_NS + MS, sink);
  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Other));
}

TEST_CASE_FIXTURE(VcuSender, "a CTS for packets an earlier CTS acknowledged is answered with Abort 8") {
  const Bytes payload = countingPayload(33);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  fromPeer(cts(2, 1), START_NS + MS);
  fromPeer(cts(2, 3), START_NS + 2 * MS);  // acknowledges 1 and 2
  REQUIRE(sink.frames.size() == 5);

  fromPeer(cts(1, 2), START_NS + 3 * MS);

  REQUIRE(sink.frames.size() == 6);
  CHECK(sink.frames[5] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::DuplicateSequenceNumber));
}

TEST_CASE("with a packet gap, packets go out one per gap and a CTS during the window gets Abort 4") {
  constexpr std::int64_t GAP_NS = 10 * MS;
  TpSenderConfig config = VCU_CONFIG;
  config.rtsPacketGapNs = GAP_NS;
  TpSender sut(config);
  RecordingSink sink;
  const Bytes payload = countingPayload(20);
  REQUIRE(sut.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
          TpSendStatus::Started);

  const std::int64_t ctsNs = START_NS + MS;
  sut.onFrame(FROM_PEER_CM_ID, cts(3, 1), ctsNs, sink);
  REQUIRE(sink.frames.size() == 2);  // packet 1 at once
  CHECK(sut.nextDeadlineNs() == ctsNs + GAP_NS);
  sut.poll(ctsNs + GAP_NS - 1, sink);
  CHECK(sink.frames.size() == 2);
  sut.poll(ctsNs + GAP_NS, sink);
  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[2] == expectedPacket(TO_PEER_DT_ID, payload, 2));

  SUBCASE("the window ends, then T3 runs") {
    sut.poll(ctsNs + 2 * GAP_NS, sink);
    REQUIRE(sink.frames.size() == 4);
    CHECK(sut.nextDeadlineNs() == ctsNs + 2 * GAP_NS + TP_T3_NS);
  }
  SUBCASE("a CTS before the window's last packet") {
    sut.onFrame(FROM_PEER_CM_ID, cts(3, 1), ctsNs + GAP_NS + MS, sink);
    REQUIRE(sink.frames.size() == 4);
    CHECK(sink.frames[3] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::CtsWhileTransferring));
    REQUIRE(sink.results.size() == 1);
    CHECK(sink.results[0].outcome == TpSendOutcome::AbortSent);
  }
}

TEST_CASE_FIXTURE(VcuSender, "an EndOfMsgAck before the last packet, or for another size, gets Abort 250") {
  const Bytes payload = countingPayload(33);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  SUBCASE("early") {
    fromPeer(cts(2, 1), START_NS + MS);
    fromPeer(endOfMsgAck(payload.size()), START_NS + 2 * MS);
  }
  SUBCASE("another size") {
    fromPeer(cts(5, 1), START_NS + MS);
    fromPeer(endOfMsgAck(payload.size() - 1), START_NS + 2 * MS);
  }
  CHECK(sink.frames.back() == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Other));
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] ==
        result(PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::AbortSent, TpAbortReason::Other));
}

TEST_CASE_FIXTURE(VcuSender, "an Abort from the receiver ends the session without a frame from us") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  std::uint8_t roleByte = ROLE_RESPONDER_BYTE;
  SUBCASE("role responder (J1939-21 2022)") { roleByte = ROLE_RESPONDER_BYTE; }
  SUBCASE("byte 2 reserved (older editions)") { roleByte = ROLE_LEGACY_BYTE; }

  fromPeer(abortFrom(TpAbortReason::AlreadyInSession, PGN_COMPONENT_ID, roleByte), START_NS + MS);

  CHECK(sink.frames.size() == 1);
  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] == result(PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::AbortedByPeer,
                                  TpAbortReason::AlreadyInSession));
  CHECK(sut.counters().sessionsAbortedByPeer == 1);
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuSender, "TP.CM frames that are not answers to our running session change nothing") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);

  // Counted as ignored: for us, but no session matches.
  fromPeer(cts(3, 1), START_NS + MS, FROM_OTHER_CM_ID);                      // no session with 0x30
  fromPeer(cts(3, 1, PGN_VEHICLE_ID), START_NS + MS);                          // another PGN
  fromPeer(abortFrom(TpAbortReason::Timeout, PGN_VEHICLE_ID), START_NS + MS);  // another PGN
  fromPeer(abortFrom(TpAbortReason::Timeout, PGN_COMPONENT_ID, ROLE_ORIGINATOR_BYTE),
           START_NS + MS);  // the peer aborts its own session to us
  sut.onFrame(FROM_PEER_CM_ID, std::array<std::uint8_t, 3>{TP_CM_CTS, 3, 1}, START_NS + MS, sink);
  CHECK(sut.counters().framesIgnored == 5);

  // Not ours at all.
  fromPeer(cts(3, 1), START_NS + MS, FROM_PEER_TO_OTHER_CM_ID);  // to another node
  fromPeer({TP_CM_RTS, 20, 0, 3, 0xFF, 0xEB, 0xFE, 0x00}, START_NS + MS);  // for our receiver
  sut.onFrame(0x1CEB2120, FrameData{1, 2, 3, 4, 5, 6, 7, 8}, START_NS + MS, sink);  // TP.DT
  sut.onFrame(0x18FECA20, FrameData{}, START_NS + MS, sink);  // DM1, not TP
  sut.onFrame(FROM_PEER_CM_ID, std::span<const std::uint8_t>{}, START_NS + MS, sink);

  CHECK(sut.counters().framesIgnored == 5);
  CHECK(sink.frames.size() == 1);
  CHECK(sink.results.empty());
  CHECK(sut.activeSessions() == 1);
}

// ---- Queue ---------------------------------------------------------------------------------

TEST_CASE_FIXTURE(VcuSender, "a second message to a busy destination waits and starts when the first ends") {
  const Bytes first = countingPayload(20);
  const Bytes second = countingPayload(30);

  REQUIRE(sendTo(PEER_ADDRESS, first, START_NS) == TpSendStatus::Started);
  REQUIRE(sendTo(PEER_ADDRESS, second, START_NS + MS, PGN_VEHICLE_ID) == TpSendStatus::Queued);
  REQUIRE(sendTo(OTHER_PEER_ADDRESS, first, START_NS + 2 * MS) == TpSendStatus::Started);
  CHECK(sut.activeSessions() == 2);
  CHECK(sut.queuedMessages() == 1);
  REQUIRE(sink.frames.size() == 2);
  CHECK(sink.frames[1] == expectedRts(TO_OTHER_CM_ID, first.size(), PGN_COMPONENT_ID));

  fromPeer(cts(3, 1), START_NS + 10 * MS);
  fromPeer(endOfMsgAck(first.size()), START_NS + 20 * MS);

  // The EndOfMsgAck's call starts the queued message.
  REQUIRE(sink.frames.size() == 6);
  CHECK(sink.frames[5] == expectedRts(TO_PEER_CM_ID, second.size(), PGN_VEHICLE_ID));
  CHECK(sut.queuedMessages() == 0);
  CHECK(sut.activeSessions() == 2);
  CHECK(sut.counters().messagesStartedFromQueue == 1);

  fromPeer(cts(5, 1, PGN_VEHICLE_ID), START_NS + 30 * MS);
  REQUIRE(sink.frames.size() == 11);
  CHECK(sink.frames[10] == expectedPacket(TO_PEER_DT_ID, second, 5));
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuSender, "a queued message also starts when the running one times out") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS, PGN_VEHICLE_ID) == TpSendStatus::Queued);

  sut.poll(START_NS + TP_T3_NS, sink);

  REQUIRE(sink.frames.size() == 3);
  CHECK(sink.frames[1] == expectedAbort(TO_PEER_CM_ID, TpAbortReason::Timeout));
  CHECK(sink.frames[2] == expectedRts(TO_PEER_CM_ID, payload.size(), PGN_VEHICLE_ID));
  CHECK(sut.nextDeadlineNs() == START_NS + 2 * TP_T3_NS);
}

TEST_CASE_FIXTURE(VcuSender, "only one BAM runs at a time: the next starts at the last packet of the first") {
  const Bytes dm1 = countingPayload(9);
  const Bytes dm2 = countingPayload(14);
  REQUIRE(sendTo(GLOBAL_ADDRESS, dm1, START_NS, PGN_DM1) == TpSendStatus::Started);
  REQUIRE(sendTo(GLOBAL_ADDRESS, dm2, START_NS + MS, PGN_DM2) == TpSendStatus::Queued);
  // RTS/CTS runs beside the BAM.
  REQUIRE(sendTo(PEER_ADDRESS, dm1, START_NS + 2 * MS) == TpSendStatus::Started);

  sut.poll(START_NS + BAM_GAP_NS, sink);
  CHECK(sut.queuedMessages() == 1);
  sut.poll(START_NS + 2 * BAM_GAP_NS, sink);

  REQUIRE(sink.results.size() == 1);
  CHECK(sink.results[0] == result(PGN_DM1, GLOBAL_ADDRESS, TpSendOutcome::Completed));
  CHECK(sink.frames.back() == expectedBam(dm2.size(), PGN_DM2));
  CHECK(sut.queuedMessages() == 0);
  CHECK(sut.nextDeadlineNs() == START_NS + 3 * BAM_GAP_NS);
}

TEST_CASE("messages to free destinations wait while maxSessions sessions run") {
  TpSenderConfig config = VCU_CONFIG;
  config.maxSessions = 1;
  TpSender sut(config);
  RecordingSink sink;
  const Bytes payload = countingPayload(20);
  REQUIRE(sut.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
          TpSendStatus::Started);
  REQUIRE(sut.send(PGN_COMPONENT_ID, OTHER_PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
          TpSendStatus::Queued);

  sut.onFrame(FROM_PEER_CM_ID, abortFrom(TpAbortReason::ResourcesNeeded), START_NS + MS, sink);

  CHECK(sink.frames.back() == expectedRts(TO_OTHER_CM_ID, payload.size(), PGN_COMPONENT_ID));
  CHECK(sut.activeSessions() == 1);
}

TEST_CASE("a full queue refuses the message, counts it and keeps what it holds") {
  TpSenderConfig config = VCU_CONFIG;
  config.queueCapacity = 2;
  TpSender sut(config);
  RecordingSink sink;
  const Bytes payload = countingPayload(20);
  REQUIRE(sut.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
          TpSendStatus::Started);
  REQUIRE(sut.send(PGN_VEHICLE_ID, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
          TpSendStatus::Queued);
  REQUIRE(sut.send(PGN_DM2, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) == TpSendStatus::Queued);

  CHECK(sut.send(PGN_DM1, PEER_ADDRESS, TP_PRIORITY, payload, START_NS, sink) ==
        TpSendStatus::RefusedQueueFull);

  CHECK(sut.counters().refusedQueueFull == 1);
  CHECK(sut.queuedMessages() == 2);
  CHECK(sink.frames.size() == 1);
  CHECK(sink.results.empty());

  // FIFO per destination: the older queued message goes first.
  sut.onFrame(FROM_PEER_CM_ID, abortFrom(TpAbortReason::ResourcesNeeded), START_NS + MS, sink);
  CHECK(sink.frames.back() == expectedRts(TO_PEER_CM_ID, payload.size(), PGN_VEHICLE_ID));
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuSender, "invalid messages are refused, counted and leave nothing behind") {
  const Bytes payload = countingPayload(20);
  CHECK(sendTo(PEER_ADDRESS, countingPayload(8), START_NS) == TpSendStatus::RefusedSize);
  CHECK(sendTo(PEER_ADDRESS, countingPayload(TP_MAX_MESSAGE_SIZE + 1), START_NS) ==
        TpSendStatus::RefusedSize);
  CHECK(sendTo(PEER_ADDRESS, payload, START_NS, PGN_MASK + 1) == TpSendStatus::RefusedPgn);
  CHECK(sut.send(PGN_COMPONENT_ID, PEER_ADDRESS, 8, payload, START_NS, sink) ==
        TpSendStatus::RefusedPriority);
  CHECK(sendTo(NULL_ADDRESS, payload, START_NS) == TpSendStatus::RefusedDestination);
  CHECK(sendTo(VCU_ADDRESS, payload, START_NS) == TpSendStatus::RefusedDestination);

  CHECK(sut.counters().refusedInvalid == 6);
  CHECK(sink.frames.empty());
  CHECK(sink.results.empty());
  CHECK(sut.activeSessions() == 0);
}

// ---- Own address ---------------------------------------------------------------------------

TEST_CASE_FIXTURE(VcuSender, "an address change ends running sessions silently and starts queued ones from the new address") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS, PGN_VEHICLE_ID) == TpSendStatus::Queued);
  REQUIRE(sendTo(GLOBAL_ADDRESS, payload, START_NS, PGN_DM1) == TpSendStatus::Started);
  fromPeer(cts(1, 1), START_NS + MS);
  const std::size_t framesBefore = sink.frames.size();

  sut.setOwnAddress(NEW_VCU_ADDRESS, START_NS + 2 * MS, sink);

  CHECK(sut.ownAddress() == NEW_VCU_ADDRESS);
  REQUIRE(sink.results.size() == 2);
  CHECK(sink.results[0].outcome == TpSendOutcome::AddressChanged);
  CHECK(sink.results[1].outcome == TpSendOutcome::AddressChanged);
  REQUIRE(sink.frames.size() == framesBefore + 1);  // no Abort from the old address
  CHECK(sink.frames.back() == expectedRts(NEW_TO_PEER_CM_ID, payload.size(), PGN_VEHICLE_ID));
  CHECK(sut.counters().sessionsEndedByAddressChange == 2);

  // CTS to the old address: not ours any more; to the new one: served.
  fromPeer(cts(3, 1, PGN_VEHICLE_ID), START_NS + 3 * MS);
  CHECK(sink.frames.size() == framesBefore + 1);
  fromPeer(cts(3, 1, PGN_VEHICLE_ID), START_NS + 3 * MS, FROM_PEER_TO_NEW_CM_ID);
  REQUIRE(sink.frames.size() == framesBefore + 4);
  CHECK(sink.frames.back().canId == 0x1CEB2081u);
  checkCountersBalance(sut);
}

TEST_CASE_FIXTURE(VcuSender, "losing the address (NULL) ends queued messages too and refuses new ones") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS, PGN_VEHICLE_ID) == TpSendStatus::Queued);

  sut.setOwnAddress(NULL_ADDRESS, START_NS + MS, sink);

  REQUIRE(sink.results.size() == 2);
  CHECK(sink.results[1] == result(PGN_VEHICLE_ID, PEER_ADDRESS, TpSendOutcome::AddressChanged));
  CHECK(sink.frames.size() == 1);
  CHECK(sut.queuedMessages() == 0);
  CHECK_FALSE(sut.nextDeadlineNs().has_value());
  CHECK(sendTo(PEER_ADDRESS, payload, START_NS + 2 * MS) == TpSendStatus::RefusedNoAddress);
  CHECK(sut.counters().refusedNoAddress == 1);
  CHECK(sut.counters().queuedDroppedByAddressChange == 1);
  checkCountersBalance(sut);

  sut.setOwnAddress(NEW_VCU_ADDRESS, START_NS + 3 * MS, sink);  // claimed again
  CHECK(sendTo(PEER_ADDRESS, payload, START_NS + 4 * MS) == TpSendStatus::Started);
  CHECK(sink.frames.back() == expectedRts(NEW_TO_PEER_CM_ID, payload.size(), PGN_COMPONENT_ID));
}

TEST_CASE_FIXTURE(VcuSender, "setting the same address again changes nothing") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  sut.setOwnAddress(VCU_ADDRESS, START_NS + MS, sink);
  CHECK(sut.activeSessions() == 1);
  CHECK(sink.results.empty());
}

TEST_CASE("a sender without an address refuses every message") {
  TpSender sut(TpSenderConfig{});
  RecordingSink sink;
  CHECK(sut.send(PGN_DM1, GLOBAL_ADDRESS, TP_PRIORITY, countingPayload(20), START_NS, sink) ==
        TpSendStatus::RefusedNoAddress);
  CHECK(sink.frames.empty());
}
