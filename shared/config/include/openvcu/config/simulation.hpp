#pragma once
// The simulation parameters ("simulation" in vehicle.json; HHEA: config/hhea/simulation.json):
// the battery, the loads, the timing of the simulated nodes, the J1939-76 pairs the
// simulated VIC checks; loaded by vcu-ecu-sim and checked by `vcu check`. Every key optional
// (defaults below); unknown keys and bad values are errors with file and JSON path.
// Reference: services/ecu-sim/README.md.

#include <cstdint>
#include <string>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::config {

struct SafetyCheckConfig {
  std::string message;          ///< the SDM's DBC message name ("S1_ES_PGN61427")
  std::uint32_t dataCanId{};    ///< resolved from the DBC
  std::int64_t srvtNs{10'000'000};  ///< longest SHM -> SDM time accepted
  std::int64_t sctNs{60'000'000};   ///< longest SHM -> SHM time accepted
};

struct SimConfig {
  std::string file;
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
};

/// Loads `path` (empty: the defaults and the S1_ES pair of the HHEA DBC when present).
Result<SimConfig> loadSimConfig(const std::string& path, const config::VehicleConfig& vehicle);

}  // namespace openvcu::config
