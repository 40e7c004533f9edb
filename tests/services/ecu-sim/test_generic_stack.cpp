// Issue 22: vcu-ecu-sim with the generic model on a DBC that is not HHEA's
// (tests/data/ecu-sim), as a process beside iox-roudi and vcu-can-rx in the sandbox: the
// other nodes' cyclic messages arrive with their start values and the file's rules applied,
// and `vcu sim fault` works for the file's fault names and refuses others with the list.

#include "integration_support.hpp"

namespace {

const fs::path GENERIC_CONFIG = fs::path(OPENVCU_SOURCE_DIR) / "tests" / "data" / "ecu-sim" / "vehicle.json";

}  // namespace

TEST_CASE("#22 ecu-sim's generic model runs a non-HHEA DBC: start values, rules and faults reach can-rx") {
  SKIP_UNLESS_ISOLATED();
  ConfiguredStack s(GENERIC_CONFIG);
  REQUIRE_STATUS(s.sut.startRoudi());
  s.startService("can-rx", CAN_RX_BINARY);
  harness::Process& sim = s.startService("ecu-sim", ECU_SIM_BINARY);
  REQUIRE(sim.waitForLine("model generic", 5s));
  s.openTable();
  // BMS_Status (100 ms) from its start values: SOC 60 % (GenSigStartValue 120 x 0.5)
  CHECK(waitForBus(*s.table, s.index("BMS.BMS_Status.SOC"), 60, 3s));
  // INV_Status (50 ms): State 1 from the rule's `otherwise` (its start value is 0)
  CHECK(waitForBus(*s.table, s.index("INV.INV_Status.State"), 1, 3s));
  const auto refused = s.vcu({"sim", "fault", "battery", "on"});
  CHECK(refused.exitCode() == 1);
  CHECK_MESSAGE(contains(refused.out + refused.err, "faults: isolation, silent.<node>"), refused.describe());
  const auto accepted = s.vcu({"sim", "fault", "isolation", "on"});
  REQUIRE_MESSAGE(contains(accepted.out, "accepted"), accepted.describe());
  CHECK(waitForBus(*s.table, s.index("BMS.BMS_Status.IsolationFault"), 1, 3s));
}
