#pragma once
// The fleet as a watcher sees it (`vcu fleet watch|get`): the messages of every vehicle on
// the broker (topics.hpp, payloads.hpp) folded into one view per vehicle: online or offline,
// what it is (birth), its FSM state, active faults, health and the newest value of each signal.
// Driven by the caller with each message; no MQTT client, no clock of its own.
//
//   FleetView fleet;
//   fleet.apply("openvcu/hhea-01/status", "online");
//   fleet.apply("openvcu/hhea-01/state", R"({"v":1,"seq":3,"t":...,"state":"Ready",...})");
//   fleet.find("hhea-01")->state->state == "Ready"
//   fleetValue(*fleet.find("hhea-01"), "status") == "online"
//
// QoS 1 may deliver a message twice, and a queue drained after an outage delivers old ones:
// a state, faults or health message replaces the one kept only when its seq is higher or its
// time stamp "t" later (a vehicle whose queue was reset starts its seq again).
// @note not thread-safe: one thread applies and reads.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "openvcu/core/result.hpp"
#include "openvcu/fleet/payloads.hpp"
#include "openvcu/fleet/topics.hpp"

namespace openvcu::fleet {

struct VehicleView {
  std::string vehicleId;
  std::optional<bool> online;  ///< from the retained status; empty until one arrived
  std::optional<BirthMessage> birth;
  std::optional<StateMessage> state;
  std::optional<FaultsMessage> faults;
  std::optional<HealthMessage> health;
  std::map<std::string, SignalSample> signals;  ///< the newest sample of each signal by name
  std::int64_t newestUnixMs{};                  ///< the newest "t" of its messages (0: none carried one)
};

class FleetView {
 public:
  /// Folds one message in. Returns whether the vehicle's view changed; a topic that is not a
  /// vehicle message (topics.hpp) changes nothing; a payload that is not the format gives an
  /// Error naming the topic and the problem (the view is unchanged).
  Result<bool> apply(std::string_view topic, std::string_view payload);

  [[nodiscard]] const std::map<std::string, VehicleView>& vehicles() const noexcept { return m_vehicles; }
  [[nodiscard]] const VehicleView* find(std::string_view vehicleId) const;

 private:
  std::map<std::string, VehicleView> m_vehicles;
};

/// Active faults: the fault events plus the DM1 DTCs of every node.
[[nodiscard]] std::int64_t activeFaultCount(const VehicleView& vehicle) noexcept;
/// The active DM1 DTCs of every node (the faults message counts them per node, no severity).
[[nodiscard]] std::int64_t activeDtcCount(const VehicleView& vehicle) noexcept;
/// The worst severity among the active fault events (DM1 DTCs carry none); empty when none.
[[nodiscard]] std::optional<FaultLevel> worstFaultLevel(const VehicleView& vehicle) noexcept;

/// The signal that stands for the state of charge: `wanted` when given, else the first of
/// the birth's signals (else of the signals seen) whose name ends in "SOC"; empty when none.
[[nodiscard]] std::string socSignalOf(const VehicleView& vehicle, std::string_view wanted = {});

/// One value as text, for `vcu fleet get VEHICLE KEY`: "status" (online/offline), "state"
/// (the FSM state), "faults" ("<count> active[, worst <severity>]: <source>/<name> <text>; ..."),
/// "health" ("<ready>/<services> services Ready; queue <pending> pending, <dropped> dropped"),
/// or a signal's name (its newest value); empty when the vehicle has not told it (yet).
[[nodiscard]] std::optional<std::string> fleetValue(const VehicleView& vehicle, std::string_view key);

/// A number as a consumer shows it: at most 3 decimals, no trailing zeros ("87.5", "-12").
[[nodiscard]] std::string formatNumber(double value);

}  // namespace openvcu::fleet
