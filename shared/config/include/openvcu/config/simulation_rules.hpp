#pragma once
// The generic simulated vehicle's behaviour, from simulation.json ("model": "generic"):
// rules, follow, integrate and faults, loaded and compiled by loadSimConfig (simulation.hpp)
// so that vcu-ecu-sim never sees JSON or a string at run time: every signal key is resolved
// to its DBC message and signal index, every value-table name to its number, every duration
// to nanoseconds. Format and semantics: services/ecu-sim/README.md, "The generic model".
//
//   {"rules": [{"when": {"key": "VCU.BMS_Command.ContactorRequest", "eq": 1}, "after": "500ms",
//               "set": {"BMS.BMS_Status.ContactorState": "Closed"}}]}
//   -> one SimRule: when = a Compare node on signals[0] (the VCU's, read as received),
//      afterNs = 500'000'000, set = {signals[1] (BMS's, settable) = 2 (VAL_ "Closed")}
//
// Conditions have the shape of fsm.json's (docs/fsm.md "Conditions"): key with eq, ne (neq),
// lt, gt, le, ge, in; the flat form {"K": V, ...}; all, any, not; `for`. Not supported here:
// `quality` and `ageGt` (the simulator has no signal table). One more key: "sim.safety.ok"
// (1 while the last J1939-76 pair judged was good, 0 after a refusal, no value before the
// first verdict; needs a "safety" list).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace openvcu::config {

inline constexpr std::uint32_t SIM_NONE = std::numeric_limits<std::uint32_t>::max();
/// The condition key of the simulator's J1939-76 verdict.
inline constexpr const char* SIM_SAFETY_OK_KEY = "sim.safety.ok";

/// A signal the generic model reads or sets, resolved once from its key.
struct SimSignal {
  enum class Kind : std::uint8_t {
    Node,      ///< a simulated node's (another node transmits its message): settable
    Vcu,       ///< this VCU transmits its message: read as last received, never set
    SafetyOk,  ///< sim.safety.ok
  };
  std::string key;         ///< "BMS.BMS_Status.SOC" (the catalog's bus-signal key)
  Kind kind{Kind::Node};
  std::size_t message{};   ///< Node/Vcu: index into Database::messages
  std::uint32_t signal{};  ///< Node/Vcu: index into Message::signals
  std::string path;        ///< JSON path of its first use
};

enum class SimNodeKind : std::uint8_t { True, All, Any, Not, Compare };
enum class SimCompareOp : std::uint8_t { Eq, Ne, Lt, Gt, Le, Ge, In };

/// One node of a condition tree; the trees of a file share SimRules::nodes.
struct SimConditionNode {
  SimNodeKind kind{SimNodeKind::True};
  SimCompareOp op{SimCompareOp::Eq};
  std::uint32_t signal{SIM_NONE};  ///< Compare: index into SimRules::signals
  double value{};                  ///< Compare (not In)
  std::uint32_t first{};           ///< All/Any/Not: into SimRules::children; In: into SimRules::constants
  std::uint32_t count{};
  std::int64_t forNs{};            ///< > 0: true once the rest held continuously this long
  std::uint32_t timer{SIM_NONE};   ///< that `for`'s timer (SimRules::timerCount of them)
};

/// signals[signal] = value (a Node signal).
struct SimAssignment {
  std::uint32_t signal{};
  double value{};
};

struct SimRule {
  std::uint32_t when{SIM_NONE};  ///< root node; SIM_NONE: always
  std::int64_t afterNs{};        ///< `when` must have held this long
  std::vector<SimAssignment> set;
  std::vector<SimAssignment> otherwise;
  std::string path;  ///< "/rules/0"
};

/// A first-order lag of `signal` toward `target` (a signal, or `targetValue` when none)
/// while `when` holds, toward 0 otherwise.
struct SimFollow {
  std::uint32_t signal{};
  std::uint32_t target{SIM_NONE};
  double targetValue{};
  std::int64_t timeConstantNs{};
  std::uint32_t when{SIM_NONE};  ///< SIM_NONE: always
  std::string path;
};

/// signal += rate x dt (s), rate = factor x signals[rateSignal] (or factor alone when
/// rateSignal is SIM_NONE), kept within [minimum, maximum].
struct SimIntegrate {
  std::uint32_t signal{};
  std::uint32_t rateSignal{SIM_NONE};
  double factor{1};
  double minimum{-std::numeric_limits<double>::infinity()};
  double maximum{std::numeric_limits<double>::infinity()};
  std::string path;
};

/// A named fault (`vcu sim fault NAME on|off`): while active its values override all else.
struct SimFault {
  std::string name;
  std::vector<SimAssignment> set;
  std::string path;
};

struct SimRules {
  std::vector<SimSignal> signals;  ///< every signal read or set, once
  std::vector<SimConditionNode> nodes;
  std::vector<std::uint32_t> children;
  std::vector<double> constants;
  std::uint32_t timerCount{};
  std::vector<SimRule> rules;
  std::vector<SimFollow> follow;
  std::vector<SimIntegrate> integrate;
  std::vector<SimFault> faults;  ///< in file order
};

}  // namespace openvcu::config
