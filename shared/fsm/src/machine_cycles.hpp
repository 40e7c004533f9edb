#pragma once
// The spin check of an FSM file (docs/fsm.md, "Cycles"): transitions that can fire in a
// cycle with no input change would keep vcu-fsm evaluating forever, so such a machine is
// refused (an error in `vcu fsm check`, at start and on reload).
//
//   A -> B when {} and B -> A when {}                           refused (always true)
//   A -> B when X eq 1 and B -> A when X eq 1                   refused (X = 1 holds both)
//   A -> B when X eq 1 and B -> A when X eq 0                   accepted (X must change)
//   A -> B when Y eq 0 (A's entry sets Y 1), B -> A when Y eq 1  accepted (the cycle itself
//                                                                makes the first one false)
//   A -> B when {} and B -> A after 1s / for 1s                  accepted (a timer in the cycle)
//
// What is proved, for each elementary cycle of transitions between different states without
// `after`: there are signal values (held constant) under which, every time the cycle enters
// a state, the cycle's transition out of it is the one taken: its condition is true and the
// conditions of the transitions before it (file order) are false. Signals the cycle's own
// actions write read as the values the cycle writes (as if no override were active); `for`
// conditions are false at the moment of entry (their timers restart); values are tried at
// and between the constants the conditions compare with, with and without a value, and, for
// `quality` and `ageGt`, every quality and age that makes a difference (within the DBC
// range; whole numbers for a signal with a value table). Whatever cannot be decided (a
// `from` action's value, a signal a self-transition of the cycle writes) counts as not
// proved: a cycle is refused only with values found that keep it firing, and the engine's loop
// guard (engine.hpp, MAX_FIRINGS) bounds what it cannot prove, cycles of more than 64 states
// and whatever lies beyond the work limits (each reported as a warning).

#include "openvcu/config/json.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::fsm {

/// Adds one error per cycle proved to spin (at most a few, then a count) naming the states,
/// the transitions' JSON paths and the signal values that keep it firing; a warning when the
/// search stopped at its work limit.
void checkSpinningCycles(config::JsonChecker& check, const Machine& machine, const signals::Catalog& catalog);

}  // namespace openvcu::fsm
