#pragma once
// The safety case of a vehicle (safety.json, named by vehicle.json's "safety"): its
// hazards, each with a severity tag, a safety goal, the safe state that meets the goal, the
// mechanisms that detect it, its fault tolerant time interval (FTTI) and the faults a
// campaign injects to show it; and the service watchdog's policy. Reference: docs/safety.md.
//
//   {
//     "watchdog": {"services": ["can-rx", "can-tx", "fsm", "gpio"], "silentAfterMs": 1500,
//                  "restart": true, "device": ""},
//     "hazards": [{
//       "id": "H-BAT-TIMEOUT", "severity": "PL d",
//       "description": "the battery stops sending: its contactors are no longer supervised",
//       "safetyGoal": "open the HV path when the battery is not heard",
//       "safeState": {"fsmStates": ["Battery Timeout"],
//                     "gpio": [{"line": "Cl15", "level": 0}],
//                     "bus": [{"signal": "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors", "value": 0}]},
//       "detection": [{"kind": "receiveTimeout", "message": "HVESSS1_PGN61590"}],
//       "fttiMs": 4000,
//       "faults": [{"inject": "silence", "node": "VIC"}]
//     }]
//   }
//   loadSafety("config/hhea/safety.json") -> SafetyCase with one hazard and the watchdog
//   -> or an error such as "safety.json: /hazards/0/fttiMs: must be a whole number of ms above 0"
//
// loadSafety() checks the file on its own (keys, types, ranges, unique ids, known kinds);
// checkSafety() checks it against the vehicle (FSM states, GPIO lines, signals, messages,
// nodes, buses, services), as `vcu check` does.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::safety {

/// The service watchdog (vcu-watchdog): which services must beat, how long a missing beat
/// is tolerated, whether a silent service is killed so its supervisor restarts it, and the
/// hardware watchdog device fed while every listed service beats.
struct WatchdogPolicy {
  std::vector<std::string> services;  ///< short names of config::SERVICES ("fsm")
  std::int64_t silentAfterMs{};       ///< a beat older than this is a silent service; > 0
  bool restart{true};                 ///< kill a silent service so that it is restarted
  std::string device;                 ///< "/dev/watchdog"; empty: no hardware watchdog is fed
};

/// A GPIO output at its safe level.
struct SafeLevel {
  std::string line;  ///< gpio.json line name ("Cl15"), an output
  bool level{};      ///< the logical level of the safe state
};

/// A bus command of the safe state: the signal (a catalog key the VCU sends) at a value.
struct SafeCommand {
  std::string signal;  ///< "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors"
  double value{};
};

/// The state the vehicle must reach for a hazard; the lists are in the order they are
/// reached (or commanded).
struct SafeState {
  std::vector<std::string> fsmStates;  ///< any of these FSM states is safe
  std::vector<SafeLevel> gpio;
  std::vector<SafeCommand> bus;
  std::vector<std::string> restarted;  ///< services running and beating again (config::SERVICES names)
};

enum class DetectionKind : std::uint8_t {
  ReceiveTimeout,   ///< a message not received in time ("message"), or a signal's age ("signal")
  J1939_76,         ///< a J1939-76 safety check of a message pair ("message": the data message)
  Dm1,              ///< a DM1 lamp or DTC another node reports ("node", or a decoded "signal")
  Dtc,              ///< a fault the VCU raises and reports as its DTC ("fault")
  GpioInput,        ///< a hard-wired input line ("line")
  ServiceWatchdog,  ///< a VCU service that stops beating ("service")
  AddressLoss,      ///< the VCU's J1939 address lost on a bus ("bus")
  StatusSignal,     ///< a fault another node reports in a status signal it sends ("signal")
};

/// "receiveTimeout", "j1939_76", "dm1", "dtc", "gpioInput", "serviceWatchdog", "addressLoss",
/// "statusSignal".
[[nodiscard]] std::string_view detectionKindName(DetectionKind kind) noexcept;

/// A detection mechanism and exactly what it watches: one of the target members is set,
/// the one its kind takes (see DetectionKind).
struct Detection {
  DetectionKind kind{DetectionKind::ReceiveTimeout};
  std::string message;  ///< DBC message name
  std::string signal;   ///< catalog key
  std::string node;     ///< DBC node name
  std::string fault;    ///< fault event name ("service_silent.fsm", "hv_lost")
  std::string line;     ///< gpio.json line name
  std::string service;  ///< config::SERVICES short name
  std::string bus;      ///< vehicle.json bus name
  /// The mechanism reports within this many ms of the fault (its own bound, inside the
  /// FTTI); empty: only the FTTI bounds it.
  std::optional<std::int64_t> withinMs;
};

enum class InjectKind : std::uint8_t {
  Silence,        ///< a node or a message stops ("node" or "message")
  Delay,          ///< a node's or message's frames arrive "delayMs" late
  Corrupt,        ///< a message's payload altered; "validCrc": with or without a valid J1939-76 CRC
  FreezeCounter,  ///< a message's J1939-76 sequence counter stops ("message")
  Replay,         ///< an old frame of a message sent again ("message")
  Babble,         ///< a high-priority babbling node at "loadPercent" % bus load ("bus")
  Spoof,          ///< a message sent from a forged "address" ("message")
  BusOff,         ///< a link goes bus-off ("bus")
  AddressClaim,   ///< a hostile Address Claimed for "address" with a higher-priority NAME ("bus" optional)
  Kill,           ///< SIGKILL of a process ("service": a VCU service, "roudi" or "supervisor")
  Stop,           ///< SIGSTOP (a hang) of a process (as Kill)
  GpioStuck,      ///< an input line stuck at "level" ("line")
  Signal,         ///< a simulated node reports "value" in "signal" (a fault it detects itself)
  SimFault,       ///< a named fault of the simulated vehicle ("name": `vcu sim fault NAME`)
};

/// "silence", "delay", "corrupt", "freezeCounter", "replay", "babble", "spoof", "busOff",
/// "addressClaim", "kill", "stop", "gpioStuck", "signal", "simFault".
[[nodiscard]] std::string_view injectKindName(InjectKind kind) noexcept;

/// A fault a campaign injects, as data (the injection itself is `vcu inject`'s). Only the
/// members its kind takes are set.
struct Injection {
  InjectKind kind{InjectKind::Silence};
  std::string node;
  std::string message;
  std::string signal;
  std::string service;
  std::string line;
  std::string bus;
  std::string name;                     ///< SimFault
  std::optional<double> value;          ///< Signal
  std::optional<bool> level;            ///< GpioStuck
  std::optional<bool> validCrc;         ///< Corrupt
  std::optional<std::int64_t> delayMs;  ///< Delay
  std::optional<double> loadPercent;    ///< Babble
  std::optional<std::uint8_t> address;  ///< Spoof, AddressClaim
};

struct Hazard {
  std::string id;           ///< unique: letters, digits, '-', '_' ("H-BAT-TIMEOUT")
  std::string description;  ///< what goes wrong and why it is dangerous
  /// "PL a".."PL e" (ISO 13849), "AgPL a".."AgPL e" (ISO 25119), "ASIL QM", "ASIL A".."ASIL D"
  /// (ISO 26262), "SIL 1".."SIL 4" (IEC 61508)
  std::string severity;
  std::string safetyGoal;
  /// FSM states the vehicle is brought to before a campaign injects the faults ("Driving");
  /// empty: any state.
  std::vector<std::string> during;
  SafeState safeState;
  std::vector<Detection> detection;  ///< at least one
  std::int64_t fttiMs{};             ///< fault tolerant time interval, ms, > 0
  std::vector<Injection> faults;     ///< what a campaign injects; may be empty
  std::string comment;
};

struct SafetyCase {
  std::string path;  ///< the file as given
  std::vector<Hazard> hazards;
  std::optional<WatchdogPolicy> watchdog;

  [[nodiscard]] const Hazard* findHazard(std::string_view id) const noexcept;
};

/// Parses a safety case from JSON text; `fileName` names it in errors. The file alone is
/// checked (see the file comment); the first error is returned with its JSON path.
/// @note allocates; start-up and tools only. Never throws.
Result<SafetyCase> parseSafety(std::string_view text, const std::string& fileName);
/// Reads and parses safety.json (as parseSafety()).
Result<SafetyCase> loadSafety(const std::string& path);

/// The safety case against the vehicle it belongs to, every problem with the safety file
/// and the JSON path: FSM states that `fsmStates` does not hold (nullptr: not checked),
/// GPIO lines not in gpio.json or of the wrong direction, signals not in the catalog,
/// unknown messages, nodes and buses, services a serviceWatchdog detection names that the
/// watchdog does not watch, and a watchdog whose silentAfterMs alone exceeds the FTTI of a
/// hazard it detects. Errors, and warnings for gaps (a hazard no fault of the file injects).
/// @note allocates; start-up and tools only. Never throws.
std::vector<Error> checkSafety(const SafetyCase& safetyCase, const config::VehicleConfig& vehicle,
                               const signals::Catalog& catalog, const std::vector<std::string>* fsmStates);

}  // namespace openvcu::safety
