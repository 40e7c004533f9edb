// vcu-ecu-sim's parts with a fake clock on the HHEA configuration: the simulation file's
// refusals, the virtual bus, and the VIC's J1939-76 checks, keep-alive and HV connection,
// the PDU and the HVLP enable sequence.

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "openvcu/dbc/codec.hpp"
#include "openvcu/j1939/safety.hpp"
#include "sim_frames.hpp"
#include "openvcu/config/simulation.hpp"
#include "vehicle_model.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0 = 1000 * 1'000'000'000LL;

struct Fixture {
  config::VehicleConfig vehicle;
  config::SimConfig sim;
  std::optional<ecusim::VirtualBus> bus;
  std::optional<ecusim::VehicleModel> model;
  dbc::DatabaseCodec codecs;
  std::vector<can::Frame> sent;
  std::optional<j1939::SafetyPairBuilder> builder;
  std::vector<can::Frame> betweenShmAndSdm;  ///< sent after each S1_ES SHM, before its SDM
  std::vector<can::Frame> afterSdm;          ///< sent right after each S1_ES SDM

  Fixture() {
    auto loaded = config::loadVehicleConfig(HHEA);
    REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
    vehicle = std::move(*loaded);
    auto simResult = config::loadSimConfig(vehicle.simulationFile, vehicle);
    REQUIRE_MESSAGE(simResult, (simResult ? "" : simResult.error().toString()));
    sim = std::move(*simResult);
    auto busResult = ecusim::VirtualBus::create(vehicle);
    REQUIRE(busResult);
    bus.emplace(std::move(*busResult));
    auto modelResult = ecusim::VehicleModel::create(*bus, sim);
    REQUIRE_MESSAGE(modelResult, (modelResult ? "" : modelResult.error().toString()));
    model.emplace(std::move(*modelResult));
    codecs = dbc::DatabaseCodec(vehicle.database);
    builder.emplace(vehicle.database.findMessage("S1_ES_PGN61427")->id);
    bus->start(T0);
  }

  /// A VCU frame from the DBC's initial payload with `values` encoded.
  can::Frame frame(const std::string& name, const std::map<std::string, double>& values) {
    return ecusim::test::encodedFrame(vehicle.database, codecs, name, values);
  }

  /// The keep-alive and one S1_ES pair (SHM, then the SDM 0.3 ms later; `corrupt` flips a bit).
  void keepAlive(std::int64_t at, double relay, bool corrupt = false) {
    model->receive(frame("CCVS1_PGN65265", {}), at);
    model->receive(frame("HVESSC1_PGN6912", {{"HS_OperConsent", 1}}), at);
    model->receive(frame("CN_PGN61483", {{"Crash_Typ", 0}}), at);
    can::Frame data = frame("S1_ES_PGN61427", {{"Control_Es_Relay", relay}});
    const can::Frame shm = ecusim::test::safetyHeaderFor(*builder, data);
    if (corrupt) data.data[7] ^= 0x01;
    model->receive(shm, at);
    for (const can::Frame& other : betweenShmAndSdm) model->receive(other, at + 100'000);
    model->receive(data, at + 300'000);
    for (const can::Frame& other : afterSdm) model->receive(other, at + 300'000);
  }

  /// Runs the models and the bus from `from` to `to` in 10 ms steps, feeding the keep-alive.
  void run(std::int64_t from, std::int64_t to, double relay, bool corrupt = false) {
    for (std::int64_t t = from; t <= to; t += 10 * MS) {
      if ((t - from) % (20 * MS) == 0) keepAlive(t, relay, corrupt);  // the 20 ms cycle of S1_ES
      const auto send = [this](std::size_t, const can::Frame& f) { sent.push_back(f); };
      model->step(t, 1'795'268'730'000'000'000LL, true, send);
      model->sendDue(t, send);
    }
  }
};

}  // namespace

TEST_CASE("the HHEA simulation file loads, and a bad one is refused with its JSON path") {
  Fixture f;
  CHECK(f.sim.safety.size() == 1);
  CHECK(f.sim.safety[0].dataCanId == 0x0CEFF321u);
  CHECK(f.sim.wakeSignal == "internal.gpio.Cl15");
  const fs::path file = fs::temp_directory_path() / ("openvcu-sim-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << R"({"model": "hhea", "battery": {"capacityAh": -1, "colour": 1}, "timing": {"connect": "fast"},
    "safety": [{"message": "S1_ES"}]})";
  auto bad = config::loadSimConfig(file.string(), f.vehicle);
  fs::remove(file);
  REQUIRE_FALSE(bad);
  CHECK(bad.error().location.jsonPath == "/battery/colour");  // the first error
}

TEST_CASE("the VIC sleeps silent without the keep-alive and connects for driving on good J1939-76 pairs") {
  Fixture f;
  const auto send = [&f](std::size_t, const can::Frame& frame) { f.sent.push_back(frame); };
  f.model->step(T0, 0, true, send);
  f.model->sendDue(T0 + 200 * MS, send);
  for (const can::Frame& frame : f.sent) CHECK(frame.id != 0x14F096F3u);  // no HVESSS1: asleep
  CHECK_FALSE(f.model->awake());

  f.run(T0, T0 + 100 * MS, 0);
  CHECK(f.model->awake());
  CHECK(f.model->connection() == 0);  // awaiting HV request
  f.run(T0 + 110 * MS, T0 + 400 * MS, 3);
  CHECK(f.model->connection() == 2);  // precharging
  f.run(T0 + 410 * MS, T0 + 1000 * MS, 3);
  CHECK(f.model->connection() == 1);
  CHECK(f.model->safety().ok > 40);
  CHECK(f.model->safety().refused == 0);
  bool heard = false;
  for (const can::Frame& frame : f.sent) heard = heard || frame.id == 0x14F096F3u;
  CHECK(heard);
}

TEST_CASE("pairs with a bad CRC are refused and the VIC does not connect, and says why once") {
  Fixture f;
  f.run(T0, T0 + 1000 * MS, 3, true);
  CHECK(f.model->connection() == 0);
  CHECK(f.model->safety().ok == 0);
  CHECK(f.model->safety().refused > 40);
  CHECK(f.model->safety().lastRefusal == j1939::SafetyResult::CrcMismatch);
  const auto change = f.model->takeSafetyChange();
  REQUIRE(change);
  CHECK(*change == j1939::SafetyResult::CrcMismatch);
  CHECK_FALSE(f.model->takeSafetyChange());  // reported once, not per pair
}

TEST_CASE("the VIC judges no pairs while asleep and after waking again its first pair synchronises and none is refused") {
  Fixture f;
  f.run(T0, T0 + 1000 * MS, 3);
  REQUIRE(f.model->connection() == 1);
  const std::uint64_t okBefore = f.model->safety().ok;
  const auto send = [](std::size_t, const can::Frame&) {};
  f.model->step(T0 + 2300 * MS, 0, true, send);  // the VCU stopped: no keep-alive for over 1 s
  REQUIRE_FALSE(f.model->awake());
  // pairs resume 10 s later (far past the SCT): judged neither while it sleeps nor once woken
  f.run(T0 + 12'000 * MS, T0 + 13'000 * MS, 3);
  CHECK(f.model->awake());
  CHECK(f.model->safety().refused == 0);
  CHECK(f.model->safety().ok > okBefore + 40);
  CHECK(f.model->connection() == 1);

  // awake, a gap past the SCT is still refused (CycleTimeout): the check itself is unchanged
  f.run(T0 + 13'500 * MS, T0 + 13'600 * MS, 3);  // 500 ms without a pair, the keep-alive (1 s) not lost
  CHECK(f.model->awake());
  CHECK(f.model->safety().refused == 1);
}

TEST_CASE("a battery fault reports 14 and clears to awaiting, the keep-alive lost sends the VIC to sleep") {
  Fixture f;
  f.run(T0, T0 + 1000 * MS, 3);
  REQUIRE(f.model->connection() == 1);
  f.model->setFault(ecusim::Fault::Battery, true);
  f.run(T0 + 1010 * MS, T0 + 1100 * MS, 3);
  CHECK(f.model->connection() == 14);
  f.model->setFault(ecusim::Fault::Battery, false);
  f.run(T0 + 1110 * MS, T0 + 1200 * MS, 0);
  CHECK(f.model->connection() == 0);
  const auto send = [](std::size_t, const can::Frame&) {};
  f.model->step(T0 + 2300 * MS, 0, true, send);  // no keep-alive for over 1 s
  CHECK_FALSE(f.model->awake());
  CHECK(ecusim::faultByName("shm_expectation") == ecusim::Fault::ShmExpectation);
  CHECK_FALSE(ecusim::faultByName("batery"));
}

// ---- issue 18: the VIC finds the SDM as J1939-76 does: by PGN, SA and DA ----------------------

TEST_CASE("issue 18: a frame with S1_ES's PGN, SA and DA between its SHM and SDM is taken as the SDM: a CRC fault") {
  Fixture f;
  const can::Frame propA = f.frame("PropA_C4_PGN61184", {});
  REQUIRE(propA.id == 0x18EFF321u);  // priority 6; S1_ES is 0x0CEFF321, priority 3
  const can::Frame sdm = f.frame("S1_ES_PGN61427", {{"Control_Es_Relay", 3}});
  const can::Frame shm = ecusim::test::safetyHeaderFor(*f.builder, sdm);

  f.run(T0 - 200 * MS, T0 - 20 * MS, 0);  // awake (asleep, the VIC checks no pairs)
  REQUIRE(f.model->awake());
  REQUIRE(f.model->safety().refused == 0);
  const std::uint64_t okAwake = f.model->safety().ok;
  f.model->receive(shm, T0);
  f.model->receive(propA, T0 + 100'000);
  CHECK(f.model->safety().last == j1939::SafetyResult::CrcMismatch);  // PropA_C4 taken as the SDM
  CHECK(f.model->safety().refused == 1);
  f.model->receive(sdm, T0 + 300'000);  // its SHM is used up: not used, and not judged twice
  CHECK(f.model->safety().last == j1939::SafetyResult::CrcMismatch);
  CHECK(f.model->safety().refused == 1);
  CHECK(f.model->takeSafetyChange() == j1939::SafetyResult::CrcMismatch);
  f.model->receive(sdm, T0 + 400'000);  // an SDM with no SHM at all
  CHECK(f.model->safety().last == j1939::SafetyResult::MissingHeader);
  CHECK(f.model->safety().refused == 2);

  f.betweenShmAndSdm.push_back(propA);  // every pair so: the VIC never connects
  f.run(T0 + 20 * MS, T0 + 1000 * MS, 3);
  CHECK(f.model->connection() == 0);
  CHECK(f.model->safety().ok == okAwake);
  CHECK(f.model->safety().last == j1939::SafetyResult::CrcMismatch);  // the cause, every pair
}

TEST_CASE("issue 18: the same frame after the SDM is an ordinary frame and the pairs stay good") {
  Fixture f;
  f.afterSdm.push_back(f.frame("PropA_C4_PGN61184", {}));
  f.run(T0, T0 + 1000 * MS, 3);
  CHECK(f.model->connection() == 1);
  CHECK(f.model->safety().ok > 40);
  CHECK(f.model->safety().refused == 0);
}

TEST_CASE("issue 18: an SHM naming another SDM to the same DA is not taken for S1_ES's, whatever its priority") {
  Fixture f;
  // HVESSC1's SHM (PGN 0x1B00 to 0xF3) sent at S1_ES's priority 3: the very identifier of S1_ES's SHM
  j1939::SafetyPairBuilder hvesscPair(0x0C1BF321u);
  const can::Frame hvessc = f.frame("HVESSC1_PGN6912", {{"HS_OperConsent", 1}});
  const can::Frame shm = ecusim::test::safetyHeaderFor(hvesscPair, hvessc);
  REQUIRE(shm.id == 0x0C0EF321u);
  f.betweenShmAndSdm.push_back(shm);
  f.run(T0, T0 + 1000 * MS, 3);
  CHECK(f.model->connection() == 1);
  CHECK(f.model->safety().refused == 0);
}
