#pragma once
// The iceoryx half of the IPC contract (STYLE.md 10): the sample types and the topic
// names. This header is the only place they are defined; services include it (and
// frame_stream.hpp, request_stream.hpp), never iceoryx.
//
// Four topics per bus, as iceoryx service descriptions (service, instance, event):
//   ("openvcu", "<instance>.<bus>", "rx")    frames received from the bus    (can-rx publishes)
//   ("openvcu", "<instance>.<bus>", "tx")    frames actually sent on the bus (can-tx publishes)
//   ("openvcu", "<instance>.<bus>", "send")  one-shot send requests          (can-tx subscribes)
//   ("openvcu", "<instance>.<bus>", "req")   J1939 requests for this node     (can-rx -> can-tx)
//   ("openvcu", "<instance>.<bus>", "net")   J1939 network management frames  (can-rx -> can-tx):
//        every Address Claimed (PGN 0xEE00) and the TP.CM frames to this node that answer a
//        transfer it sends (CTS, EndOfMsgAck, Abort)
// and one per simulated bus (the sim:NAME link itself, shared by every stack instance):
//   ("openvcu", "sim.<NAME>", "wire")        every frame on the simulated bus (sim links)
//   e.g. FrameTopic{"hhea", "vehicle", FrameStream::Received} -> ("openvcu", "hhea.vehicle", "rx")
//
// "req" carries RequestSample (32 bytes: the parsed request, not the frame); every other
// topic carries FrameSample, 120 bytes. Both are plain data living in iceoryx shared memory
// (STYLE.md 9). Changing a layout is a contract change: bump its *_VERSION and update
// config/iceoryx/roudi.toml if a size grows past the mempool's 128 bytes.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>

#include "openvcu/can/frame.hpp"

namespace openvcu::ipc {

/// FNV-1a, 32 bit: the stable hash used for bus names and sender ids.
/// fnv1a32("vehicle") is the same in every process and every build.
constexpr std::uint32_t fnv1a32(std::string_view text) noexcept {
  std::uint32_t hash = 0x811C9DC5u;  // FNV offset basis
  for (const char c : text) {
    hash ^= static_cast<std::uint8_t>(c);
    hash *= 0x01000193u;  // FNV prime
  }
  return hash;
}

inline constexpr std::uint32_t FRAME_SAMPLE_VERSION = 1;

/// One CAN frame on a frame stream.
///
/// Contract: the producer fills `frame`, `busIndex` and, when known, `hardwareNs` and
/// `monotonicNs`. FramePublisher::publish stamps `sequence`, `senderId` and `busNameHash`,
/// and `monotonicNs` when it was left 0. Consumers treat every field as read-only.
/// A gap in `sequence` from one `senderId` means frames were dropped (a subscriber queue
/// overflowed); `sequence` starts at 1 for every publisher.
struct FrameSample {
  std::uint64_t sequence{};     ///< per publisher, 1, 2, 3, ... (stamped)
  std::int64_t monotonicNs{};   ///< CLOCK_MONOTONIC ns when the frame was received / sent / requested
  std::int64_t hardwareNs{};    ///< kernel or hardware timestamp (CLOCK_REALTIME ns); 0 when unknown
  std::uint32_t senderId{};     ///< identifies the publisher (FramePublisher::senderId(), stamped)
  std::uint32_t busNameHash{};  ///< fnv1a32(bus name) of the topic (stamped)
  std::uint16_t busIndex{};     ///< position of the bus in the configuration
  std::uint16_t reserved0{};    ///< zero
  std::uint32_t reserved1{};    ///< zero
  can::Frame frame{};           ///< frame.timestampNs mirrors hardwareNs when the link has one
};
static_assert(std::is_trivially_copyable_v<FrameSample>);
static_assert(std::is_standard_layout_v<FrameSample>);
static_assert(sizeof(FrameSample) == 120, "layout change: bump FRAME_SAMPLE_VERSION, check roudi.toml");
static_assert(alignof(FrameSample) == 8);
static_assert(offsetof(FrameSample, frame) == 40);

/// A J1939 Request for this node (PGN 59904, 0xEA00), as can-rx parsed it
/// (j1939::parseRequest), on the "req" topic for can-tx to answer.
///
/// Contract: can-rx fills `bus`, `pgn`, `requester`, `global` and `monotonicNs` (when the
/// frame was received); RequestPublisher::publish stamps `sequence`, `senderId` and
/// `busNameHash` like FramePublisher. Consumers treat every field as read-only.
struct RequestSample {
  std::uint64_t sequence{};     ///< per publisher, 1, 2, 3, ... (stamped)
  std::int64_t monotonicNs{};   ///< CLOCK_MONOTONIC ns when the request frame was received
  std::uint32_t senderId{};     ///< identifies the publisher (stamped)
  std::uint32_t busNameHash{};  ///< fnv1a32(bus name) of the topic (stamped)
  std::uint32_t pgn{};          ///< the requested PGN (18 bits)
  std::uint16_t bus{};          ///< position of the bus in the configuration
  std::uint8_t requester{};     ///< the requester's J1939 source address
  bool global{};                ///< sent to the global address 0xFF (255): answered, never NACKed
};
inline constexpr std::uint32_t REQUEST_SAMPLE_VERSION = 1;
static_assert(std::is_trivially_copyable_v<RequestSample>);
static_assert(std::is_standard_layout_v<RequestSample>);
static_assert(sizeof(RequestSample) == 32, "layout change: bump REQUEST_SAMPLE_VERSION");
static_assert(alignof(RequestSample) == 8);
static_assert(offsetof(RequestSample, pgn) == 24);

/// Which of the streams of a bus.
enum class FrameStream : std::uint8_t {
  Received,     ///< "rx": frames read from the bus
  Sent,         ///< "tx": frames written to the bus
  SendRequest,  ///< "send": one-shot frames others ask can-tx to send
  Request,      ///< "req": J1939 Requests (PGN 59904) for this node, as RequestSample, for can-tx
  SimWire,      ///< "wire": the simulated bus itself (FrameTopic{"sim", NAME, SimWire})
  Network,      ///< "net": J1939 address claims and TP answers to this node's transfers, for can-tx
};

inline constexpr std::string_view FRAME_TOPIC_SERVICE = "openvcu";

/// "rx", "tx", "send", "req", "wire" or "net".
constexpr std::string_view eventName(FrameStream stream) noexcept {
  switch (stream) {
    case FrameStream::Received:
      return "rx";
    case FrameStream::Sent:
      return "tx";
    case FrameStream::SendRequest:
      return "send";
    case FrameStream::Request:
      return "req";
    case FrameStream::SimWire:
      return "wire";
    case FrameStream::Network:
      return "net";
  }
  return "rx";
}

/// Names one stream of one bus of one stack instance.
struct FrameTopic {
  std::string instance;  ///< stack instance, e.g. "hhea" ([A-Za-z0-9_-], 1..32 chars)
  std::string bus;       ///< logical bus name from the configuration, e.g. "vehicle" (same rules)
  FrameStream stream{FrameStream::Received};

  /// iceoryx instance string: "<instance>.<bus>".
  [[nodiscard]] std::string instanceString() const { return instance + "." + bus; }
  /// "openvcu/hhea.vehicle/rx", for messages and logs.
  [[nodiscard]] std::string toString() const {
    return std::string(FRAME_TOPIC_SERVICE) + "/" + instanceString() + "/" + std::string(eventName(stream));
  }
};

/// true when `name` is usable as an instance or bus name: 1..32 characters of
/// [A-Za-z0-9_-]. The same rule keeps LCM channel names and iceoryx ids valid.
bool isValidName(std::string_view name) noexcept;

}  // namespace openvcu::ipc
