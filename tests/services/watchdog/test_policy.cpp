// What vcu-watchdog watches: the safety case's "watchdog" section, the defaults without one,
// and a refusal naming the file and JSON path for a service the stack does not have.

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "policy.hpp"

namespace fs = std::filesystem;
using namespace openvcu;

namespace {

/// config/hhea copied to a fresh folder; `edit` changes its vehicle.json before it is written.
struct VehicleCopy {
  fs::path folder;
  template <typename Edit>
  explicit VehicleCopy(const Edit& edit) {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp != nullptr ? tmp : "/tmp") + "/openvcu-policy-XXXXXX";
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    folder = pattern;
    for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config" / "hhea")) {
      fs::copy(entry.path(), folder / entry.path().filename());
    }
    std::ifstream in(folder / "vehicle.json");
    nlohmann::json vehicle = nlohmann::json::parse(in);
    edit(vehicle);
    std::ofstream(folder / "vehicle.json") << vehicle.dump(2);
  }
  ~VehicleCopy() { fs::remove_all(folder); }
  void writeSafety(const nlohmann::json& safety) const { std::ofstream(folder / "safety.json") << safety.dump(2); }
  [[nodiscard]] Result<watchdog::WatchedPolicy> policy() const {
    auto vehicle = config::loadVehicleConfig((folder / "vehicle.json").string());
    REQUIRE_MESSAGE(vehicle.ok(), (vehicle.ok() ? "" : vehicle.error().toString()));
    auto catalog = config::buildCatalog(*vehicle);
    REQUIRE(catalog.ok());
    return watchdog::policyOf(*vehicle, *catalog);
  }
};

}  // namespace

TEST_CASE("the shipped HHEA vehicle is watched as its safety case says") {
  const VehicleCopy sut([](nlohmann::json&) {});
  const auto policy = sut.policy();
  REQUIRE_MESSAGE(policy.ok(), (policy.ok() ? "" : policy.error().toString()));
  CHECK(policy->services == std::vector<std::string>{"can-rx", "can-tx", "fsm", "gpio"});
  CHECK(policy->silentAfterMs == 2500);
  CHECK(policy->restart);
  CHECK(policy->device.empty());
  CHECK(policy->origin.find("safety.json /watchdog") != std::string::npos);
}

TEST_CASE("a vehicle without a safety case is watched with the defaults") {
  const VehicleCopy sut([](nlohmann::json& vehicle) { vehicle.erase("safety"); });
  const auto policy = sut.policy();
  REQUIRE(policy.ok());
  CHECK(policy->services == std::vector<std::string>{"can-rx", "can-tx", "fsm", "gpio"});
  CHECK(policy->silentAfterMs == watchdog::DEFAULT_SILENT_AFTER_MS);
  CHECK(policy->restart);
  CHECK(policy->device.empty());
  CHECK(policy->origin.find("names no safety case") != std::string::npos);
}

TEST_CASE("the safety case's watchdog section sets services, silence, restart and device") {
  const VehicleCopy sut([](nlohmann::json&) {});
  sut.writeSafety(
      {{"watchdog", {{"services", {"fsm"}}, {"silentAfterMs", 700}, {"restart", false}, {"device", "/dev/watchdog1"}}},
       {"hazards", nlohmann::json::array()}});
  const auto policy = sut.policy();
  REQUIRE_MESSAGE(policy.ok(), (policy.ok() ? "" : policy.error().toString()));
  CHECK(policy->services == std::vector<std::string>{"fsm"});
  CHECK(policy->silentAfterMs == 700);
  CHECK_FALSE(policy->restart);
  CHECK(policy->device == "/dev/watchdog1");
}

TEST_CASE("a watched service the stack does not have is refused with the file and JSON path") {
  const VehicleCopy sut([](nlohmann::json&) {});
  sut.writeSafety(
      {{"watchdog", {{"services", {"fsm", "fms"}}, {"silentAfterMs", 1500}}}, {"hazards", nlohmann::json::array()}});
  const auto policy = sut.policy();
  REQUIRE_FALSE(policy.ok());
  const std::string message = policy.error().toString();
  CHECK_MESSAGE(message.find("safety.json") != std::string::npos, message);
  CHECK_MESSAGE(message.find("/watchdog/services/1") != std::string::npos, message);
  CHECK_MESSAGE(message.find("fms") != std::string::npos, message);
}
