// libFuzzer target: LCM message decoding. The first byte picks the type, the rest is the
// message: 0 command_request_t and 1 command_ack_t through ipc::decodeCommandRequest /
// decodeCommandAck (what a command socket does with each datagram), 2..9 the event types
// (fsm_transition_t, fault_event_t, log_record_t, heartbeat_t, signal_snapshot_t), 7 stats_t,
// 8 tx_schedule_t, 9 j1939_network_t and 10 j1939_dm1_t through
// their lcm-gen decoders as EventBus does (shared/ipc/src/event_bus.cpp, decodeOne).
// Invariants: no crash, leak or UB; a decoded command encodes and decodes to itself.
//
// Findings (docs/testing.md, "Fuzzing"), fixed in shared/ipc/src/event_bus.cpp by a layout
// walk before lcm-gen's decoders and kept in tests/data/fuzz/fuzz_lcm/regressions/: a
// heartbeat or snapshot count that made every subscriber allocate up to 64 GiB, and a string
// length of INT32_MIN that made the decoders copy 2 GiB (SIGSEGV).
#include "fuzz_require.hpp"

#include <cstdlib>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu_lcm/fault_event_t.hpp"
#include "openvcu_lcm/fsm_transition_t.hpp"
#include "openvcu_lcm/heartbeat_t.hpp"
#include "openvcu_lcm/log_record_t.hpp"
#include "openvcu_lcm/signal_snapshot_t.hpp"
#include "openvcu_lcm/stats_t.hpp"
#include "openvcu_lcm/tx_schedule_t.hpp"
#include "openvcu_lcm/j1939_dm1_t.hpp"
#include "openvcu_lcm/j1939_network_t.hpp"

using namespace openvcu;

namespace {

bool hasNul(const std::uint8_t* data, std::size_t size) {
  return std::memchr(data, 0, size) != nullptr && size > 0;
}

bool anyNul(std::initializer_list<const std::string*> texts) {
  for (const std::string* text : texts) {
    if (text->find('\0') != std::string::npos) return true;
  }
  return false;
}

template <typename LcmType>
void decodeEvent(ipc::EventKind kind, const std::uint8_t* data, std::size_t size) {
  if (!ipc::fitsEventLayout(kind, data, size)) return;  // what EventBus checks first
  try {  // as EventBus's decodeOne: std::length_error / bad_alloc count as "does not decode"
    LcmType decoded;
    if (decoded.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) return;
    const int encodedSize = decoded.getEncodedSize();
    std::vector<std::uint8_t> buffer(static_cast<std::size_t>(encodedSize));
    // Finding 3: a decoded string may hold NUL bytes, which encode() drops (it writes
    // strlen()), so it writes fewer bytes than getEncodedSize() promised.
    const int written = decoded.encode(buffer.data(), 0, encodedSize);
    fuzz::require(written == encodedSize || (written > 0 && written < encodedSize && hasNul(data, size)));
  } catch (const std::exception&) {
  }
}

bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

void checkRequest(const std::uint8_t* data, std::size_t size) {
  const auto maybeRequest = ipc::decodeCommandRequest(data, size);
  if (!maybeRequest || maybeRequest->timestampNs == 0) return;  // 0 is replaced by "now" when encoding
  if (anyNul({&maybeRequest->issuer, &maybeRequest->key, &maybeRequest->text})) return;  // finding 3
  const std::vector<std::uint8_t> encoded = ipc::encodeCommandRequest(*maybeRequest);
  const auto again = ipc::decodeCommandRequest(encoded.data(), encoded.size());
  fuzz::require(again.has_value());
  fuzz::require(again->timestampNs == maybeRequest->timestampNs && again->requestId == maybeRequest->requestId &&
                again->issuer == maybeRequest->issuer && again->kind == maybeRequest->kind &&
                again->key == maybeRequest->key && sameBits(again->value, maybeRequest->value) &&
                again->text == maybeRequest->text && again->deadlineNs == maybeRequest->deadlineNs);
}

void checkAck(const std::uint8_t* data, std::size_t size) {
  const auto maybeAck = ipc::decodeCommandAck(data, size);
  if (!maybeAck || maybeAck->timestampNs == 0) return;
  if (anyNul({&maybeAck->issuer, &maybeAck->responder, &maybeAck->reason})) return;  // finding 3
  const std::vector<std::uint8_t> encoded = ipc::encodeCommandAck(*maybeAck);
  const auto again = ipc::decodeCommandAck(encoded.data(), encoded.size());
  fuzz::require(again.has_value() && *again == *maybeAck);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || size > ipc::MAX_COMMAND_BYTES * 8) return 0;
  const std::uint8_t type = data[0] % 11;  // the regressions' first bytes (0, 2, 5) pick the same types as with % 10
  const std::uint8_t* message = data + 1;
  const std::size_t messageSize = size - 1;
  switch (type) {
    case 0: checkRequest(message, messageSize); break;
    case 1: checkAck(message, messageSize); break;
    case 2: decodeEvent<openvcu_lcm::fsm_transition_t>(ipc::EventKind::Fsm, message, messageSize); break;
    case 3: decodeEvent<openvcu_lcm::fault_event_t>(ipc::EventKind::Fault, message, messageSize); break;
    case 4: decodeEvent<openvcu_lcm::log_record_t>(ipc::EventKind::Log, message, messageSize); break;
    case 5: decodeEvent<openvcu_lcm::heartbeat_t>(ipc::EventKind::Heartbeat, message, messageSize); break;
    case 6: decodeEvent<openvcu_lcm::signal_snapshot_t>(ipc::EventKind::Snapshot, message, messageSize); break;
    case 7: decodeEvent<openvcu_lcm::stats_t>(ipc::EventKind::Stats, message, messageSize); break;
    case 8: decodeEvent<openvcu_lcm::tx_schedule_t>(ipc::EventKind::Schedule, message, messageSize); break;
    case 9: decodeEvent<openvcu_lcm::j1939_network_t>(ipc::EventKind::J1939, message, messageSize); break;
    default: decodeEvent<openvcu_lcm::j1939_dm1_t>(ipc::EventKind::Dm1, message, messageSize); break;
  }
  return 0;
}
