#pragma once
// The whole-vehicle J1939-81 checks (vehicle_check.hpp): the VCU's address policy on a bus
// where it sends J1939-76 safety pairs (design: docs/design/j1939-address-claim.md,
// "Safety networks").

#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/error.hpp"
#include "vehicle_files.hpp"

namespace openvcu::check {

/// A warning per bus whose "j1939" object claims an address with an arbitrary-address-
/// capable NAME while the schedule sends J1939-76 safety pairs on that bus, at
/// /buses/<i>/j1939/name/arbitraryAddressCapable of vehicle.json. Needs the schedule.
///   {"j1939": {"name": {..., "arbitraryAddressCapable": true}}} + S1_ES with "safety"
///   -> vehicle.json: /buses/0/j1939/name/arbitraryAddressCapable: warning: bus 'vehicle': ...
void checkSafetyAddressPolicy(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::vector<Error>& out);

}  // namespace openvcu::check
