// Issue 22: vcu-ecu-sim's generic model with a fake clock on tests/data/ecu-sim (a small
// non-HHEA vehicle): a rule with `after` and `otherwise`, follow, integrate with clamping,
// a fault overriding a rule, the values on the frames the bus sends, and (on HHEA's DBC)
// the J1939-76 pairs judged with a safety list and read back as sim.safety.ok.

#include <doctest/doctest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "generic_model.hpp"
#include "openvcu/config/simulation.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/j1939/safety.hpp"
#include "sim_frames.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string GENERIC = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/ecu-sim/vehicle.json";
const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0 = 1000 * 1'000'000'000LL;
constexpr std::int64_t TICK = 10 * MS;

struct Fixture {
  config::VehicleConfig vehicle;
  config::SimConfig sim;
  std::optional<ecusim::VirtualBus> bus;
  std::optional<ecusim::GenericModel> sut;
  dbc::DatabaseCodec codecs;
  std::int64_t now{T0};

  /// `simulationText` empty: the vehicle's own simulation.json.
  explicit Fixture(const std::string& simulationText = "", const std::string& vehiclePath = GENERIC) {
    auto loaded = config::loadVehicleConfig(vehiclePath);
    REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
    vehicle = std::move(*loaded);
    std::string file = vehicle.simulationFile;
    const fs::path scratch = fs::temp_directory_path() / ("openvcu-generic-" + std::to_string(::getpid()) + ".json");
    if (!simulationText.empty()) {
      std::ofstream(scratch) << simulationText;
      file = scratch.string();
    }
    auto simResult = config::loadSimConfig(file, vehicle);
    fs::remove(scratch);
    REQUIRE_MESSAGE(simResult, (simResult ? "" : simResult.error().toString()));
    sim = std::move(*simResult);
    auto busResult = ecusim::VirtualBus::create(vehicle);
    REQUIRE(busResult);
    bus.emplace(std::move(*busResult));
    auto modelResult = ecusim::GenericModel::create(*bus, sim);
    REQUIRE_MESSAGE(modelResult, (modelResult ? "" : modelResult.error().toString()));
    sut.emplace(std::move(*modelResult));
    codecs = dbc::DatabaseCodec(vehicle.database);
    bus->start(T0);
  }

  /// A VCU frame of `name` from the DBC's initial payload with `values` encoded.
  can::Frame frame(const std::string& name, const std::map<std::string, double>& values) {
    return ecusim::test::encodedFrame(vehicle.database, codecs, name, values);
  }
  void receive(const std::string& name, const std::map<std::string, double>& values) {
    sut->receive(frame(name, values), now);
  }

  /// Steps every tick after `now` up to `until` (inclusive).
  void runUntil(std::int64_t until) {
    while (now + TICK <= until) {
      now += TICK;
      sut->step(now);
    }
  }
  void tick() {
    now += TICK;
    sut->step(now);
  }

  /// What a simulated node's signal is on the bus now.
  double value(const std::string& message, const std::string& signal) {
    const auto ref = bus->output(message, signal);
    REQUIRE_MESSAGE(ref, (message + "." + signal));
    return bus->current(*ref);
  }
};

}  // namespace

TEST_CASE("#22 a rule with after sets its values once its condition held that long, its otherwise values at once") {
  Fixture f;
  f.sut->step(f.now);
  CHECK(f.value("BMS_Status", "ContactorState") == 0);  // otherwise: Open
  f.now += TICK;
  f.receive("BMS_Command", {{"ContactorRequest", 1}});  // "Close", seen from T0 + 10 ms
  f.sut->step(f.now);
  f.runUntil(T0 + 500 * MS);                             // held 490 ms
  CHECK(f.value("BMS_Status", "ContactorState") == 0);
  f.tick();                                              // held 500 ms
  CHECK(f.value("BMS_Status", "ContactorState") == 2);   // set: Closed
  f.receive("BMS_Command", {{"ContactorRequest", 0}});
  f.tick();
  CHECK(f.value("BMS_Status", "ContactorState") == 0);  // otherwise, at once
}

TEST_CASE("#22 the values the model sets go out on the node's cyclic frames, encoded by the DBC") {
  Fixture f;
  f.receive("BMS_Command", {{"ContactorRequest", 1}});
  f.runUntil(T0 + 600 * MS);
  std::vector<can::Frame> sent;
  f.bus->sendDue(f.now + 100 * MS, [&](std::size_t, const can::Frame& frame) { sent.push_back(frame); });
  const auto status = std::find_if(sent.begin(), sent.end(), [](const can::Frame& frame) { return frame.id == 256; });
  REQUIRE(status != sent.end());
  CHECK((status->data[0] & 0x03) == 2);  // ContactorState Closed
  CHECK(status->data[1] == 120);         // SOC 60 % (GenSigStartValue 120 x 0.5), not integrated: no current
}

TEST_CASE("#22 follow lags toward its target while its condition holds and toward 0 otherwise") {
  Fixture f;
  f.receive("BMS_Command", {{"ContactorRequest", 1}});
  f.receive("INV_Command", {{"SpeedRequest", 1000}});
  f.runUntil(T0 + 500 * MS);
  CHECK(f.value("INV_Status", "MotorSpeed") == 0);  // State not yet 3: toward 0
  // Closed at T0+510ms, State 3 one tick later, follow sees it from T0+530ms
  f.runUntil(T0 + 520 * MS + 500 * MS);
  const double afterOneTimeConstant = f.value("INV_Status", "MotorSpeed");
  // 50 steps of 10 ms with a 500 ms time constant: 1 - 0.98^50 = 63.6 %
  CHECK(afterOneTimeConstant == doctest::Approx(636).epsilon(0.01));
  f.runUntil(T0 + 4000 * MS);
  CHECK(f.value("INV_Status", "MotorSpeed") == doctest::Approx(1000).epsilon(0.002));
  f.receive("BMS_Command", {{"ContactorRequest", 0}});  // open: State 1, the condition fails
  f.runUntil(f.now + 520 * MS);
  CHECK(f.value("INV_Status", "MotorSpeed") < 400);
  f.runUntil(f.now + 5000 * MS);
  CHECK(std::fabs(f.value("INV_Status", "MotorSpeed")) <= 1);
}

TEST_CASE("#22 integrate adds rate x dt and stays within min and max without winding up") {
  Fixture f(R"({"rules": [{"set": {"BMS.BMS_Status.PackCurrent": -100}}],
    "integrate": [{"signal": "BMS.BMS_Status.SOC", "rate": {"signal": "BMS.BMS_Status.PackCurrent", "factor": -0.5},
                   "min": 10, "max": 90}],
    "faults": {"discharge": {"set": {"BMS.BMS_Status.PackCurrent": 100}}}})");
  f.sut->step(f.now);  // samples PackCurrent 0 (start), sets -100
  CHECK(f.value("BMS_Status", "SOC") == 60);
  f.runUntil(T0 + 300 * MS);  // 30 steps of 10 ms at +50 %/s
  CHECK(f.value("BMS_Status", "SOC") == doctest::Approx(75));
  f.runUntil(T0 + 3000 * MS);
  CHECK(f.value("BMS_Status", "SOC") == 90);  // max
  // the fault reverses the current: SOC falls at once from 90, not from a wound-up integral
  f.sut->setFault(*f.sut->faultIndex("discharge"), true);
  f.runUntil(f.now + 200 * MS);
  CHECK(f.value("BMS_Status", "SOC") == doctest::Approx(80.5));  // 1 step at +0.5 (clamped), 19 at -0.5
  f.runUntil(f.now + 5000 * MS);
  CHECK(f.value("BMS_Status", "SOC") == 10);  // min
}

TEST_CASE("#22 an active fault overrides a rule, and when cleared the rule's value and the start value return") {
  Fixture f;
  f.receive("BMS_Command", {{"ContactorRequest", 1}});
  f.runUntil(T0 + 600 * MS);
  REQUIRE(f.value("BMS_Status", "ContactorState") == 2);
  CHECK(f.value("BMS_Status", "IsolationFault") == 0);
  const auto isolation = f.sut->faultIndex("isolation");
  REQUIRE(isolation);
  CHECK_FALSE(f.sut->faultIndex("battery"));
  f.sut->setFault(*isolation, true);
  f.tick();
  CHECK(f.value("BMS_Status", "ContactorState") == 0);  // the fault wins over the rule
  CHECK(f.value("BMS_Status", "IsolationFault") == 1);
  f.runUntil(f.now + 200 * MS);
  CHECK(f.value("BMS_Status", "ContactorState") == 0);  // every step
  f.sut->setFault(*isolation, false);
  f.tick();
  CHECK(f.value("BMS_Status", "ContactorState") == 2);  // the rule again (its `after` held throughout)
  CHECK(f.value("BMS_Status", "IsolationFault") == 0);  // no rule sets it: its start value
}

TEST_CASE("#22 a condition on a VCU signal not received yet is false, ne included") {
  Fixture f(R"({"rules": [{"when": {"key": "VCU.BMS_Command.ContactorRequest", "ne": 1},
    "set": {"INV.INV_Status.State": 7}, "otherwise": {"INV.INV_Status.State": 2}}]})");
  f.sut->step(f.now);
  CHECK(std::isnan(f.sut->sampled("VCU.BMS_Command.ContactorRequest")));
  CHECK(f.value("INV_Status", "State") == 2);
  f.receive("BMS_Command", {{"ContactorRequest", 0}});
  f.tick();
  CHECK(f.value("INV_Status", "State") == 7);
}

TEST_CASE("#22 with a safety list the generic model judges the VCU's J1939-76 pairs and exposes the verdict as sim.safety.ok") {
  // the generic model on HHEA's DBC: nothing of the HHEA models, only this file's rules
  Fixture f(R"({"safety": [{"message": "S1_ES_PGN61427"}],
    "rules": [{"when": {"sim.safety.ok": 1}, "set": {"VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts": 1},
               "otherwise": {"VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts": 0}}]})",
            HHEA);
  REQUIRE(f.sut->checksPairs());
  j1939::SafetyPairBuilder builder(f.vehicle.database.findMessage("S1_ES_PGN61427")->id);
  const auto pairs = [&](double relayValue, bool corrupt, std::int64_t until) {
    while (f.now + 20 * MS <= until) {  // S1_ES's 20 ms cycle: SHM, SDM 0.3 ms later, then two ticks
      can::Frame data = f.frame("S1_ES_PGN61427", {{"Control_Es_Relay", relayValue}});
      const can::Frame shm = ecusim::test::safetyHeaderFor(builder, data);
      if (corrupt) data.data[7] ^= 0x01;
      f.sut->receive(shm, f.now);
      f.sut->receive(data, f.now + 300'000);
      f.runUntil(f.now + 20 * MS);
    }
  };
  f.sut->step(f.now);
  CHECK(std::isnan(f.sut->sampled("sim.safety.ok")));  // no verdict yet
  CHECK(f.value("HVESSS1_PGN61590", "HS_HiUBusCnctnSts") == 0);
  pairs(3, false, T0 + 300 * MS);
  CHECK(f.sut->sampled("sim.safety.ok") == 1);
  CHECK(f.value("HVESSS1_PGN61590", "HS_HiUBusCnctnSts") == 1);
  CHECK(f.sut->safety().ok > 10);
  CHECK(f.sut->safety().refused == 0);
  // pairs with a bad CRC: refused, their data (relay 5) not taken, the verdict 0
  const auto change = f.sut->takeSafetyChange();
  pairs(5, true, T0 + 600 * MS);
  CHECK(f.sut->sampled("sim.safety.ok") == 0);
  CHECK(f.value("HVESSS1_PGN61590", "HS_HiUBusCnctnSts") == 0);
  CHECK(f.sut->safety().refused > 10);
  CHECK(f.sut->safety().lastRefusal == j1939::SafetyResult::CrcMismatch);
  const auto relayRef = f.bus->input("S1_ES_PGN61427", "Control_Es_Relay");
  REQUIRE(relayRef);
  CHECK(f.bus->get(*relayRef) == 3);  // the last good pair's value
  CHECK(change == j1939::SafetyResult::Ok);
  CHECK(f.sut->takeSafetyChange() == j1939::SafetyResult::CrcMismatch);
}

TEST_CASE("#22 a simulator that comes up between an SHM and its SDM judges nothing until the next SHM") {
  Fixture f(R"({"safety": [{"message": "S1_ES_PGN61427"}]})", HHEA);
  j1939::SafetyPairBuilder builder(f.vehicle.database.findMessage("S1_ES_PGN61427")->id);
  const auto pair = [&](std::int64_t atNs, bool withHeader) {
    can::Frame data = f.frame("S1_ES_PGN61427", {{"Control_Es_Relay", 3}});
    const can::Frame shm = ecusim::test::safetyHeaderFor(builder, data);
    if (withHeader) f.sut->receive(shm, atNs);
    f.sut->receive(data, atNs + 300'000);
  };
  pair(T0, false);  // the SDM of a pair whose SHM went out before the simulator listened
  CHECK(f.sut->safety().refused == 0);
  CHECK(f.sut->safety().ok == 0);
  pair(T0 + 20 * MS, true);  // synchronises
  pair(T0 + 40 * MS, true);
  CHECK(f.sut->safety().refused == 0);
  CHECK(f.sut->safety().ok == 1);
  pair(T0 + 60 * MS, false);  // listening since: an SDM without its SHM is refused
  CHECK(f.sut->safety().refused == 1);
  CHECK(f.sut->safety().lastRefusal == j1939::SafetyResult::MissingHeader);
}
