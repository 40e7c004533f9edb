#pragma once
// The FSM file (docs/fsm.md) loaded, validated and compiled: every signal key resolved to
// a catalog index, every state name to a state index, every duration to nanoseconds, so
// that the engine (engine.hpp) never sees JSON or a string at run time.
//
//   std::vector<Error> diagnostics;
//   auto machineResult = fsm::loadMachine("fsm.json", vehicle, catalog, &diagnostics);
//   -> refused when any diagnostic is an error (the first one is returned); warnings
//      ("empty condition: always true") are in `diagnostics` either way.
//
// The thesis' format (appendix C.2) is accepted unchanged; the extensions (nested
// all/any/not, `for`, `after`, signal quality and age, entry/exit actions, send groups,
// faults, events) are documented in docs/fsm.md.

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::fsm {

inline constexpr std::uint32_t NONE = std::numeric_limits<std::uint32_t>::max();

/// `for` conditions whose running timers survive a restart of vcu-fsm (slots
/// internal.fsm.timer.<i>); later ones restart from zero (the checker warns).
inline constexpr std::uint32_t PERSISTED_TIMERS = config::FSM_TIMER_SLOTS;

enum class NodeKind : std::uint8_t {
  True,     ///< the empty condition {}
  All,      ///< every child true (an empty list is true)
  Any,      ///< some child true (an empty list is false)
  Not,      ///< its one child false
  Compare,  ///< signal OP constant(s)
  Quality,  ///< the signal's quality is one of a set
  Age,      ///< no value for longer than `durationNs` (never received counts as old)
};

enum class CompareOp : std::uint8_t { Eq, Ne, Lt, Gt, Le, Ge, In };

/// "eq", "ne", "lt", "gt", "le", "ge", "in".
std::string_view compareOpName(CompareOp op) noexcept;

/// One node of a condition tree; the trees of a machine share one array.
struct ConditionNode {
  NodeKind kind{NodeKind::True};
  CompareOp op{CompareOp::Eq};
  std::uint8_t qualityMask{};  ///< Quality: bit (1 << signals::Quality)
  std::uint32_t signal{NONE};  ///< Compare/Quality/Age: index into Machine::signals
  double value{};              ///< Compare (not In)
  std::uint32_t first{};       ///< All/Any/Not: children in Machine::children; In: values in Machine::constants
  std::uint32_t count{};
  std::int64_t durationNs{};   ///< Age
  std::int64_t forNs{};        ///< > 0: true only once the rest held continuously this long
  std::uint32_t timer{NONE};   ///< the `for` timer's index (Machine::timerCount of them)
  std::string path;            ///< JSON path, for causes and diagnostics
};

enum class ActionKind : std::uint8_t {
  Nothing,     ///< the thesis' empty action object { }
  SetSignal,   ///< command a signal (a DBC signal this VCU transmits, or an internal one)
  RaiseFault,  ///< publish a fault event (active)
  ClearFault,  ///< publish a fault event (cleared)
  Event,       ///< publish a log record
};

struct Action {
  ActionKind kind{ActionKind::Nothing};
  signals::SignalIndex signal{};  ///< SetSignal: catalog index
  double value{};
  bool copy{};                    ///< SetSignal from `source`'s value when it runs ("from")
  signals::SignalIndex source{};
  std::string name;  ///< fault name
  std::string text;  ///< fault or event text
  ipc::FaultSeverity severity{ipc::FaultSeverity::Error};
};

struct Transition {
  std::uint32_t condition{NONE};  ///< root node; NONE: no condition (an `after` alone)
  std::int64_t afterNs{};         ///< > 0: only once the state was active this long
  std::vector<Action> actions;
  std::uint32_t target{};         ///< state index
  std::string path;               ///< "/states/2/transitions/0"
  bool broken{};                  ///< its condition had errors (the whole-machine checks skip it)
};

struct State {
  std::string name;
  std::vector<Action> entry;
  std::vector<Action> exit;
  std::vector<Transition> transitions;
  std::vector<std::uint32_t> signals;  ///< indices into Machine::signals its conditions read (sorted)
};

/// Where a condition reads a signal from.
enum class ReadPlane : std::uint8_t {
  Bus,      ///< a received signal: the value on the bus, with its quality
  Command,  ///< a transmitted or internal signal: override, else command, else the bus plane
};

struct SignalRef {
  signals::SignalIndex index{};
  ReadPlane plane{ReadPlane::Bus};
  /// An internal signal nobody has written yet reads as its configured initial value.
  std::optional<double> initial;
};

struct Machine {
  std::string file;
  std::vector<State> states;
  std::uint32_t initial{};
  std::vector<ConditionNode> nodes;
  std::vector<std::uint32_t> children;
  std::vector<double> constants;
  std::vector<SignalRef> signals;  ///< every signal a condition reads, once
  std::uint32_t timerCount{};
  /// FNV-1a of the file's canonical JSON, 48 bits (exact in a double): a restarted
  /// vcu-fsm resumes only the machine it left.
  std::uint64_t hash{};

  [[nodiscard]] std::optional<std::uint32_t> findState(std::string_view name) const noexcept;
};

/// Loads, validates and compiles an FSM file. Errors and warnings (file, JSON path,
/// reason) are appended to *diagnostics; any error refuses the file (the first returned).
Result<Machine> loadMachine(const std::string& path, const config::VehicleConfig& vehicle,
                            const signals::Catalog& catalog, std::vector<Error>* diagnostics = nullptr);

/// The same from text (`fileName` names it in messages).
Result<Machine> parseMachine(std::string_view text, const std::string& fileName,
                             const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                             std::vector<Error>* diagnostics = nullptr);

/// Every diagnostic of a file, for `vcu fsm check` (errors and warnings, in file order).
std::vector<Error> checkMachine(const std::string& path, const config::VehicleConfig& vehicle,
                                const signals::Catalog& catalog);

/// A condition as one line of text ("all(VIC.X.Y eq 14, PDU.A.B ne 1) for 2s").
std::string describeCondition(const Machine& machine, const signals::Catalog& catalog, std::uint32_t node);

/// "2s", "250ms", "1.5s".
std::string formatDuration(std::int64_t ns);

}  // namespace openvcu::fsm
