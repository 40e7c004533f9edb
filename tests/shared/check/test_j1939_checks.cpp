// The J1939-81 address policy on a safety network (shared/check j1939_checks.cpp), on a copy
// of config/hhea: the VCU sends J1939-76 pairs (S1_ES, ...) on its bus "vehicle" from 0x21.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "openvcu/check/vehicle_check.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const fs::path HHEA = fs::path(OPENVCU_SOURCE_DIR) / "config" / "hhea";
const std::string POLICY_PATH = "/buses/0/j1939/name/arbitraryAddressCapable";

/// A copy of config/hhea whose vehicle.json and schedule.json the case may change.
class HheaCopy {
 public:
  HheaCopy() {
    static int counter = 0;
    m_dir = fs::temp_directory_path() /
            ("openvcu-j1939-check-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    fs::create_directories(m_dir);
    for (const auto& entry : fs::directory_iterator(HHEA)) {
      if (entry.is_regular_file()) fs::copy_file(entry.path(), m_dir / entry.path().filename());
    }
    vehicle = read("vehicle.json");
    schedule = read("schedule.json");
  }
  ~HheaCopy() { fs::remove_all(m_dir); }
  HheaCopy(const HheaCopy&) = delete;
  HheaCopy& operator=(const HheaCopy&) = delete;

  nlohmann::json vehicle;
  nlohmann::json schedule;

  /// Writes both files back and runs the whole-vehicle checks.
  std::vector<Error> check() {
    std::ofstream(m_dir / "vehicle.json") << vehicle.dump(2);
    std::ofstream(m_dir / "schedule.json") << schedule.dump(2);
    auto loaded = config::loadVehicleConfig((m_dir / "vehicle.json").string());
    REQUIRE_MESSAGE(loaded.ok(), loaded.error().toString());
    auto catalog = config::buildCatalog(*loaded);
    REQUIRE_MESSAGE(catalog.ok(), catalog.error().toString());
    return check::checkVehicle(*loaded, *catalog);
  }
  [[nodiscard]] std::string file(const std::string& name) const { return (m_dir / name).string(); }

 private:
  nlohmann::json read(const std::string& name) const {
    std::ifstream in(m_dir / name);
    return nlohmann::json::parse(in);
  }
  fs::path m_dir;
};

std::vector<Error> atPolicy(const std::vector<Error>& all) {
  std::vector<Error> found;
  std::copy_if(all.begin(), all.end(), std::back_inserter(found),
               [](const Error& e) { return e.location.jsonPath == POLICY_PATH; });
  return found;
}

std::string describe(const std::vector<Error>& all) {
  std::string text;
  for (const Error& e : all) text += e.toString() + "\n";
  return text;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("the shipped HHEA vehicle keeps a fixed J1939 address where it sends its safety pairs") {
  HheaCopy sut;
  const auto diagnostics = sut.check();
  CHECK_MESSAGE(atPolicy(diagnostics).empty(), describe(diagnostics));
  CHECK(sut.vehicle["buses"][0]["j1939"]["name"]["arbitraryAddressCapable"] == false);
}

TEST_CASE("an arbitrary-address-capable NAME on a bus with J1939-76 pairs is a warning at its JSON path") {
  HheaCopy sut;
  sut.vehicle["buses"][0]["j1939"]["name"]["arbitraryAddressCapable"] = true;
  const auto found = atPolicy(sut.check());
  REQUIRE(found.size() == 1);
  CHECK(found[0].severity == Severity::Warning);
  CHECK(found[0].location.file == sut.file("vehicle.json"));
  CHECK(contains(found[0].message, "bus 'vehicle'"));
  CHECK(contains(found[0].message, "S1_ES_PGN61427"));
  CHECK(contains(found[0].message, "from 0x21 (33)"));
  CHECK(contains(found[0].message, "arbitrary address capable"));
  CHECK(contains(found[0].message, "\"arbitraryAddressCapable\": false"));
}

TEST_CASE("an arbitrary-address-capable NAME is no warning where no safety pair is sent or no claim runs") {
  HheaCopy sut;
  sut.vehicle["buses"][0]["j1939"]["name"]["arbitraryAddressCapable"] = true;
  SUBCASE("no claim on the bus") {
    sut.vehicle["buses"][0]["j1939"]["claim"] = false;
    CHECK(atPolicy(sut.check()).empty());
  }
  SUBCASE("no J1939-76 pair in the schedule") {
    for (auto& [name, entry] : sut.schedule["messages"].items()) entry.erase("safety");
    const auto diagnostics = sut.check();
    CHECK_MESSAGE(atPolicy(diagnostics).empty(), describe(diagnostics));
  }
}
