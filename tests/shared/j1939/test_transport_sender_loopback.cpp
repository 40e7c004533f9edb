// TpSender talking to TpReceiver over a simulated bus with a set clock, issue 24: both
// sides of J1939-21 agree and the payload arrives intact.
#include "openvcu/j1939/transport.hpp"
#include "openvcu/j1939/transport_sender.hpp"
#include "transport_sender_support.hpp"  // printers

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <deque>
#include <limits>
#include <vector>

using namespace openvcu::j1939;

namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::uint8_t VCU_ADDRESS = 0x21;     // the TpSender
constexpr std::uint8_t PEER_ADDRESS = 0x20;    // the TpReceiver
constexpr std::uint8_t THIRD_ADDRESS = 0x30;   // another originator talking to the peer
constexpr std::uint32_t PGN_COMPONENT_ID = 0xFEEB;
constexpr std::uint32_t PGN_VEHICLE_ID = 0xFEEC;
constexpr std::uint32_t PGN_DM1 = 0xFECA;
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START_NS = 1'000 * MS;
// An 8-byte extended frame takes about 0.5 ms at 250 kbit/s.
constexpr std::int64_t FRAME_TIME_NS = 500'000;
constexpr std::size_t MAX_STEPS = 100'000;  // guards against a session that never ends
constexpr std::int64_t NEVER = std::numeric_limits<std::int64_t>::max();

// Pseudo-random bytes (a fixed LCG): a shifted or repeated packet shows up as a mismatch.
Bytes randomPayload(std::size_t size, std::uint32_t seed) {
  Bytes payload(size);
  std::uint32_t state = seed;
  for (std::uint8_t& byte : payload) {
    state = state * 1'664'525u + 1'013'904'223u;
    byte = static_cast<std::uint8_t>(state >> 24);
  }
  return payload;
}

struct BusFrame {
  TpFrame frame;
  bool fromSender{};
};

struct ReceivedMessage {
  std::uint32_t pgn{};
  std::uint8_t source{};
  bool broadcast{};
  Bytes data;
};

/// One CAN bus: every frame either side sends reaches the other side, in order, one
/// FRAME_TIME_NS after the previous one. Deadlines are served by poll() in between.
struct Bus final : TpSendSink, TpSink {
  TpSender sender;
  TpReceiver receiver;
  std::int64_t nowNs{START_NS};
  std::deque<BusFrame> pending;
  std::vector<TpFrame> log;  // everything that went on the bus
  std::vector<TpSendResult> results;
  std::vector<ReceivedMessage> messages;
  std::vector<TpEvent> events;

  Bus(const TpSenderConfig& senderConfig, const TpReceiverConfig& receiverConfig)
      : sender(senderConfig), receiver(receiverConfig) {}

  // Sender side.
  void send(const TpFrame& frame) noexcept override { post(frame); }
  void finished(const TpSendResult& result) noexcept override { results.push_back(result); }
  // Receiver side (its send() is the one above: TpSink::send and TpSendSink::send share
  // a signature, so frames of both sides are told apart by their source address).
  void completed(const TpMessage& message) noexcept override {
    messages.push_back({message.pgn, message.source, message.broadcast,
                        Bytes(message.data.begin(), message.data.end())});
  }
  void event(const TpEvent& event) noexcept override { events.push_back(event); }

  void post(const TpFrame& frame) noexcept {
    const bool fromSender = (frame.canId & 0xFFu) == sender.ownAddress();
    pending.push_back({frame, fromSender});
    log.push_back(frame);
  }

  void deliver(const BusFrame& busFrame) {
    const std::span<const std::uint8_t> data(busFrame.frame.data.data(), busFrame.frame.length);
    if (busFrame.fromSender) {
      receiver.onFrame(busFrame.frame.canId, data, nowNs, *this);
    } else {
      sender.onFrame(busFrame.frame.canId, data, nowNs, *this);
    }
  }

  /// Runs until neither side has a frame to deliver nor a deadline to serve.
  void run() {
    for (std::size_t step = 0; step < MAX_STEPS; ++step) {
      if (!pending.empty()) {
        const BusFrame busFrame = pending.front();
        pending.pop_front();
        nowNs += FRAME_TIME_NS;
        deliver(busFrame);
        continue;
      }
      const auto senderDeadline = sender.nextDeadlineNs();
      const auto receiverDeadline = receiver.nextDeadlineNs();
      if (!senderDeadline && !receiverDeadline) return;
      const std::int64_t next = std::min(senderDeadline.value_or(NEVER),
                                         receiverDeadline.value_or(NEVER));
      nowNs = std::max(nowNs, next);
      sender.poll(nowNs, *this);
      receiver.poll(nowNs, *this);
    }
    FAIL("the bus did not go idle");
  }

  [[nodiscard]] std::size_t abortsOnBus() const {
    return static_cast<std::size_t>(std::count_if(log.begin(), log.end(), [](const TpFrame& frame) {
      return ((frame.canId >> 16) & 0xFFu) == 0xECu && frame.data[0] == TP_CM_ABORT;
    }));
  }
};

TpSenderConfig senderConfig() {
  return TpSenderConfig{.ownAddress = VCU_ADDRESS};
}
TpReceiverConfig receiverConfig(std::uint8_t window = TP_NO_PACKET_LIMIT, std::size_t sessions = 8) {
  return TpReceiverConfig{PEER_ADDRESS, window, sessions, 4};
}

}  // namespace

TEST_CASE("loopback: BAM of 9, 20 and 1785 bytes arrives intact at the receiver") {
  for (const std::size_t size : {std::size_t{9}, std::size_t{20}, TP_MAX_MESSAGE_SIZE}) {
    CAPTURE(size);
    Bus bus(senderConfig(), receiverConfig());
    const Bytes payload = randomPayload(size, static_cast<std::uint32_t>(size));

    REQUIRE(bus.sender.send(PGN_DM1, GLOBAL_ADDRESS, TP_CM_PRIORITY, payload, bus.nowNs, bus) ==
            TpSendStatus::Started);
    bus.run();

    REQUIRE(bus.messages.size() == 1);
    CHECK(bus.messages[0].pgn == PGN_DM1);
    CHECK(bus.messages[0].source == VCU_ADDRESS);
    CHECK(bus.messages[0].broadcast);
    CHECK(bus.messages[0].data == payload);
    REQUIRE(bus.results.size() == 1);
    CHECK(bus.results[0].outcome == TpSendOutcome::Completed);
    CHECK(bus.receiver.counters().sessionsCompleted == 1);
    CHECK(bus.abortsOnBus() == 0);
  }
}

TEST_CASE("loopback: RTS/CTS with receive windows of 1, 3, 16 and 255 packets") {
  const Bytes payload = randomPayload(TP_MAX_MESSAGE_SIZE, 24);
  for (const std::uint8_t window : {std::uint8_t{1}, std::uint8_t{3}, std::uint8_t{16}, TP_NO_PACKET_LIMIT}) {
    CAPTURE(window);
    Bus bus(senderConfig(), receiverConfig(window));

    REQUIRE(bus.sender.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_CM_PRIORITY, payload, bus.nowNs, bus) ==
            TpSendStatus::Started);
    bus.run();

    REQUIRE(bus.messages.size() == 1);
    CHECK(bus.messages[0].pgn == PGN_COMPONENT_ID);
    CHECK(bus.messages[0].source == VCU_ADDRESS);
    CHECK_FALSE(bus.messages[0].broadcast);
    CHECK(bus.messages[0].data == payload);
    REQUIRE(bus.results.size() == 1);
    CHECK(bus.results[0] ==
          TpSendResult{PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::Completed, TpAbortReason::None});
    CHECK(bus.abortsOnBus() == 0);
    // RTS + 255 packets + EndOfMsgAck + one CTS per window.
    const std::size_t windows = (TP_MAX_PACKETS + window - 1) / window;
    CHECK(bus.log.size() == 1 + TP_MAX_PACKETS + 1 + windows);
  }
}

TEST_CASE("loopback: the sender's own limit per CTS and a packet gap are honoured by the receiver") {
  TpSenderConfig config = senderConfig();
  config.maxPacketsPerCts = 4;
  config.rtsPacketGapNs = 20 * MS;
  Bus bus(config, receiverConfig());
  const Bytes payload = randomPayload(100, 7);  // 15 packets -> 4 windows

  REQUIRE(bus.sender.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_CM_PRIORITY, payload, bus.nowNs, bus) ==
          TpSendStatus::Started);
  bus.run();

  REQUIRE(bus.messages.size() == 1);
  CHECK(bus.messages[0].data == payload);
  CHECK(bus.log.size() == 1 + 15 + 1 + 4);
  CHECK(bus.abortsOnBus() == 0);
}

TEST_CASE("loopback: messages queued for one destination arrive one after the other, in order") {
  Bus bus(senderConfig(), receiverConfig(2));
  const Bytes first = randomPayload(50, 1);
  const Bytes second = randomPayload(300, 2);
  const Bytes broadcast = randomPayload(40, 3);

  REQUIRE(bus.sender.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_CM_PRIORITY, first, bus.nowNs, bus) ==
          TpSendStatus::Started);
  REQUIRE(bus.sender.send(PGN_VEHICLE_ID, PEER_ADDRESS, TP_CM_PRIORITY, second, bus.nowNs, bus) ==
          TpSendStatus::Queued);
  REQUIRE(bus.sender.send(PGN_DM1, GLOBAL_ADDRESS, TP_CM_PRIORITY, broadcast, bus.nowNs, bus) ==
          TpSendStatus::Started);
  bus.run();

  REQUIRE(bus.messages.size() == 3);
  const auto directed = std::find_if(bus.messages.begin(), bus.messages.end(),
                                     [](const ReceivedMessage& message) { return !message.broadcast; });
  REQUIRE(directed != bus.messages.end());
  CHECK(directed->data == first);
  const auto later = std::find_if(directed + 1, bus.messages.end(),
                                  [](const ReceivedMessage& message) { return !message.broadcast; });
  REQUIRE(later != bus.messages.end());
  CHECK(later->data == second);
  CHECK(bus.sender.counters().sessionsCompleted == 3);
  CHECK(bus.abortsOnBus() == 0);
}

TEST_CASE("loopback: a busy receiver holds our session with CTS(0) and serves it when a buffer frees") {
  // The receiver has one buffer, taken by a third node's transfer; ours is held.
  Bus bus(senderConfig(), receiverConfig(TP_NO_PACKET_LIMIT, 1));
  constexpr std::uint32_t THIRD_RTS_ID = 0x1CEC2030;  // TP.CM from 0x30 to the peer
  constexpr std::uint32_t THIRD_DT_ID = 0x1CEB2030;
  const std::array<std::uint8_t, 8> thirdRts{TP_CM_RTS, 9, 0, 2, 0xFF, 0x00, 0xEF, 0x00};
  bus.receiver.onFrame(THIRD_RTS_ID, thirdRts, bus.nowNs, bus);
  bus.pending.clear();  // its CTS goes to 0x30, not to us
  const Bytes payload = randomPayload(200, 5);

  REQUIRE(bus.sender.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_CM_PRIORITY, payload, bus.nowNs, bus) ==
          TpSendStatus::Started);
  // Deliver our RTS and the hold answers for a while (Th repeats stay inside T4), then
  // complete the third node's transfer about 1 s later.
  const std::int64_t thirdPacketsNs = bus.nowNs + 1000 * MS;
  while (bus.nowNs < thirdPacketsNs) {
    if (!bus.pending.empty()) {
      const BusFrame busFrame = bus.pending.front();
      bus.pending.pop_front();
      bus.nowNs += FRAME_TIME_NS;
      bus.deliver(busFrame);
      continue;
    }
    bus.nowNs = std::min(thirdPacketsNs, std::min(bus.sender.nextDeadlineNs().value_or(NEVER),
                                                  bus.receiver.nextDeadlineNs().value_or(NEVER)));
    bus.sender.poll(bus.nowNs, bus);
    bus.receiver.poll(bus.nowNs, bus);
  }
  CHECK(bus.sender.counters().holdsReceived >= 2);
  CHECK(bus.results.empty());
  const std::array<std::uint8_t, 8> packet1{1, 1, 2, 3, 4, 5, 6, 7};
  const std::array<std::uint8_t, 8> packet2{2, 8, 9, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  bus.receiver.onFrame(THIRD_DT_ID, packet1, bus.nowNs, bus);
  bus.receiver.onFrame(THIRD_DT_ID, packet2, bus.nowNs + MS, bus);
  bus.nowNs += MS;
  // The receiver's EndOfMsgAck to 0x30 and then its CTS to us are on the bus now.
  bus.run();

  REQUIRE(bus.messages.size() == 2);
  CHECK(bus.messages[1].source == VCU_ADDRESS);
  CHECK(bus.messages[1].data == payload);
  REQUIRE(bus.results.size() == 1);
  CHECK(bus.results[0].outcome == TpSendOutcome::Completed);
  CHECK(bus.abortsOnBus() == 0);
}

TEST_CASE("loopback: a receiver without buffers or hold places refuses and the sender reports the Abort") {
  Bus bus(senderConfig(), TpReceiverConfig{PEER_ADDRESS, TP_NO_PACKET_LIMIT, 0, 0});
  const Bytes payload = randomPayload(20, 9);

  REQUIRE(bus.sender.send(PGN_COMPONENT_ID, PEER_ADDRESS, TP_CM_PRIORITY, payload, bus.nowNs, bus) ==
          TpSendStatus::Started);
  bus.run();

  REQUIRE(bus.results.size() == 1);
  CHECK(bus.results[0] == TpSendResult{PGN_COMPONENT_ID, PEER_ADDRESS, TpSendOutcome::AbortedByPeer,
                                       TpAbortReason::AlreadyInSession});
  CHECK(bus.messages.empty());
}
