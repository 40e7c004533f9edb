// TpSender (J1939-21 transport originator) with a set clock, issue 24: BAM and RTS/CTS.
#include "transport_sender_support.hpp"

using namespace tp_sender_test;

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
