#pragma once
// The HHEA configuration and catalog for the FSM unit tests, and a machine compiled from
// inline JSON text.

#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "openvcu/config/catalog.hpp"
#include "openvcu/fsm/machine.hpp"
#include "vehicle_fixture.hpp"

namespace fsmtest {

using namespace openvcu;

inline const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";

inline constexpr const char* SOC = "VIC.HVESSD2_PGN61585.HS_FastUpdSOC";
inline constexpr const char* CONNECTION = "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts";
inline constexpr const char* PDU_STATUS = "PDU.PDU_Tx_1.byPDU_Status";
inline constexpr const char* BMS_CONTROL = "Vehicle_Control_Unit.BMS.BMS_Control";
inline constexpr const char* CONTROL_WORD = "Vehicle_Control_Unit.HC1_Demands.ControlWord";
inline constexpr const char* CONTACTOR_A = "Vehicle_Control_Unit.PDU_Rx_1.Close_GroupA_Contactors";
inline constexpr const char* START_STOP = "internal.operator.StartStop";
inline constexpr const char* KEEP_ALIVE = "internal.tx.keepAlive";

struct Hhea : openvcu::testing::VehicleTable {
  Hhea() : VehicleTable(HHEA) {}

  signals::SignalIndex key(const std::string& name) const {
    const auto index = catalog.indexOf(name);
    REQUIRE_MESSAGE(index, name);
    return *index;
  }

  /// Compiles `text`; diagnostics land in *diagnostics.
  Result<fsm::Machine> compile(const std::string& text, std::vector<Error>* diagnostics = nullptr) const {
    return fsm::parseMachine(text, "test.json", vehicle, catalog, diagnostics);
  }

  /// Compiles `text`, which must have no errors.
  fsm::Machine good(const std::string& text) const {
    std::vector<Error> diagnostics;
    auto result = compile(text, &diagnostics);
    REQUIRE_MESSAGE(result, (result ? "" : result.error().toString()));
    return std::move(*result);
  }
};

/// Every diagnostic as "severity path: message" lines, for readable failures.
inline std::string listing(const std::vector<Error>& diagnostics) {
  std::string text;
  for (const Error& diagnostic : diagnostics) text += diagnostic.toString() + "\n";
  return text;
}

/// The diagnostics whose path is `path` and whose message contains `part`.
inline std::size_t count(const std::vector<Error>& diagnostics, Severity severity, const std::string& path,
                         const std::string& part) {
  std::size_t found = 0;
  for (const Error& diagnostic : diagnostics) {
    if (diagnostic.severity == severity && diagnostic.location.jsonPath == path &&
        diagnostic.message.find(part) != std::string::npos) {
      ++found;
    }
  }
  return found;
}

}  // namespace fsmtest
