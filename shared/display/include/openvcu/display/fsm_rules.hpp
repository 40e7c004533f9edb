#pragma once
// The state machine file seen from a display: state names by index and which signals each
// state's transitions read, so that an operator switch is offered when it may matter.
//
//   config/hhea/fsm.json: stateName(0) -> "Standby"; stateReads(0, "internal.operator.StartStop") -> true

#include <cstddef>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::display {

/// The FSM file (docs/fsm.md) as a display needs it: state names by index
/// (internal.fsm.state holds the index) and, per state, the signal keys its transition
/// conditions read. An operator switch is offered when the current state reads it (a
/// transition may follow). The file's full checks are vcu-fsm's (shared/fsm); this reads
/// only names and keys.
/// @note immutable once loaded: safe to read from several threads.
class FsmRules {
 public:
  /// Reads the vcu-fsm file. Errors name the file and what is wrong.
  static Result<FsmRules> load(const std::string& path);
  /// The same from text; `source` names it in errors (JSON path "/states/N").
  static Result<FsmRules> parse(std::string_view text, const std::string& source);

  [[nodiscard]] std::size_t stateCount() const noexcept { return m_states.size(); }
  /// "Standby", or "state N" for an index the file does not have.
  [[nodiscard]] std::string stateName(double index) const;
  /// True when the transitions of state `index` read `key`.
  [[nodiscard]] bool stateReads(double index, std::string_view key) const;

 private:
  struct State {
    std::string name;
    std::set<std::string, std::less<>> reads;
  };
  std::vector<State> m_states;
};

}  // namespace openvcu::display
