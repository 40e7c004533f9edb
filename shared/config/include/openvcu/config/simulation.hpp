#pragma once
// The simulation parameters ("simulation" in vehicle.json; HHEA: config/hhea/simulation.json),
// loaded by vcu-ecu-sim and checked by `vcu check`. `"model"` chooses what the simulated
// nodes do besides sending their cyclic messages from the DBC's start values:
//   "generic" (the default, also without a file): the rules, follow, integrate and faults
//           of simulation_rules.hpp;
//   "hhea": the HHEA node models with the battery, the loads, the timing of the simulated
//           nodes and the wake signal below (keys refused under "generic").
// Both: the model tick, the J1939-76 pairs the simulator checks and a scripted J1939 peer
// ("j1939Peer", simulation_peer.hpp). Every key optional
// (defaults below); unknown keys, keys of the other model and bad values are errors with
// file and JSON path. Reference: services/ecu-sim/README.md.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/config/simulation_peer.hpp"
#include "openvcu/config/simulation_rules.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::config {

struct SafetyCheckConfig {
  std::string message;          ///< the SDM's DBC message name ("S1_ES_PGN61427")
  std::uint32_t dataCanId{};    ///< resolved from the DBC
  std::int64_t srvtNs{10'000'000};  ///< longest SHM -> SDM time accepted
  std::int64_t sctNs{60'000'000};   ///< longest SHM -> SHM time accepted
};

enum class SimModel : std::uint8_t {
  Generic,  ///< the DBC's cyclic messages from their start values (and the rules)
  Hhea,     ///< the HHEA node models (services/ecu-sim/src/vehicle_model.hpp)
};

/// "generic", "hhea".
std::string_view simModelName(SimModel model) noexcept;

struct SimConfig {
  std::string file;
  SimModel model{SimModel::Generic};
  std::int64_t tickNs{10'000'000};  ///< the node models' step
  // battery
  double capacityAh{100};
  double initialSoc{60};           ///< %
  double emptyVoltage{560};        ///< open-circuit voltage at 0 % SOC
  double fullVoltage{720};         ///< at 100 %
  double resistanceOhm{0.05};
  double stateOfHealth{96};        ///< %
  double lowSoc{15};               ///< % the fault soc_low sets
  double highSoc{90};              ///< % the fault soc_high sets
  double chargeVoltageLimit{700};  ///< V, PropA_C3 UChLimLong
  double chargeCurrentLimit{60};   ///< A, PropA_C3 IChLimLong
  double fullSoc{95};              ///< % above which the VIC stops allowing charge current
  // loads
  double drivingCurrent{110};  ///< A drawn while the inverters are enabled
  double dcdcCurrent{5};       ///< A on the 12 V side while the DC-DC runs
  // timing
  std::int64_t keepAliveTimeoutNs{1'000'000'000};  ///< the VIC sleeps when CCVS1/HVESSC1/CN stop this long
  std::int64_t connectNs{500'000'000};             ///< precharge before "connected"
  std::int64_t disconnectNs{300'000'000};
  std::int64_t inverterStepNs{100'000'000};        ///< an HVLP inverter follows a ControlWord step after this
  std::int64_t timeDateAnswerNs{1'000'000'000};    ///< the VCU's Time/Date answer must come within this
  std::string wakeSignal;  ///< when set, the VIC also needs this table key (bus plane) = 1 to wake (the Cl15 relay)
  std::vector<SafetyCheckConfig> safety;
  SimRules rules;  ///< the generic model's rules, follow, integrate and faults
  std::optional<SimPeerConfig> peer;  ///< "j1939Peer": a scripted J1939 node (either model)
};

/// Loads `path` (empty: the defaults, i.e. the generic model without pairs).
Result<SimConfig> loadSimConfig(const std::string& path, const config::VehicleConfig& vehicle);

}  // namespace openvcu::config
