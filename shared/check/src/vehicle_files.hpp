#pragma once
// The files of a vehicle as their own loaders read them, and helpers shared by the checks
// (vehicle_check.cpp: signals; bus_checks.cpp: bus load and addresses).

#include <optional>
#include <string>
#include <vector>

#include "openvcu/config/dashboard.hpp"
#include "openvcu/config/diagnostics.hpp"
#include "openvcu/config/receive.hpp"
#include "openvcu/config/simulation.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/error.hpp"
#include "openvcu/fsm/machine.hpp"
#include "openvcu/schedule/schedule_config.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::check {

/// Each file loaded, or empty when it is not configured or does not load (then its own
/// check reports why and the cross-checks that need it are skipped).
struct VehicleFiles {
  std::optional<schedule::Schedule> schedule;
  std::optional<fsm::Machine> machine;
  std::optional<config::ReceiveConfig> receive;
  std::optional<config::SimConfig> simulation;
  std::optional<config::DashboardConfig> dashboard;
  /// diagnostics.json: no per-file check of `vcu check` loads it, so loadFiles() reports its
  /// loader's errors and warnings itself (with the FSM's state names when the FSM loads).
  std::optional<config::DiagnosticsConfig> diagnostics;
};

/// "74.0 %".
std::string percent(double share);
/// "0x18FEF121" (8 digits) or "0x123" (3 digits, standard IDs).
std::string hexId(std::uint32_t id, bool extended);
/// Where a DBC message is defined: the DBC file and line when the vehicle has one DBC file,
/// else vehicle.json's /dbc (the merged database does not keep the file of each message).
Location messageLocation(const config::VehicleConfig& vehicle, const dbc::Message& message);
/// "A, B, C, D, E and 7 more" (NAMES_SHOWN names at most).
std::string listNames(const std::vector<std::string>& names);

/// Expected bus load per bus (needs the schedule; see vehicle_check.hpp).
void checkBusLoads(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::vector<Error>& out);
/// Address and identifier collisions per bus (see vehicle_check.hpp).
void checkAddresses(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::vector<Error>& out);

}  // namespace openvcu::check
