#pragma once
// Private to shared/config: the generic model's keys of simulation.json (rules, follow,
// integrate, faults) read into SimRules; called by loadSimConfig (simulation.cpp).

#include "openvcu/config/json.hpp"
#include "openvcu/config/simulation_rules.hpp"
#include "openvcu/config/vehicle.hpp"

namespace openvcu::config {

/// The generic model's keys of `root`: every problem is an error in `check` with its JSON
/// path; `out` is complete only when `check` stayed ok. `hasSafety`: the file lists pairs
/// (sim.safety.ok is then a condition key).
void loadSimRules(const Json& root, JsonChecker& check, const VehicleConfig& vehicle, bool hasSafety, SimRules& out);

}  // namespace openvcu::config
