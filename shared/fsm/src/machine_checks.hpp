#pragma once
// The whole-machine checks of an FSM file (docs/fsm.md, "Checks"): contradictory and
// repeated conditions, unreachable states, transitions that can never be taken. The loader
// (machine_loader.cpp) calls them; they only add diagnostics.

#include <cstdint>
#include <string>

#include "openvcu/config/json.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::fsm {

/// The children of the All/Any node `node`: the same comparison twice (warning) and, for
/// All, one signal required to take values that exclude each other (error). `listPath`:
/// where the children are written ("/.../condition/all"; a flat object's own path).
void checkSiblings(config::JsonChecker& check, const Machine& machine, const signals::Catalog& catalog,
                   std::uint32_t node, const std::string& listPath);

/// States no transition reaches, transitions after an always-true one, transitions with the
/// same condition as an earlier one, self-transitions that do nothing, `for` timers
/// beyond PERSISTED_TIMERS.
void checkMachineGraph(config::JsonChecker& check, const Machine& machine, const signals::Catalog& catalog,
                       bool initialDefined);

/// Fills state.signals: the machine's signal slots its transitions' conditions read.
void collectStateSignals(const Machine& machine, State& state);

}  // namespace openvcu::fsm
