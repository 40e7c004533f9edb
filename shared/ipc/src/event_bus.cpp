#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/host_filter.hpp"

#include "openvcu/ipc/topics.hpp"

// Generated at build time from shared/ipc/lcm/*.lcm (lcm-gen -x); private to this file.
#include <openvcu_lcm/command_ack_t.hpp>
#include <openvcu_lcm/command_request_t.hpp>
#include <openvcu_lcm/fault_event_t.hpp>
#include <openvcu_lcm/fsm_transition_t.hpp>
#include <openvcu_lcm/heartbeat_t.hpp>
#include <openvcu_lcm/log_record_t.hpp>
#include <openvcu_lcm/signal_snapshot_t.hpp>
#include <openvcu_lcm/stats_t.hpp>
#include <openvcu_lcm/tx_schedule_t.hpp>
#include <openvcu_lcm/j1939_network_t.hpp>
#include <openvcu_lcm/j1939_dm1_t.hpp>

// The C API, not lcm-cpp.hpp: LCM 1.3.1's member-handler subscription crashes when built
// with -fsanitize=vptr (part of the Asan preset's -fsanitize=undefined); the C API is all we need.
#include <lcm/lcm.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <stdexcept>
#include <vector>

namespace openvcu::ipc {

// The plain enums carry the IDL's constants: a mismatch is a contract break.
static_assert(static_cast<std::int8_t>(CommandKind::SetSignal) == openvcu_lcm::command_request_t::SET_SIGNAL);
static_assert(static_cast<std::int8_t>(CommandKind::SetOverride) == openvcu_lcm::command_request_t::SET_OVERRIDE);
static_assert(static_cast<std::int8_t>(CommandKind::ClearOverride) == openvcu_lcm::command_request_t::CLEAR_OVERRIDE);
static_assert(static_cast<std::int8_t>(CommandKind::OperatorSwitch) == openvcu_lcm::command_request_t::OPERATOR_SWITCH);
static_assert(static_cast<std::int8_t>(CommandKind::FaultReset) == openvcu_lcm::command_request_t::FAULT_RESET);
static_assert(static_cast<std::int8_t>(CommandKind::ScheduleCycle) == openvcu_lcm::command_request_t::SCHEDULE_CYCLE);
static_assert(static_cast<std::int8_t>(CommandKind::ScheduleEnable) == openvcu_lcm::command_request_t::SCHEDULE_ENABLE);
static_assert(static_cast<std::int8_t>(CommandKind::ScheduleDefault) ==
              openvcu_lcm::command_request_t::SCHEDULE_DEFAULT);
static_assert(static_cast<std::int8_t>(CommandKind::FsmReload) == openvcu_lcm::command_request_t::FSM_RELOAD);
static_assert(static_cast<std::int8_t>(CommandKind::SimFault) == openvcu_lcm::command_request_t::SIM_FAULT);
static_assert(static_cast<std::int8_t>(CommandKind::ScheduleAdd) == openvcu_lcm::command_request_t::SCHEDULE_ADD);
static_assert(static_cast<std::int8_t>(FaultSeverity::Info) == openvcu_lcm::fault_event_t::INFO);
static_assert(static_cast<std::int8_t>(FaultSeverity::Warning) == openvcu_lcm::fault_event_t::WARNING);
static_assert(static_cast<std::int8_t>(FaultSeverity::Error) == openvcu_lcm::fault_event_t::ERROR);
static_assert(static_cast<std::int8_t>(FaultSeverity::Critical) == openvcu_lcm::fault_event_t::CRITICAL);
static_assert(static_cast<std::int8_t>(LogLevel::Trace) == openvcu_lcm::log_record_t::TRACE);
static_assert(static_cast<std::int8_t>(LogLevel::Debug) == openvcu_lcm::log_record_t::DEBUG);
static_assert(static_cast<std::int8_t>(LogLevel::Info) == openvcu_lcm::log_record_t::INFO);
static_assert(static_cast<std::int8_t>(LogLevel::Warning) == openvcu_lcm::log_record_t::WARNING);
static_assert(static_cast<std::int8_t>(LogLevel::Error) == openvcu_lcm::log_record_t::ERROR);
static_assert(static_cast<std::int8_t>(LogLevel::Critical) == openvcu_lcm::log_record_t::CRITICAL);

namespace {

/// Messages LCM keeps per subscription until handle() takes them; beyond, it drops
/// arrivals. LCM's default of 30 overflows when a busy service is ~10 ms late with a burst of
/// log records; 512 small events cost nothing until they are actually queued.
constexpr int SUBSCRIPTION_QUEUE_CAPACITY = 512;

std::int64_t stampOrNow(std::int64_t timestampNs) noexcept {
  return timestampNs != 0 ? timestampNs : clock::realtimeNs();
}

bool fitsArray(std::size_t size) noexcept {
  return size <= static_cast<std::size_t>(INT32_MAX);
}

// ---- plain struct <-> generated LCM type ----------------------------------------------
// toLcm returns false when the message cannot be represented (an array over 2^31 entries).

bool toLcm(const CommandRequest& in, openvcu_lcm::command_request_t& out) {
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.request_id = in.requestId;
  out.issuer = in.issuer;
  out.kind = static_cast<std::int8_t>(in.kind);
  out.key = in.key;
  out.value = in.value;
  out.text = in.text;
  out.deadline_ns = in.deadlineNs;
  return true;
}
CommandRequest fromLcm(const openvcu_lcm::command_request_t& in) {
  return CommandRequest{in.timestamp_ns, in.request_id, in.issuer, static_cast<CommandKind>(in.kind),
                        in.key,          in.value,      in.text,   in.deadline_ns};
}

bool toLcm(const CommandAck& in, openvcu_lcm::command_ack_t& out) {
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.request_id = in.requestId;
  out.issuer = in.issuer;
  out.responder = in.responder;
  out.accepted = in.accepted;
  out.reason = in.reason;
  out.owner = in.owner;
  return true;
}
CommandAck fromLcm(const openvcu_lcm::command_ack_t& in) {
  return CommandAck{in.timestamp_ns, in.request_id, in.issuer, in.responder, in.accepted != 0, in.reason,
                    in.owner != 0};
}

bool toLcm(const FsmTransition& in, openvcu_lcm::fsm_transition_t& out) {
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.from_state = in.fromState;
  out.to_state = in.toState;
  out.cause = in.cause;
  return true;
}
FsmTransition fromLcm(const openvcu_lcm::fsm_transition_t& in) {
  return FsmTransition{in.timestamp_ns, in.from_state, in.to_state, in.cause};
}

bool toLcm(const FaultEvent& in, openvcu_lcm::fault_event_t& out) {
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.name = in.name;
  out.source = in.source;
  out.severity = static_cast<std::int8_t>(in.severity);
  out.active = in.active;
  out.text = in.text;
  return true;
}
FaultEvent fromLcm(const openvcu_lcm::fault_event_t& in) {
  return FaultEvent{in.timestamp_ns, in.name, in.source, static_cast<FaultSeverity>(in.severity),
                    in.active != 0,  in.text};
}

bool toLcm(const LogRecord& in, openvcu_lcm::log_record_t& out) {
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.service = in.service;
  out.level = static_cast<std::int8_t>(in.level);
  out.text = in.text;
  return true;
}
LogRecord fromLcm(const openvcu_lcm::log_record_t& in) {
  return LogRecord{in.timestamp_ns, in.service, static_cast<LogLevel>(in.level), in.text};
}

/// Counters as the IDL's parallel arrays (heartbeat_t, stats_t), and back.
template <typename LcmType>
void countersToLcm(const std::vector<Counter>& counters, LcmType& out) {
  out.num_counters = static_cast<std::int32_t>(counters.size());
  out.counter_names.clear();
  out.counter_values.clear();
  out.counter_names.reserve(counters.size());
  out.counter_values.reserve(counters.size());
  for (const Counter& counter : counters) {
    out.counter_names.push_back(counter.name);
    out.counter_values.push_back(counter.value);
  }
}
template <typename LcmType>
std::vector<Counter> countersFromLcm(const LcmType& in) {
  std::vector<Counter> counters;
  const std::size_t count = std::min(in.counter_names.size(), in.counter_values.size());
  counters.reserve(count);
  for (std::size_t i = 0; i < count; ++i) counters.push_back(Counter{in.counter_names[i], in.counter_values[i]});
  return counters;
}

bool toLcm(const Heartbeat& in, openvcu_lcm::heartbeat_t& out) {
  if (!fitsArray(in.counters.size())) return false;
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.service = in.service;
  out.instance = in.instance;
  out.pid = in.pid;
  out.uptime_ms = in.uptimeMs;
  countersToLcm(in.counters, out);
  out.status = in.status;
  return true;
}
Heartbeat fromLcm(const openvcu_lcm::heartbeat_t& in) {
  return Heartbeat{in.timestamp_ns, in.service, in.instance, in.pid, in.uptime_ms, countersFromLcm(in), in.status};
}

bool toLcm(const Stats& in, openvcu_lcm::stats_t& out) {
  if (!fitsArray(in.counters.size())) return false;
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.service = in.service;
  out.instance = in.instance;
  out.pid = in.pid;
  out.part = in.part;
  out.parts = in.parts;
  countersToLcm(in.counters, out);
  return true;
}
Stats fromLcm(const openvcu_lcm::stats_t& in) {
  return Stats{in.timestamp_ns, in.service, in.instance, in.pid, in.part, in.parts, countersFromLcm(in)};
}

bool toLcm(const TxSchedule& in, openvcu_lcm::tx_schedule_t& out) {
  if (!fitsArray(in.entries.size())) return false;
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.service = in.service;
  out.instance = in.instance;
  out.pid = in.pid;
  out.part = in.part;
  out.parts = in.parts;
  out.num_messages = static_cast<std::int32_t>(in.entries.size());
  out.messages.clear();
  out.cycle_us.clear();
  out.enabled.clear();
  out.added.clear();
  for (const ScheduleEntry& entry : in.entries) {
    out.messages.push_back(entry.message);
    out.cycle_us.push_back(entry.cycleUs);
    out.enabled.push_back(entry.enabled ? 1 : 0);
    out.added.push_back(entry.added ? 1 : 0);
  }
  return true;
}
TxSchedule fromLcm(const openvcu_lcm::tx_schedule_t& in) {
  TxSchedule out{in.timestamp_ns, in.service, in.instance, in.pid, in.part, in.parts, {}};
  const std::size_t count = std::min({in.messages.size(), in.cycle_us.size(), in.enabled.size(), in.added.size()});
  out.entries.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    out.entries.push_back(ScheduleEntry{in.messages[i], in.cycle_us[i], in.enabled[i] != 0, in.added[i] != 0});
  }
  return out;
}

bool toLcm(const J1939Network& in, openvcu_lcm::j1939_network_t& out) {
  if (!fitsArray(in.nodes.size()) || !fitsArray(in.dtcs.size())) return false;
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.service = in.service;
  out.instance = in.instance;
  out.pid = in.pid;
  out.bus = in.bus;
  out.claim_state = static_cast<std::int8_t>(in.claimState);
  out.address = in.address;
  out.name = static_cast<std::int64_t>(in.name);
  out.num_nodes = static_cast<std::int32_t>(in.nodes.size());
  out.node_addresses.clear();
  out.node_names.clear();
  for (const J1939Node& node : in.nodes) {
    out.node_addresses.push_back(node.address);
    out.node_names.push_back(static_cast<std::int64_t>(node.name));
  }
  out.num_dtcs = static_cast<std::int32_t>(in.dtcs.size());
  out.dtc_names.clear();
  out.dtc_spns.clear();
  out.dtc_fmis.clear();
  out.dtc_occurrences.clear();
  out.dtc_active.clear();
  for (const J1939Dtc& dtc : in.dtcs) {
    out.dtc_names.push_back(dtc.name);
    out.dtc_spns.push_back(dtc.spn);
    out.dtc_fmis.push_back(static_cast<std::int8_t>(dtc.fmi));
    out.dtc_occurrences.push_back(static_cast<std::int8_t>(dtc.occurrences));
    out.dtc_active.push_back(dtc.active ? 1 : 0);
  }
  out.lamps = static_cast<std::int8_t>(in.lamps);
  return true;
}
J1939Network fromLcm(const openvcu_lcm::j1939_network_t& in) {
  J1939Network out;
  out.timestampNs = in.timestamp_ns;
  out.service = in.service;
  out.instance = in.instance;
  out.pid = in.pid;
  out.bus = in.bus;
  out.claimState = in.claim_state >= 0 && in.claim_state <= 3 ? static_cast<ClaimState>(in.claim_state) : ClaimState::Off;
  out.address = static_cast<std::uint8_t>(in.address & 0xFF);
  out.name = static_cast<std::uint64_t>(in.name);
  const std::size_t nodes = std::min(in.node_addresses.size(), in.node_names.size());
  for (std::size_t i = 0; i < nodes; ++i) {
    out.nodes.push_back(J1939Node{static_cast<std::uint8_t>(in.node_addresses[i] & 0xFF),
                                  static_cast<std::uint64_t>(in.node_names[i])});
  }
  const std::size_t dtcs = std::min({in.dtc_names.size(), in.dtc_spns.size(), in.dtc_fmis.size(),
                                     in.dtc_occurrences.size(), in.dtc_active.size()});
  for (std::size_t i = 0; i < dtcs; ++i) {
    out.dtcs.push_back(J1939Dtc{in.dtc_names[i], static_cast<std::uint32_t>(in.dtc_spns[i] & 0x7FFFF),
                                static_cast<std::uint8_t>(in.dtc_fmis[i]), static_cast<std::uint8_t>(in.dtc_occurrences[i]),
                                in.dtc_active[i] != 0});
  }
  out.lamps = static_cast<std::uint8_t>(in.lamps);
  return out;
}

bool toLcm(const NodeDm1& in, openvcu_lcm::j1939_dm1_t& out) {
  if (!fitsArray(in.dtcs.size())) return false;
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.service = in.service;
  out.instance = in.instance;
  out.bus = in.bus;
  out.node = in.node;
  out.source = in.source;
  out.lamps = static_cast<std::int8_t>(in.lamps);
  out.flash = static_cast<std::int8_t>(in.flash);
  out.num_dtcs = static_cast<std::int32_t>(in.dtcs.size());
  out.dtc_spns.clear();
  out.dtc_fmis.clear();
  out.dtc_occurrences.clear();
  out.dtc_cms.clear();
  for (const NodeDtc& dtc : in.dtcs) {
    out.dtc_spns.push_back(dtc.spn);
    out.dtc_fmis.push_back(static_cast<std::int8_t>(dtc.fmi));
    out.dtc_occurrences.push_back(static_cast<std::int8_t>(dtc.occurrences));
    out.dtc_cms.push_back(dtc.conversionMethod ? 1 : 0);
  }
  return true;
}
NodeDm1 fromLcm(const openvcu_lcm::j1939_dm1_t& in) {
  NodeDm1 out{in.timestamp_ns, in.service, in.instance, in.bus, in.node, static_cast<std::uint8_t>(in.source & 0xFF),
              static_cast<std::uint8_t>(in.lamps), static_cast<std::uint8_t>(in.flash), {}};
  const std::size_t dtcs =
      std::min({in.dtc_spns.size(), in.dtc_fmis.size(), in.dtc_occurrences.size(), in.dtc_cms.size()});
  out.dtcs.reserve(dtcs);
  for (std::size_t i = 0; i < dtcs; ++i) {
    out.dtcs.push_back(NodeDtc{static_cast<std::uint32_t>(in.dtc_spns[i] & 0x7FFFF),
                               static_cast<std::uint8_t>(in.dtc_fmis[i] & 0x1F),
                               static_cast<std::uint8_t>(in.dtc_occurrences[i] & 0x7F), in.dtc_cms[i] != 0});
  }
  return out;
}

// ---- datagram-sized parts ------------------------------------------------------------------
// LCM encodes a string as int32 length (with the NUL), the bytes and the NUL.
constexpr std::size_t encodedStringSize(const std::string& text) noexcept { return 4 + text.size() + 1; }
std::size_t encodedItemSize(const Counter& counter) noexcept { return encodedStringSize(counter.name) + 8; }
std::size_t encodedItemSize(const ScheduleEntry& entry) noexcept {
  return encodedStringSize(entry.message) + 8 + 1 + 1;
}

/// Cuts `items` into runs whose encoded message (`fixedSize` plus the items) stays within
/// `limit`; an item too large for any datagram gets a run of its own (LCM fragments it).
/// Returns the start index of each run (at least one run, possibly empty).
template <typename Item>
std::vector<std::size_t> splitPoints(const std::vector<Item>& items, std::size_t fixedSize, std::size_t limit) {
  std::vector<std::size_t> starts{0};
  std::size_t size = fixedSize;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const std::size_t item = encodedItemSize(items[i]);
    if (size + item > limit && size > fixedSize) {
      starts.push_back(i);
      size = fixedSize;
    }
    size += item;
  }
  return starts;
}

bool toLcm(const SignalSnapshot& in, openvcu_lcm::signal_snapshot_t& out) {
  if (!fitsArray(in.signals.size())) return false;
  out.timestamp_ns = stampOrNow(in.timestampNs);
  out.source = in.source;
  out.num_signals = static_cast<std::int32_t>(in.signals.size());
  out.keys.clear();
  out.values.clear();
  out.quality.clear();
  out.keys.reserve(in.signals.size());
  out.values.reserve(in.signals.size());
  out.quality.reserve(in.signals.size());
  for (const SignalValue& signal : in.signals) {
    out.keys.push_back(signal.key);
    out.values.push_back(signal.value);
    out.quality.push_back(signal.quality);
  }
  return true;
}
SignalSnapshot fromLcm(const openvcu_lcm::signal_snapshot_t& in) {
  SignalSnapshot out{in.timestamp_ns, in.source, {}};
  const std::size_t count = std::min({in.keys.size(), in.values.size(), in.quality.size()});
  out.signals.reserve(count);
  for (std::size_t i = 0; i < count; ++i) out.signals.push_back(SignalValue{in.keys[i], in.values[i], in.quality[i]});
  return out;
}

// ---- bounds check before lcm-gen's decoders ---------------------------------------------
// lcm-gen 1.3's C++ decoders trust the lengths in a message: a string length of INT32_MIN
// makes them copy ~2 GiB from the buffer (SIGSEGV), an array count makes them allocate
// count x element size before reading a byte (fuzz_lcm, docs/testing.md). Every message is
// therefore walked against its type's layout (the .lcm files) first: each string length
// in 1..rest, each count in 0..what the rest can hold. Linear in the message, no allocation.

enum class Field : std::uint8_t { I8, I32, I64, F64, Str, Count, StrArray, I64Array, F64Array, ByteArray };

bool readInt32(const std::uint8_t* data, std::size_t size, std::size_t pos, std::int32_t& out) noexcept {
  if (size - pos < 4) return false;
  const std::uint32_t raw = (static_cast<std::uint32_t>(data[pos]) << 24) | (static_cast<std::uint32_t>(data[pos + 1]) << 16) |
                            (static_cast<std::uint32_t>(data[pos + 2]) << 8) | static_cast<std::uint32_t>(data[pos + 3]);
  out = static_cast<std::int32_t>(raw);
  return true;
}

bool skipString(const std::uint8_t* data, std::size_t size, std::size_t& pos) noexcept {
  std::int32_t length = 0;
  if (!readInt32(data, size, pos, length)) return false;
  pos += 4;
  if (length < 1 || static_cast<std::size_t>(length) > size - pos) return false;
  pos += static_cast<std::size_t>(length);
  return true;
}

/// true when `data` holds the 8-byte type hash and then `fields` within `size` bytes.
bool fitsLayout(const void* raw, std::size_t size, std::initializer_list<Field> fields) noexcept {
  const auto* data = static_cast<const std::uint8_t*>(raw);
  if (data == nullptr || size < 8) return false;
  std::size_t pos = 8;
  std::size_t count = 0;
  for (const Field field : fields) {
    const std::size_t rest = size - pos;
    switch (field) {
      case Field::I8:
        if (rest < 1) return false;
        pos += 1;
        break;
      case Field::I32:
        if (rest < 4) return false;
        pos += 4;
        break;
      case Field::I64:
      case Field::F64:
        if (rest < 8) return false;
        pos += 8;
        break;
      case Field::Str:
        if (!skipString(data, size, pos)) return false;
        break;
      case Field::Count: {
        std::int32_t value = 0;
        if (!readInt32(data, size, pos, value) || value < 0) return false;
        pos += 4;
        count = static_cast<std::size_t>(value);
        if (count > size - pos) return false;  // every element takes at least one byte
        break;
      }
      case Field::StrArray:
        for (std::size_t i = 0; i < count; ++i) {
          if (!skipString(data, size, pos)) return false;
        }
        break;
      case Field::I64Array:
      case Field::F64Array:
        if (count > rest / 8) return false;
        pos += count * 8;
        break;
      case Field::ByteArray:
        if (count > rest) return false;
        pos += count;
        break;
    }
  }
  return true;
}

bool fits(const openvcu_lcm::command_request_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size, {F::I64, F::I64, F::Str, F::I8, F::Str, F::F64, F::Str, F::I64});
}
bool fits(const openvcu_lcm::command_ack_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size, {F::I64, F::I64, F::Str, F::Str, F::I8, F::Str, F::I8});
}
bool fits(const openvcu_lcm::fsm_transition_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size, {F::I64, F::Str, F::Str, F::Str});
}
bool fits(const openvcu_lcm::fault_event_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size, {F::I64, F::Str, F::Str, F::I8, F::I8, F::Str});
}
bool fits(const openvcu_lcm::log_record_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size, {F::I64, F::Str, F::I8, F::Str});
}
bool fits(const openvcu_lcm::heartbeat_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size,
                    {F::I64, F::Str, F::Str, F::I32, F::I64, F::Count, F::StrArray, F::I64Array, F::Str});
}
bool fits(const openvcu_lcm::signal_snapshot_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size, {F::I64, F::Str, F::Count, F::StrArray, F::F64Array, F::ByteArray});
}
bool fits(const openvcu_lcm::stats_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size,
                    {F::I64, F::Str, F::Str, F::I32, F::I32, F::I32, F::Count, F::StrArray, F::I64Array});
}
bool fits(const openvcu_lcm::tx_schedule_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size,
                    {F::I64, F::Str, F::Str, F::I32, F::I32, F::I32, F::Count, F::StrArray, F::I64Array,
                     F::ByteArray, F::ByteArray});
}

bool fits(const openvcu_lcm::j1939_network_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size,
                    {F::I64, F::Str, F::Str, F::I32, F::Str, F::I8, F::I64, F::I64, F::Count, F::I64Array,
                     F::I64Array, F::Count, F::StrArray, F::I64Array, F::ByteArray, F::ByteArray, F::ByteArray,
                     F::I8});
}

bool fits(const openvcu_lcm::j1939_dm1_t*, const void* data, std::size_t size) noexcept {
  using F = Field;
  return fitsLayout(data, size,
                    {F::I64, F::Str, F::Str, F::Str, F::Str, F::I64, F::I8, F::I8, F::Count, F::I64Array,
                     F::ByteArray, F::ByteArray, F::ByteArray});
}

/// The layout check for LcmType.
template <typename LcmType>
bool fitsType(const void* data, std::size_t size) noexcept {
  return fits(static_cast<const LcmType*>(nullptr), data, size);
}

/// Receives raw LCM messages for one subscription and hands them to `dispatch`.
struct RawHandler {
  std::function<void(const void* data, std::uint32_t size)> dispatch;
};

// LCM's C callback: user data is the RawHandler of the subscription.
void onLcmMessage(const lcm_recv_buf_t* buffer, const char* /*channel*/, void* userData) {
  static_cast<RawHandler*>(userData)->dispatch(buffer->data, buffer->data_size);
}

}  // namespace

namespace {

template <typename LcmType, typename Plain>
std::vector<std::uint8_t> encodeOne(const Plain& message) {
  LcmType encoded;
  if (!toLcm(message, encoded)) return {};
  const int size = encoded.getEncodedSize();
  std::vector<std::uint8_t> buffer(static_cast<std::size_t>(size));
  if (encoded.encode(buffer.data(), 0, size) != size) return {};
  return buffer;
}

template <typename LcmType>
auto decodeOne(const void* data, std::size_t size) -> std::optional<decltype(fromLcm(std::declval<LcmType>()))> {
  if (data == nullptr || size == 0 || size > static_cast<std::size_t>(INT_MAX)) return std::nullopt;
  if (!fitsType<LcmType>(data, size)) return std::nullopt;
  try {
    LcmType decoded;
    if (decoded.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) return std::nullopt;
    return fromLcm(decoded);
  } catch (...) {  // bad_alloc on a hostile length field
    return std::nullopt;
  }
}

}  // namespace

bool fitsEventLayout(EventKind kind, const void* data, std::size_t size) noexcept {
  switch (kind) {
    case EventKind::Command: return fitsType<openvcu_lcm::command_request_t>(data, size);
    case EventKind::Ack: return fitsType<openvcu_lcm::command_ack_t>(data, size);
    case EventKind::Fsm: return fitsType<openvcu_lcm::fsm_transition_t>(data, size);
    case EventKind::Fault: return fitsType<openvcu_lcm::fault_event_t>(data, size);
    case EventKind::Log: return fitsType<openvcu_lcm::log_record_t>(data, size);
    case EventKind::Heartbeat: return fitsType<openvcu_lcm::heartbeat_t>(data, size);
    case EventKind::Snapshot: return fitsType<openvcu_lcm::signal_snapshot_t>(data, size);
    case EventKind::Stats: return fitsType<openvcu_lcm::stats_t>(data, size);
    case EventKind::Schedule: return fitsType<openvcu_lcm::tx_schedule_t>(data, size);
    case EventKind::J1939: return fitsType<openvcu_lcm::j1939_network_t>(data, size);
    case EventKind::Dm1: return fitsType<openvcu_lcm::j1939_dm1_t>(data, size);
  }
  return false;
}

// Command socket messages (command_socket.hpp) share the event types' encoding.
std::vector<std::uint8_t> encodeCommandRequest(const CommandRequest& request) {
  return encodeOne<openvcu_lcm::command_request_t>(request);
}
std::optional<CommandRequest> decodeCommandRequest(const void* data, std::size_t size) {
  return decodeOne<openvcu_lcm::command_request_t>(data, size);
}
std::vector<std::uint8_t> encodeCommandAck(const CommandAck& ack) {
  return encodeOne<openvcu_lcm::command_ack_t>(ack);
}
std::optional<CommandAck> decodeCommandAck(const void* data, std::size_t size) {
  return decodeOne<openvcu_lcm::command_ack_t>(data, size);
}
std::optional<FsmTransition> decodeFsmTransition(const void* data, std::size_t size) {
  return decodeOne<openvcu_lcm::fsm_transition_t>(data, size);
}
std::optional<FaultEvent> decodeFaultEvent(const void* data, std::size_t size) {
  return decodeOne<openvcu_lcm::fault_event_t>(data, size);
}
std::vector<std::uint8_t> encodeFaultEvent(const FaultEvent& fault) {
  return encodeOne<openvcu_lcm::fault_event_t>(fault);
}

namespace {

constexpr std::string_view UDPM_SCHEME = "udpm://";
constexpr std::string_view TCPQ_SCHEME = "tcpq://";
/// LCM's own self-test channel: lcm-spy and lcm-logger already see one message on it from
/// every LCM start, so the marker below adds no channel and no type to the event plane.
constexpr const char* MARKER_CHANNEL = "LCM_SELF_TEST";
constexpr std::chrono::milliseconds MARKER_TIMEOUT{2000};
constexpr std::chrono::milliseconds MARKER_RESEND{100};
/// LCM's port when the URL gives only an address ("udpm://" -> 239.255.76.67:7667).
constexpr std::uint16_t LCM_DEFAULT_PORT = 7667;

/// The port a udpm URL binds, parsed as LCM 1.3.1 parses it: "udpm://ADDR:PORT?opts";
/// no network part -> 7667; an address without a port -> 0 (LCM binds a random port).
/// "udpm://239.255.76.67:7667?ttl=0" -> 7667.
std::uint16_t udpmPort(std::string_view url) noexcept {
  std::string_view network = url.substr(UDPM_SCHEME.size());
  network = network.substr(0, network.find('?'));
  if (network.empty()) return LCM_DEFAULT_PORT;
  const std::size_t colon = network.find(':');
  if (colon == std::string_view::npos) return 0;
  const std::string port(network.substr(colon + 1));
  const long value = std::strtol(port.c_str(), nullptr, 0);
  return value > 0 && value <= UINT16_MAX ? static_cast<std::uint16_t>(value) : 0;
}

/// The marker's text and whether it came back.
struct Marker {
  std::string text;
  bool seen{false};
};

void onMarker(const lcm_recv_buf_t* buffer, const char* /*channel*/, void* userData) {
  auto* marker = static_cast<Marker*>(userData);
  if (buffer->data_size == marker->text.size() &&
      std::memcmp(buffer->data, marker->text.data(), buffer->data_size) == 0) {
    marker->seen = true;
  }
}

}  // namespace

struct EventBusImpl {
  struct Entry {
    std::uint64_t id{};
    lcm_subscription_t* subscription{nullptr};
    std::unique_ptr<RawHandler> handler;
  };

  EventBusImpl() = default;
  EventBusImpl(const EventBusImpl&) = delete;
  EventBusImpl& operator=(const EventBusImpl&) = delete;
  ~EventBusImpl() {
    if (lcm == nullptr) return;
    for (const Entry& entry : entries) lcm_unsubscribe(lcm, entry.subscription);
    lcm_destroy(lcm);
  }

  std::string url;
  std::string instance;
  std::array<std::string, EVENT_KIND_COUNT> channels;
  lcm_t* lcm{nullptr};
  std::vector<Entry> entries;
  std::uint64_t nextId{1};
  std::atomic<std::uint64_t> publishFailures{0};
  std::atomic<std::uint64_t> decodeErrors{0};
  std::atomic<std::uint64_t> callbackErrors{0};

  const std::string& channel(EventKind kind) const { return channels.at(static_cast<std::size_t>(kind)); }

  /// After the filter is on: publishes a marker and dispatches until it comes back, with
  /// nothing subscribed but the marker. A datagram from another host that was queued on the
  /// socket before the filter precedes the marker, so LCM drops it here (no subscriber)
  /// instead of handing it to the subscriptions made after open().
  Status dropWhatCameBeforeTheFilter() {
    Marker marker;
    marker.text = "openvcu event bus " + std::to_string(::getpid()) + " " + std::to_string(clock::monotonicNs());
    lcm_subscription_t* subscription = lcm_subscribe(lcm, MARKER_CHANNEL, &onMarker, &marker);
    if (subscription == nullptr) return Error{"cannot subscribe to " + std::string(MARKER_CHANNEL)};
    const auto start = std::chrono::steady_clock::now();
    auto nextSend = start;
    for (auto now = start; !marker.seen && now - start < MARKER_TIMEOUT; now = std::chrono::steady_clock::now()) {
      if (now >= nextSend) {
        lcm_publish(lcm, MARKER_CHANNEL, marker.text.data(), static_cast<unsigned int>(marker.text.size()));
        nextSend = now + MARKER_RESEND;
      }
      lcm_handle_timeout(lcm, static_cast<int>(MARKER_RESEND.count() / 5));
    }
    lcm_unsubscribe(lcm, subscription);
    if (!marker.seen) {
      return Error{"its own marker did not come back within " + std::to_string(MARKER_TIMEOUT.count()) + " ms"};
    }
    return {};
  }

  template <typename LcmType, typename Plain>
  bool publish(EventKind kind, const Plain& message) noexcept {
    try {
      LcmType encoded;
      if (toLcm(message, encoded)) {
        const int size = encoded.getEncodedSize();
        std::vector<std::uint8_t> buffer(static_cast<std::size_t>(size));
        if (encoded.encode(buffer.data(), 0, size) == size &&
            lcm_publish(lcm, channel(kind).c_str(), buffer.data(), static_cast<unsigned int>(size)) == 0) {
          return true;
        }
      }
    } catch (...) {  // bad_alloc while encoding: count it like any failed send
    }
    ++publishFailures;
    return false;
  }

  /// Publishes `whole` as parts of one datagram each (splitPoints): every part carries the
  /// same timestamp, its number and the number of parts. false if any part failed.
  template <typename LcmType, typename Plain, typename Item>
  bool publishParts(EventKind kind, const Plain& whole, std::vector<Item> Plain::*items) noexcept {
    try {
      const std::vector<Item>& all = whole.*items;
      Plain part = whole;
      (part.*items).clear();
      part.timestampNs = stampOrNow(whole.timestampNs);
      part.part = 0;
      part.parts = 1;
      LcmType empty;
      if (!toLcm(part, empty)) throw std::length_error("parts");
      const std::vector<std::size_t> starts =
          splitPoints(all, static_cast<std::size_t>(empty.getEncodedSize()), datagramPayloadLimit(channel(kind)));
      part.parts = static_cast<std::int32_t>(starts.size());
      bool ok = true;
      for (std::size_t k = 0; k < starts.size(); ++k) {
        const std::size_t end = k + 1 < starts.size() ? starts[k + 1] : all.size();
        part.part = static_cast<std::int32_t>(k);
        (part.*items).assign(all.begin() + static_cast<std::ptrdiff_t>(starts[k]),
                             all.begin() + static_cast<std::ptrdiff_t>(end));
        ok = publish<LcmType>(kind, part) && ok;
      }
      return ok;
    } catch (...) {  // bad_alloc while copying: count it like any failed send
    }
    ++publishFailures;
    return false;
  }

  template <typename LcmType, typename Plain>
  Result<Subscription> subscribe(EventKind kind, std::function<void(const Plain&)> callback) {
    if (!callback) return Error{"EventBus: empty callback for " + channel(kind)};
    auto handler = std::make_unique<RawHandler>();
    handler->dispatch = [this, callback = std::move(callback)](const void* data, std::uint32_t size) {
      try {
        LcmType decoded;
        if (size > static_cast<std::uint32_t>(INT_MAX) || !fitsType<LcmType>(data, size) ||
            decoded.decode(data, 0, static_cast<int>(size)) < 0) {
          ++decodeErrors;
          return;
        }
        callback(fromLcm(decoded));
      } catch (...) {  // never let an exception unwind through LCM's C code
        ++callbackErrors;
      }
    };
    lcm_subscription_t* subscription = lcm_subscribe(lcm, channel(kind).c_str(), &onLcmMessage, handler.get());
    if (subscription == nullptr) return Error{"EventBus: cannot subscribe to " + channel(kind) + " on " + url};
    lcm_subscription_set_queue_capacity(subscription, SUBSCRIPTION_QUEUE_CAPACITY);
    const std::uint64_t id = nextId++;
    entries.push_back(Entry{id, subscription, std::move(handler)});
    return Subscription{id};
  }
};

Result<EventBus> EventBus::open(std::string_view url, std::string_view instance) {
  if (!isValidName(instance)) {
    return Error{"invalid instance name '" + std::string(instance) + "': use 1..32 characters of [A-Za-z0-9_-]"};
  }
  auto impl = std::make_unique<EventBusImpl>();
  impl->url = url.empty() ? std::string(DEFAULT_EVENT_URL) : std::string(url);
  impl->instance = std::string(instance);
  for (std::size_t i = 0; i < EVENT_KIND_COUNT; ++i) {
    impl->channels.at(i) = channelName(instance, static_cast<EventKind>(i));
  }
  const std::string routeHint =
      impl->url.rfind("udpm://", 0) == 0
          ? " (multicast needs a route, e.g. `ip route add 224.0.0.0/4 dev lo`; see docs/design/ipc.md)"
          : "";
  if (impl->url.rfind(TCPQ_SCHEME, 0) == 0) {
    return Error{"refusing LCM URL " + impl->url +
                 ": a tcpq hub (lcm.lcm.TCPService) relays what any client that reaches its port sends, "
                 "so events could come from another host; use udpm:// (default " +
                 std::string(DEFAULT_EVENT_URL) + ")"};
  }
  const bool udpm = impl->url.rfind(UDPM_SCHEME, 0) == 0;
  const std::string refusal = "refusing events from " + impl->url + ": cannot restrict them to this host: ";
  std::vector<std::uint64_t> socketsBefore;
  if (udpm) {
    auto known = openSocketInodes();
    if (!known) return Error{refusal + known.error().message};
    socketsBefore = std::move(*known);
  }
  impl->lcm = lcm_create(impl->url.c_str());
  if (impl->lcm == nullptr) return Error{"cannot open LCM at " + impl->url + routeHint};
  // LCM sets up udpm's receive side lazily; ask for the fd now so a broken transport
  // (no multicast route: LCM's self test fails) is reported here, not on first wait.
  if (lcm_get_fileno(impl->lcm) < 0) return Error{"cannot receive on LCM at " + impl->url + routeHint};
  if (udpm) {
    // LCM does not hand out its receive socket: it is the new UDP socket bound to the
    // URL's port (host_filter.hpp). Without the filter nothing is received at all.
    auto restricted = restrictNewUdpSockets(socketsBefore, udpmPort(impl->url));
    if (!restricted) return Error{refusal + restricted.error().message};
    Status drained = impl->dropWhatCameBeforeTheFilter();
    if (!drained) return Error{refusal + drained.error().message};
  }
  return EventBus(std::move(impl));
}

EventBus::EventBus(std::unique_ptr<EventBusImpl> impl) noexcept : m_impl(std::move(impl)) {}
EventBus::EventBus(EventBus&& other) noexcept = default;
EventBus& EventBus::operator=(EventBus&& other) noexcept = default;
EventBus::~EventBus() = default;

bool EventBus::publish(const CommandAck& message) noexcept {
  return m_impl->publish<openvcu_lcm::command_ack_t>(EventKind::Ack, message);
}
bool EventBus::publish(const FsmTransition& message) noexcept {
  return m_impl->publish<openvcu_lcm::fsm_transition_t>(EventKind::Fsm, message);
}
bool EventBus::publish(const FaultEvent& message) noexcept {
  return m_impl->publish<openvcu_lcm::fault_event_t>(EventKind::Fault, message);
}
bool EventBus::publish(const LogRecord& message) noexcept {
  return m_impl->publish<openvcu_lcm::log_record_t>(EventKind::Log, message);
}
bool EventBus::publish(const Heartbeat& message) noexcept {
  return m_impl->publish<openvcu_lcm::heartbeat_t>(EventKind::Heartbeat, message);
}
bool EventBus::publish(const SignalSnapshot& message) noexcept {
  return m_impl->publish<openvcu_lcm::signal_snapshot_t>(EventKind::Snapshot, message);
}

Result<Subscription> EventBus::onAck(std::function<void(const CommandAck&)> callback) {
  return m_impl->subscribe<openvcu_lcm::command_ack_t>(EventKind::Ack, std::move(callback));
}
Result<Subscription> EventBus::onFsmTransition(std::function<void(const FsmTransition&)> callback) {
  return m_impl->subscribe<openvcu_lcm::fsm_transition_t>(EventKind::Fsm, std::move(callback));
}
Result<Subscription> EventBus::onFault(std::function<void(const FaultEvent&)> callback) {
  return m_impl->subscribe<openvcu_lcm::fault_event_t>(EventKind::Fault, std::move(callback));
}
Result<Subscription> EventBus::onLog(std::function<void(const LogRecord&)> callback) {
  return m_impl->subscribe<openvcu_lcm::log_record_t>(EventKind::Log, std::move(callback));
}
bool EventBus::publish(const Stats& message) noexcept {
  return m_impl->publishParts<openvcu_lcm::stats_t>(EventKind::Stats, message, &Stats::counters);
}
bool EventBus::publish(const TxSchedule& message) noexcept {
  return m_impl->publishParts<openvcu_lcm::tx_schedule_t>(EventKind::Schedule, message, &TxSchedule::entries);
}
Result<Subscription> EventBus::onStats(std::function<void(const Stats&)> callback) {
  return m_impl->subscribe<openvcu_lcm::stats_t>(EventKind::Stats, std::move(callback));
}
Result<Subscription> EventBus::onSchedule(std::function<void(const TxSchedule&)> callback) {
  return m_impl->subscribe<openvcu_lcm::tx_schedule_t>(EventKind::Schedule, std::move(callback));
}
bool EventBus::publish(const J1939Network& message) noexcept {
  return m_impl->publish<openvcu_lcm::j1939_network_t>(EventKind::J1939, message);
}
Result<Subscription> EventBus::onJ1939Network(std::function<void(const J1939Network&)> callback) {
  return m_impl->subscribe<openvcu_lcm::j1939_network_t>(EventKind::J1939, std::move(callback));
}
bool EventBus::publish(const NodeDm1& message) noexcept {
  return m_impl->publish<openvcu_lcm::j1939_dm1_t>(EventKind::Dm1, message);
}
Result<Subscription> EventBus::onNodeDm1(std::function<void(const NodeDm1&)> callback) {
  return m_impl->subscribe<openvcu_lcm::j1939_dm1_t>(EventKind::Dm1, std::move(callback));
}

namespace {
template <typename LcmType, typename Plain>
std::size_t encodedSizeOf(const Plain& message) {
  LcmType encoded;
  if (!toLcm(message, encoded)) return SIZE_MAX;
  return static_cast<std::size_t>(encoded.getEncodedSize());
}
}  // namespace

std::size_t encodedSize(const Heartbeat& message) { return encodedSizeOf<openvcu_lcm::heartbeat_t>(message); }
std::size_t encodedSize(const Stats& message) { return encodedSizeOf<openvcu_lcm::stats_t>(message); }
std::size_t encodedSize(const TxSchedule& message) { return encodedSizeOf<openvcu_lcm::tx_schedule_t>(message); }
std::size_t encodedSize(const J1939Network& message) { return encodedSizeOf<openvcu_lcm::j1939_network_t>(message); }
std::size_t encodedSize(const NodeDm1& message) { return encodedSizeOf<openvcu_lcm::j1939_dm1_t>(message); }

Result<Subscription> EventBus::onHeartbeat(std::function<void(const Heartbeat&)> callback) {
  return m_impl->subscribe<openvcu_lcm::heartbeat_t>(EventKind::Heartbeat, std::move(callback));
}
Result<Subscription> EventBus::onSnapshot(std::function<void(const SignalSnapshot&)> callback) {
  return m_impl->subscribe<openvcu_lcm::signal_snapshot_t>(EventKind::Snapshot, std::move(callback));
}

void EventBus::unsubscribe(Subscription subscription) noexcept {
  auto& entries = m_impl->entries;
  for (auto it = entries.begin(); it != entries.end(); ++it) {
    if (it->id == subscription.id) {
      lcm_unsubscribe(m_impl->lcm, it->subscription);
      entries.erase(it);
      return;
    }
  }
}

int EventBus::fileno() const noexcept {
  return lcm_get_fileno(m_impl->lcm);
}

HandleResult EventBus::handle(std::chrono::milliseconds timeout) noexcept {
  const auto clamped = std::clamp<std::chrono::milliseconds::rep>(timeout.count(), 0, INT_MAX);
  const int rc = lcm_handle_timeout(m_impl->lcm, static_cast<int>(clamped));
  if (rc > 0) return HandleResult::Handled;
  if (rc == 0) return HandleResult::Timeout;
  return HandleResult::Failed;
}

std::size_t EventBus::handleAll() noexcept {
  std::size_t handled = 0;
  while (lcm_handle_timeout(m_impl->lcm, 0) > 0) ++handled;
  return handled;
}

const std::string& EventBus::instance() const noexcept {
  return m_impl->instance;
}
const std::string& EventBus::url() const noexcept {
  return m_impl->url;
}
std::string EventBus::channel(EventKind kind) const {
  return m_impl->channel(kind);
}
std::uint64_t EventBus::publishFailures() const noexcept {
  return m_impl->publishFailures;
}
std::uint64_t EventBus::decodeErrors() const noexcept {
  return m_impl->decodeErrors;
}
std::uint64_t EventBus::callbackErrors() const noexcept {
  return m_impl->callbackErrors;
}

}  // namespace openvcu::ipc
