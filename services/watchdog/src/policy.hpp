#pragma once
// What vcu-watchdog watches: the "watchdog" section of the vehicle's safety case
// (safety.json, openvcu::safety), or, for a vehicle without one, DEFAULT_SERVICES silent
// after DEFAULT_SILENT_AFTER_MS, restarted, no board watchdog.
//
//   auto policyResult = watchdog::policyOf(runtime.config(), runtime.catalog());
//   // -> WatchedPolicy{{"can-rx", "can-tx", "fsm", "gpio"}, 2500, true, "", "defaults: ..."}
//   // or "config/hhea/safety.json: /watchdog/services/1: 'fms' has no heartbeat slot ..."

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::watchdog {

inline constexpr std::array<std::string_view, 4> DEFAULT_SERVICES = {"can-rx", "can-tx", "fsm", "gpio"};
inline constexpr std::int64_t DEFAULT_SILENT_AFTER_MS = 2500;  // above the FSM dead-man of config/*/schedule.json (1500 ms)

struct WatchedPolicy {
  std::vector<std::string> services;  ///< short names ("fsm"), each with a heartbeat slot
  std::int64_t silentAfterMs{DEFAULT_SILENT_AFTER_MS};
  bool restart{true};
  std::string device;  ///< empty: no board watchdog
  std::string origin;  ///< where it came from, for the start-up log line
};

/// The policy of `vehicle`, each service checked against `catalog` (its heartbeat slot).
/// @note allocates; start-up only.
Result<WatchedPolicy> policyOf(const config::VehicleConfig& vehicle, const signals::Catalog& catalog);

}  // namespace openvcu::watchdog
