#pragma once
// Shared by the TpSender tests (issue 24): printers, addresses, frame builders, a recording
// sink and the fixture, in namespace tp_sender_test.

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

namespace tp_sender_test {

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
inline Bytes countingPayload(std::size_t size) {
  Bytes payload(size);
  for (std::size_t i = 0; i < size; ++i) payload[i] = static_cast<std::uint8_t>(i + 1);
  return payload;
}

constexpr std::uint8_t byteAt(std::size_t value, unsigned index) {
  return static_cast<std::uint8_t>((value >> (8 * index)) & 0xFF);
}
inline std::uint8_t packetsOf(std::size_t size) {
  return static_cast<std::uint8_t>((size + TP_BYTES_PER_PACKET - 1) / TP_BYTES_PER_PACKET);
}

inline FrameData cts(std::uint8_t count, std::uint8_t next, std::uint32_t pgn = PGN_COMPONENT_ID) {
  return {TP_CM_CTS, count, next, 0xFF, 0xFF, byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)};
}
inline FrameData endOfMsgAck(std::size_t size, std::uint32_t pgn = PGN_COMPONENT_ID) {
  return {TP_CM_END_OF_MSG_ACK, byteAt(size, 0), byteAt(size, 1), packetsOf(size), 0xFF,
          byteAt(pgn, 0),       byteAt(pgn, 1),  byteAt(pgn, 2)};
}
inline FrameData abortFrom(TpAbortReason reason, std::uint32_t pgn = PGN_COMPONENT_ID,
                    std::uint8_t roleByte = ROLE_RESPONDER_BYTE) {
  return {TP_CM_ABORT, static_cast<std::uint8_t>(reason), roleByte, 0xFF, 0xFF,
          byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)};
}

inline TpFrame frameOf(std::uint32_t canId, const FrameData& data) {
  return TpFrame{canId, static_cast<std::uint8_t>(TP_FRAME_LENGTH), data};
}
inline TpFrame expectedRts(std::uint32_t canId, std::size_t size, std::uint32_t pgn,
                    std::uint8_t limit = TP_NO_PACKET_LIMIT) {
  return frameOf(canId, {TP_CM_RTS, byteAt(size, 0), byteAt(size, 1), packetsOf(size), limit,
                         byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)});
}
inline TpFrame expectedBam(std::size_t size, std::uint32_t pgn) {
  return frameOf(BAM_CM_ID, {TP_CM_BAM, byteAt(size, 0), byteAt(size, 1), packetsOf(size), 0xFF,
                             byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)});
}
// Our Abort: byte 2 reserved bits 1, role 00 = originator.
inline TpFrame expectedAbort(std::uint32_t canId, TpAbortReason reason, std::uint32_t pgn = PGN_COMPONENT_ID) {
  return frameOf(canId, {TP_CM_ABORT, static_cast<std::uint8_t>(reason), ROLE_ORIGINATOR_BYTE, 0xFF,
                         0xFF, byteAt(pgn, 0), byteAt(pgn, 1), byteAt(pgn, 2)});
}
// Packet `sequence` (1-based) of `payload`, the last one padded with 0xFF.
inline TpFrame expectedPacket(std::uint32_t canId, const Bytes& payload, std::size_t sequence) {
  FrameData data;
  data.fill(0xFF);
  data[0] = static_cast<std::uint8_t>(sequence);
  const std::size_t offset = (sequence - 1) * TP_BYTES_PER_PACKET;
  for (std::size_t i = 0; i < TP_BYTES_PER_PACKET && offset + i < payload.size(); ++i) {
    data[1 + i] = payload[offset + i];
  }
  return frameOf(canId, data);
}

inline TpSendResult result(std::uint32_t pgn, std::uint8_t destination, TpSendOutcome outcome,
                    TpAbortReason reason = TpAbortReason::None) {
  return TpSendResult{pgn, destination, outcome, reason};
}

inline void checkCountersBalance(const TpSender& sender) {
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

}  // namespace tp_sender_test
