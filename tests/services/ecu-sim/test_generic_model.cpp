// Issue 22: vcu-ecu-sim's generic model with a fake clock on tests/data/ecu-sim (a small
// non-HHEA vehicle): a rule with `after` and `otherwise`, follow, integrate with clamping,
// a fault overriding a rule, and the values on the frames the bus sends.

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

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string GENERIC = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/ecu-sim/vehicle.json";
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

  /// `simulationText` empty: the test vehicle's own simulation.json.
  explicit Fixture(const std::string& simulationText = "") {
    auto loaded = config::loadVehicleConfig(GENERIC);
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

  /// A VCU frame of `name` with `values` encoded (the rest zero).
  void receive(const std::string& name, const std::map<std::string, double>& values) {
    const dbc::Message* message = vehicle.database.findMessage(name);
    REQUIRE_MESSAGE(message, name);
    const auto index = static_cast<std::size_t>(message - vehicle.database.messages.data());
    can::Frame frame;
    frame.id = message->id;
    frame.length = static_cast<std::uint8_t>(message->length);
    for (const auto& [signal, value] : values) {
      const auto* found = message->findSignal(signal);
      REQUIRE_MESSAGE(found, signal);
      const auto signalIndex = static_cast<std::uint32_t>(found - message->signals.data());
      REQUIRE(codecs[index].encode(signalIndex, value, std::span<std::uint8_t>(frame.data.data(), frame.length)) ==
              dbc::EncodeStatus::Ok);
    }
    sut->receive(frame, now);
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
