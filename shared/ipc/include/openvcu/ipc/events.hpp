#pragma once
// The events of the stack as plain openvcu structs: the C++ face of the LCM types in
// shared/ipc/lcm/*.lcm (the IDL is the contract; these mirror it field by field, and
// EventBus converts). Services use these and never see LCM's generated classes.
//
// Channels (INSTANCE = the stack instance in upper case, e.g. "hhea" -> HHEA):
//   (command sockets)             CommandRequest   openvcu_lcm.command_request_t (command_socket.hpp)
//   OPENVCU_<INSTANCE>_ACK        CommandAck       openvcu_lcm.command_ack_t
//   OPENVCU_<INSTANCE>_FSM        FsmTransition    openvcu_lcm.fsm_transition_t
//   OPENVCU_<INSTANCE>_FAULT      FaultEvent       openvcu_lcm.fault_event_t
//   OPENVCU_<INSTANCE>_LOG        LogRecord        openvcu_lcm.log_record_t
//   OPENVCU_<INSTANCE>_HEARTBEAT  Heartbeat        openvcu_lcm.heartbeat_t
//   OPENVCU_<INSTANCE>_SNAPSHOT   SignalSnapshot   openvcu_lcm.signal_snapshot_t
//   OPENVCU_<INSTANCE>_STATS      Stats            openvcu_lcm.stats_t        (in datagram-sized parts)
//   OPENVCU_<INSTANCE>_SCHEDULE   TxSchedule       openvcu_lcm.tx_schedule_t  (in datagram-sized parts)
//   OPENVCU_<INSTANCE>_J1939      J1939Network     openvcu_lcm.j1939_network_t (one per bus)
//   OPENVCU_<INSTANCE>_DM1        NodeDm1          openvcu_lcm.j1939_dm1_t     (one per source node)
//
// A heartbeat always fits one datagram (LCM_DATAGRAM_BYTES): per-bus and per-message
// statistics go to STATS, can-tx's live schedule to SCHEDULE, each split into parts that
// fit one datagram. LCM fragments larger messages, and a lost fragment loses the whole
// message: a heartbeat of hundreds of counters kept a restarted service unseen for seconds.
//
// Timestamps are CLOCK_REALTIME nanoseconds since the Unix epoch; EventBus stamps the
// current time into a 0 timestampNs when publishing.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::ipc {

/// Host-local multicast (ttl=0: never leaves this machine). Also LCM's own default, so
/// lcm-spy and lcm-logger without arguments see the stack.
inline constexpr std::string_view DEFAULT_EVENT_URL = "udpm://239.255.76.67:7667?ttl=0";

enum class EventKind : std::uint8_t { Command, Ack, Fsm, Fault, Log, Heartbeat, Snapshot, Stats, Schedule, J1939, Dm1 };
inline constexpr std::size_t EVENT_KIND_COUNT = 11;

/// LCM 1.3 sends a message of at most this many bytes (its 8-byte header, the channel name
/// with its NUL, the payload) as one UDP datagram, and fragments anything larger.
inline constexpr std::size_t LCM_DATAGRAM_BYTES = 1400;

/// The largest encoded payload (with the type's 8-byte fingerprint) that goes out on
/// `channel` as one datagram.
constexpr std::size_t datagramPayloadLimit(std::string_view channel) noexcept {
  return LCM_DATAGRAM_BYTES - 8 - (channel.size() + 1);
}

/// "COMMAND", "ACK", "FSM", "FAULT", "LOG", "HEARTBEAT", "SNAPSHOT", "STATS", "SCHEDULE",
/// "J1939", "DM1".
std::string_view channelSuffix(EventKind kind) noexcept;

/// "OPENVCU_HHEA_HEARTBEAT" for ("hhea", EventKind::Heartbeat). `instance` must satisfy
/// isValidName() (topics.hpp).
std::string channelName(std::string_view instance, EventKind kind);

/// command_request_t::kind. Values are the IDL's constants; a receiver must refuse
/// values it does not know (the enum may hold them).
enum class CommandKind : std::int8_t {
  SetSignal = 1,       ///< set the commanded value of `key` to `value`
  SetOverride = 2,     ///< operator override of `key` to `value`, wins until cleared
  ClearOverride = 3,   ///< remove the override of `key`
  OperatorSwitch = 4,  ///< operator intent (Start, Connect Driving, ...): switch `key` to `value`
  FaultReset = 5,      ///< reset latched fault `key` (empty: all)
  // can-tx's transmit schedule (services/can-tx): effective at once, kept across restarts.
  ScheduleCycle = 6,    ///< cycle time of the message named `key` to `value` ms
  ScheduleEnable = 7,   ///< message `key` transmitted (`value` 1) or not (0)
  ScheduleDefault = 8,  ///< value sent for signal `key` while nothing commands it
  FsmReload = 9,        ///< vcu-fsm: load the FSM file `key` (empty: its configured file) and switch to it
  SimFault = 10,        ///< vcu-ecu-sim: inject (`value` 1) or clear (0) the fault named `key`
  ScheduleAdd = 11,     ///< can-tx: add the DBC message `key` to the transmit schedule, cycle `value` ms
};

struct CommandRequest {
  std::int64_t timestampNs{};
  std::int64_t requestId{};  ///< unique per issuer; echoed in the CommandAck
  std::string issuer;        ///< "vcu-hmi", "vcu", ...
  CommandKind kind{CommandKind::SetSignal};
  std::string key;
  double value{};
  std::string text;
  /// CLOCK_MONOTONIC ns after which the request is never applied (0: none given, refused).
  std::int64_t deadlineNs{};
  bool operator==(const CommandRequest&) const = default;
};

/// A random, positive, odd request id for a new issuer process (vcu, vcu-hmi): another
/// process started in the same nanosecond does not pick it, and 2^43 ids can be counted up
/// from it without overflow.
std::int64_t randomRequestId();

struct CommandAck {
  std::int64_t timestampNs{};
  std::int64_t requestId{};
  std::string issuer;     ///< copied from the request
  std::string responder;  ///< the service that decided
  bool accepted{};
  std::string reason;  ///< why refused; empty when accepted
  /// false: the responder does not answer for this command (command sockets only).
  bool owner{true};
  bool operator==(const CommandAck&) const = default;
};

struct FsmTransition {
  std::int64_t timestampNs{};
  std::string fromState;  ///< empty for the initial entry
  std::string toState;
  std::string cause;
  bool operator==(const FsmTransition&) const = default;
};

enum class FaultSeverity : std::int8_t { Info = 0, Warning = 1, Error = 2, Critical = 3 };

/// A fault raised (active) or cleared (!active).
struct FaultEvent {
  std::int64_t timestampNs{};
  std::string name;
  std::string source;
  FaultSeverity severity{FaultSeverity::Error};
  bool active{true};
  std::string text;
  bool operator==(const FaultEvent&) const = default;
};

enum class LogLevel : std::int8_t { Trace = 0, Debug = 1, Info = 2, Warning = 3, Error = 4, Critical = 5 };

struct LogRecord {
  std::int64_t timestampNs{};
  std::string service;
  LogLevel level{LogLevel::Info};
  std::string text;
  bool operator==(const LogRecord&) const = default;
};

/// One named counter of a heartbeat (the IDL carries names and values as parallel
/// arrays so lcm-spy shows them side by side; here they cannot get out of step).
struct Counter {
  std::string name;
  std::int64_t value{};
  bool operator==(const Counter&) const = default;
};

struct Heartbeat {
  std::int64_t timestampNs{};
  std::string service;
  std::string instance;  ///< the stack instance
  std::int32_t pid{};
  std::int64_t uptimeMs{};
  std::vector<Counter> counters;
  std::string status;  ///< one line: "ok", "bus vehicle: bus-off", ...
  bool operator==(const Heartbeat&) const = default;
};

/// Per-bus and per-message statistics of one service (names like "vehicle.frames_rx",
/// "rx.EEC1.period_us"). EventBus::publish splits it into parts of one datagram each;
/// a subscriber gets the parts one by one (`part` of `parts`, same timestampNs).
struct Stats {
  std::int64_t timestampNs{};
  std::string service;
  std::string instance;
  std::int32_t pid{};
  std::int32_t part{};   ///< set by publish
  std::int32_t parts{};  ///< set by publish
  std::vector<Counter> counters;
  bool operator==(const Stats&) const = default;
};

/// One message of can-tx's live schedule.
struct ScheduleEntry {
  std::string message;  ///< DBC message name
  std::int64_t cycleUs{};
  bool enabled{true};
  bool added{};  ///< added at run time, not from schedule.json
  bool operator==(const ScheduleEntry&) const = default;
};

/// vcu-can-tx's live transmit schedule; split into parts like Stats.
struct TxSchedule {
  std::int64_t timestampNs{};
  std::string service;
  std::string instance;
  std::int32_t pid{};
  std::int32_t part{};
  std::int32_t parts{};
  std::vector<ScheduleEntry> entries;
  bool operator==(const TxSchedule&) const = default;
};

/// The VCU's address claim state on one bus (J1939-81), as j1939_network_t carries it.
enum class ClaimState : std::int8_t { Off = 0, Claiming = 1, Claimed = 2, CannotClaim = 3 };

/// Another node's address claim.
struct J1939Node {
  std::uint8_t address{};
  std::uint64_t name{};
  bool operator==(const J1939Node&) const = default;
};

/// One of the VCU's own diagnostic trouble codes (J1939-73).
struct J1939Dtc {
  std::string name;  ///< diagnostics.json name
  std::uint32_t spn{};
  std::uint8_t fmi{};
  std::uint8_t occurrences{};
  bool active{};  ///< true: in DM1; false: previously active (DM2)
  bool operator==(const J1939Dtc&) const = default;
};

/// vcu-can-tx's view of one J1939 network (shared/ipc/lcm/j1939_network_t.lcm).
struct J1939Network {
  std::int64_t timestampNs{};
  std::string service;
  std::string instance;
  std::int32_t pid{};
  std::string bus;
  ClaimState claimState{ClaimState::Off};
  std::uint8_t address{0xFE};  ///< 254 (null) while none is claimed
  std::uint64_t name{};
  std::vector<J1939Node> nodes;
  std::vector<J1939Dtc> dtcs;
  std::uint8_t lamps{};  ///< DM1 byte 0
  bool operator==(const J1939Network&) const = default;
};

/// One active DTC of another node's DM1 (J1939-73; j1939::Dtc without the decoder).
struct NodeDtc {
  std::uint32_t spn{};         ///< 0..524287
  std::uint8_t fmi{};          ///< 0..31
  std::uint8_t occurrences{};  ///< 0..126; 127 = not available
  bool conversionMethod{};     ///< the CM bit
  bool operator==(const NodeDtc&) const = default;
};

/// Another node's last DM1 as vcu-can-rx decoded it (shared/ipc/lcm/j1939_dm1_t.lcm): sent
/// when its content changes and at most once a second while the node keeps sending DM1.
struct NodeDm1 {
  std::int64_t timestampNs{};
  std::string service;
  std::string instance;
  std::string bus;
  std::string node;  ///< the DBC node at `source`, or "SA 0x21" when none has that address
  std::uint8_t source{};
  std::uint8_t lamps{};  ///< DM1 byte 0: malfunction, red stop, amber warning, protect (2 bits each)
  std::uint8_t flash{};  ///< DM1 byte 1
  std::vector<NodeDtc> dtcs;
  bool operator==(const NodeDm1&) const = default;
};

/// "off", "claiming", "claimed", "cannot claim".
std::string_view claimStateName(ClaimState state) noexcept;

/// Encoded size in bytes of the LCM payload (with the 8-byte fingerprint) of a message,
/// as EventBus sends it; compare with datagramPayloadLimit().
std::size_t encodedSize(const Heartbeat& message);
std::size_t encodedSize(const Stats& message);
std::size_t encodedSize(const TxSchedule& message);
std::size_t encodedSize(const J1939Network& message);
std::size_t encodedSize(const NodeDm1& message);

/// One signal in a snapshot.
struct SignalValue {
  std::string key;
  double value{};
  std::uint8_t quality{};  ///< the signal table's quality bits
  bool operator==(const SignalValue&) const = default;
};

/// A rate-limited batch of signal values for people and recorders (never for control).
struct SignalSnapshot {
  std::int64_t timestampNs{};
  std::string source;
  std::vector<SignalValue> signals;
  bool operator==(const SignalSnapshot&) const = default;
};

}  // namespace openvcu::ipc
