// TpSender (J1939-21 transport originator) with a set clock, issue 24: the queue, the
// refusals and changes of our own address.
#include "transport_sender_support.hpp"

using namespace tp_sender_test;

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

TEST_CASE_FIXTURE(VcuSender, "a queued message to our new address ends instead of going to ourselves") {
  const Bytes payload = countingPayload(20);
  REQUIRE(sendTo(OTHER_PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  REQUIRE(sendTo(OTHER_PEER_ADDRESS, payload, START_NS, PGN_VEHICLE_ID) == TpSendStatus::Queued);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS) == TpSendStatus::Started);
  REQUIRE(sendTo(PEER_ADDRESS, payload, START_NS, PGN_VEHICLE_ID) == TpSendStatus::Queued);

  sut.setOwnAddress(PEER_ADDRESS, START_NS + MS, sink);

  // Both running sessions and the message to 0x20 end; the one to 0x30 starts from 0x20.
  REQUIRE(sink.results.size() == 3);
  CHECK(std::count(sink.results.begin(), sink.results.end(),
                   result(PGN_VEHICLE_ID, PEER_ADDRESS, TpSendOutcome::AddressChanged)) == 1);
  CHECK(sink.frames.back() == expectedRts(0x1CEC3020, payload.size(), PGN_VEHICLE_ID));
  CHECK(sut.queuedMessages() == 0);
  checkCountersBalance(sut);
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
