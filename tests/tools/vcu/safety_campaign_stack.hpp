#pragma once
// The stack `vcu safety campaign` runs against in the sandbox: iox-roudi, vcu-can-rx,
// vcu-can-tx, vcu-fsm, vcu-gpio and vcu-ecu-sim (the simulated HHEA vehicle) on a copy of
// config/hhea in the sandbox's /tmp/hhea, each started through the harness with its readiness
// awaited; the stack is up once the FSM is in Standby. A case may change its copy of the
// configuration before any service reads it (`edit`) and start vcu-fsm its own way
// (`startFsm`, e.g. under supervisord).
// The test target defines CAN_RX_BINARY, CAN_TX_BINARY, FSM_BINARY, GPIO_BINARY,
// ECU_SIM_BINARY, VCU_BINARY, FIXTURE_SERVICE and INTEGRATION_CONFIG.

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "integration_support.hpp"

namespace openvcu::integration {

inline const std::string CAN_RX = CAN_RX_BINARY;
inline const std::string CAN_TX = CAN_TX_BINARY;
inline const std::string FSM = FSM_BINARY;
inline const std::string GPIO = GPIO_BINARY;
inline const std::string ECU_SIM = ECU_SIM_BINARY;

/// Reads a JSON file; a discarded value when it does not parse.
inline nlohmann::json readJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

/// Rewrites the JSON file `path` through `change` (REQUIREs that it parses).
inline void editJson(const std::filesystem::path& path, const std::function<void(nlohmann::json&)>& change) {
  nlohmann::json content = readJson(path);
  REQUIRE_MESSAGE(!content.is_discarded(), path.string() << " does not parse");
  change(content);
  std::ofstream(path) << content.dump(2);
}

struct CampaignStack : ConfiguredStack {
  /// Changes the copy of config/hhea in `folder` (vehicle.json, fsm.json, ... beside each other).
  using ConfigEdit = std::function<void(const std::filesystem::path& folder)>;
  /// Starts vcu-fsm on the stack's configuration (default: through the harness, readiness awaited).
  using FsmStart = std::function<void(CampaignStack&)>;

  explicit CampaignStack(const ConfigEdit& edit = {}, const FsmStart& startFsm = {})
      : ConfiguredStack(editedHheaCopy(edit)) {
    REQUIRE_STATUS(sut.startRoudi());
    startService("can-rx", CAN_RX);
    startService("can-tx", CAN_TX);
    if (startFsm) {
      startFsm(*this);
    } else {
      startService("fsm", FSM);
    }
    startService("gpio", GPIO);
    startService("ecu-sim", ECU_SIM);
    openTable();
    REQUIRE(waitForBus(*table, index("internal.fsm.state"), hheaStateIndex("Standby"), 5s));
  }
  /// Writes a safety case beside the configuration; returns its path.
  std::filesystem::path writeSafety(const nlohmann::json& content) {
    const std::filesystem::path path = config.parent_path() / "campaign-safety.json";
    std::ofstream(path) << content.dump(2);
    return path;
  }

 private:
  static std::filesystem::path editedHheaCopy(const ConfigEdit& edit) {
    const std::filesystem::path vehicle = copyHheaConfig(std::filesystem::temp_directory_path() / "hhea");
    if (edit) edit(vehicle.parent_path());
    return vehicle;
  }
};

}  // namespace openvcu::integration
