// diagnostics.json (config/diagnostics.hpp): every key, the checks with file and JSON path,
// and the occurrence-count file (atomic save, a corrupt file set aside). Issue 24.

#include <doctest/doctest.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "config_fixture.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/diagnostics.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::vector<std::string> FSM_STATES = {"Ready", "Battery Fault", "Crash"};

/// A scratch folder with the small test vehicle; diagnostics.json is written into it.
class DiagnosticsFixture {
 public:
  DiagnosticsFixture() {
    m_dir = fs::temp_directory_path() /
            ("openvcu-diagnostics-test-" + std::to_string(::getpid()) + "-" + std::to_string(s_counter++));
    fs::create_directories(m_dir);
    auto loaded = config::loadVehicleConfig(test::CONFIG_DATA_DIR + "/small.json");
    REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
    vehicle = std::move(*loaded);
    vehicle.fsmFile = (m_dir / "fsm.json").string();  // named only: the state list is passed in
    vehicle.diagnosticsFile = (m_dir / "diagnostics.json").string();
    auto built = config::buildCatalog(vehicle);
    REQUIRE(built);
    catalog = std::move(*built);
  }
  ~DiagnosticsFixture() { fs::remove_all(m_dir); }
  DiagnosticsFixture(const DiagnosticsFixture&) = delete;
  DiagnosticsFixture& operator=(const DiagnosticsFixture&) = delete;

  Result<config::DiagnosticsConfig> load(const std::string& text) {
    std::ofstream(vehicle.diagnosticsFile) << text;
    return config::loadDiagnosticsConfig(vehicle, catalog, &FSM_STATES);
  }
  std::string errorOf(const std::string& text) {
    auto result = load(text);
    REQUIRE_FALSE(result);
    return result.error().toString();
  }
  [[nodiscard]] std::string file(const std::string& name) const { return (m_dir / name).string(); }

  config::VehicleConfig vehicle;
  signals::Catalog catalog;

 private:
  fs::path m_dir;
  static inline int s_counter = 0;
};

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("diagnostics.json with every key loads into DTC definitions, policies and identification") {
  DiagnosticsFixture fixture;
  auto loaded = fixture.load(R"({
    "comment": "test",
    "dtcs": [
      {"name": "battery", "fsmState": "Battery Fault", "spn": 520192, "fmi": 12, "lamps": ["red"], "comment": "c"},
      {"name": "mode fault", "signal": "BMS.Status.Mode", "activeWhen": {"eq": "Fault"}, "spn": 520193, "fmi": 31,
       "lamps": ["amber", "protect"], "flash": {"amber": "fast"}},
      {"name": "start", "signal": "internal.operator.Start", "spn": 520194, "fmi": 31, "lamps": []},
      {"name": "soc", "signal": "BMS.Status.SOC", "activeWhen": {"lt": 20}, "spn": 520195, "fmi": 18}
    ],
    "dm3": "accept", "dm11": "refuse", "dm1PeriodMs": 500,
    "identification": {
      "software": ["openvcu"],
      "ecu": {"partNumber": "P1", "serialNumber": "S1", "location": "cab", "type": "VCU", "manufacturer": "M",
              "hardwareId": "H1"},
      "component": {"make": "LUT", "model": "HHEA", "serialNumber": "0001", "unitNumber": "1"}
    },
    "countsFile": "state/counts.json"
  })");
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
  const config::DiagnosticsConfig& sut = *loaded;
  REQUIRE(sut.dtcs.size() == 4);
  CHECK(sut.dtcs[0].source == config::DtcSource::FsmState);
  CHECK(sut.dtcs[0].fsmState == "Battery Fault");
  CHECK(sut.dtcs[0].definition.spn == 520192);
  CHECK(sut.dtcs[0].definition.fmi == 12);
  CHECK(sut.dtcs[0].definition.lamps == j1939::DtcLampRequest{.redStop = true});
  CHECK(sut.dtcs[1].source == config::DtcSource::Signal);
  CHECK(sut.dtcs[1].compare == config::DtcCompare::Eq);
  CHECK(sut.dtcs[1].value == 2);  // VAL_ "Fault"
  CHECK(sut.dtcs[1].definition.lamps ==
        j1939::DtcLampRequest{.protect = true, .amberWarning = true, .amberWarningFlash = j1939::LampFlash::Fast});
  CHECK(sut.dtcs[2].activeFor(1));  // without activeWhen: value != 0
  CHECK_FALSE(sut.dtcs[2].activeFor(0));
  CHECK(sut.dtcs[3].activeFor(19.5));
  CHECK_FALSE(sut.dtcs[3].activeFor(20));
  CHECK(sut.dm3 == config::ClearPolicy::Accept);
  CHECK(sut.dm11 == config::ClearPolicy::Refuse);
  CHECK(sut.dm1PeriodNs == 500'000'000);
  CHECK(sut.identification.software == std::vector<std::string>{"openvcu"});
  CHECK(sut.identification.hardwareId == "H1");
  CHECK(sut.identification.componentSerialNumber == "0001");
  CHECK(sut.countsFile == fixture.file("state/counts.json"));
  CHECK(sut.definitions().size() == 4);
  CHECK(j1939::DiagnosticState::create(sut.definitions()));
}

TEST_CASE("diagnostics defaults: no DTCs, clears refused, DM1 each second, counts beside the file") {
  DiagnosticsFixture fixture;
  auto loaded = fixture.load("{}");
  REQUIRE(loaded);
  CHECK(loaded->dtcs.empty());
  CHECK(loaded->dm3 == config::ClearPolicy::Refuse);
  CHECK(loaded->dm11 == config::ClearPolicy::Refuse);
  CHECK(loaded->dm1PeriodNs == 1'000'000'000);
  CHECK(loaded->countsFile == fixture.file("dtc_counts.json"));
}

TEST_CASE("diagnostics errors name the file and JSON path") {
  DiagnosticsFixture fixture;
  const std::string file = fixture.vehicle.diagnosticsFile;
  const auto dtc = [](const std::string& body) { return R"({"dtcs": [)" + body + "]}"; };

  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "spn": 524288, "fmi": 1})")) ==
        file + ": /dtcs/0/spn: must be a whole number from 0 to 524287, not 524288");
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "spn": 1, "fmi": 32})")) ==
        file + ": /dtcs/0/fmi: must be a whole number from 0 to 31, not 32");
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "spn": 0, "fmi": 0})")).find("/dtcs/0/spn") !=
        std::string::npos);
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "spn": 5, "fmi": 1},
                               {"name": "b", "fsmState": "Crash", "spn": 5, "fmi": 1})")) ==
        file + ": /dtcs/1: SPN 5 FMI 1 is already the DTC at /dtcs/0");
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Batery Fault", "spn": 5, "fmi": 1})")) ==
        file + ": /dtcs/0/fsmState: the FSM (" + fixture.vehicle.fsmFile +
            ") has no state 'Batery Fault'; did you mean 'Battery Fault'?");
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "signal": "internal.operator.Stat", "spn": 5, "fmi": 1})"))
            .find(file + ": /dtcs/0/signal: unknown signal 'internal.operator.Stat'") == 0);
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "signal": "BMS.Status.Mode", "activeWhen": {"eq": "Broken"},
                               "spn": 5, "fmi": 1})")) ==
        file + ": /dtcs/0/activeWhen/eq: signal 'BMS.Status.Mode' has no value named 'Broken'");
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "signal": "BMS.Status.Mode", "spn": 5, "fmi": 1})"))
            .find(file + ": /dtcs/0: give exactly one of") == 0);
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "spn": 5, "fmi": 1, "lamps": ["yellow"]})")) ==
        file + ": /dtcs/0/lamps/0: expected one of \"protect\", \"amber\", \"red\", \"malfunction\"");
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "spn": 5, "fmi": 1, "lamps": ["red"],
                               "flash": {"amber": "fast"}})")) ==
        file + ": /dtcs/0/flash/amber: lamp 'amber' is not in \"lamps\": only a lamp that is on flashes");
  CHECK(fixture.errorOf(dtc(R"({"name": "a", "fsmState": "Ready", "spn": 5, "fmi": 1},
                               {"name": "a", "fsmState": "Ready", "spn": 6, "fmi": 1})")) ==
        file + ": /dtcs/1/name: DTC name 'a' is given twice (first at /dtcs/0)");
  CHECK(fixture.errorOf(R"({"dm3": "maybe"})") == file + ": /dm3: expected \"accept\" or \"refuse\"");
  CHECK(fixture.errorOf(R"({"dm1PeriodMs": 5})").find(file + ": /dm1PeriodMs:") == 0);
  CHECK(fixture.errorOf(R"({"identification": {"ecu": {"type": "a*b"}}})").find(file + ": /identification/ecu/type:") ==
        0);
  CHECK(fixture.errorOf(R"({"dtc": []})").find(file + ": /dtc: unknown key") == 0);
}

TEST_CASE("DM3 or DM11 accepted from any node loads with a warning naming the file and JSON path") {
  DiagnosticsFixture fixture;
  fixture.load("{}");  // writes the file; the defaults refuse: no warning
  std::vector<Error> diagnostics;
  REQUIRE(config::loadDiagnosticsConfig(fixture.vehicle, fixture.catalog, &FSM_STATES, &diagnostics));
  CHECK(diagnostics.empty());

  std::ofstream(fixture.vehicle.diagnosticsFile) << R"({"dm3": "accept", "dm11": "accept"})";
  auto loaded = config::loadDiagnosticsConfig(fixture.vehicle, fixture.catalog, &FSM_STATES, &diagnostics);
  REQUIRE(loaded);
  CHECK(loaded->dm3 == config::ClearPolicy::Accept);
  REQUIRE(diagnostics.size() == 2);
  const std::string file = fixture.vehicle.diagnosticsFile;
  CHECK(diagnostics[0].severity == Severity::Warning);
  CHECK(diagnostics[0].toString().find(file + ": /dm3: warning: DM3 (clear previously active DTCs) is accepted "
                                              "from any node on the bus") == 0);
  CHECK(diagnostics[1].severity == Severity::Warning);
  CHECK(diagnostics[1].toString().find(file + ": /dm11: warning: DM11 (clear active DTCs) is accepted") == 0);
}

TEST_CASE("the shipped HHEA diagnostics refuse DM3 and DM11") {
  auto vehicle = config::loadVehicleConfig(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json");
  REQUIRE_MESSAGE(vehicle, (vehicle ? "" : vehicle.error().toString()));
  auto catalog = config::buildCatalog(*vehicle);
  REQUIRE(catalog);
  std::vector<Error> diagnostics;
  auto sut = config::loadDiagnosticsConfig(*vehicle, *catalog, nullptr, &diagnostics);
  REQUIRE_MESSAGE(sut, (sut ? "" : sut.error().toString()));
  CHECK(sut->dm3 == config::ClearPolicy::Refuse);
  CHECK(sut->dm11 == config::ClearPolicy::Refuse);
  CHECK(diagnostics.empty());
}

TEST_CASE("an fsmState DTC is refused when the vehicle has no FSM") {
  DiagnosticsFixture fixture;
  fixture.vehicle.fsmFile.clear();
  CHECK(fixture.errorOf(R"({"dtcs": [{"name": "a", "fsmState": "Ready", "spn": 5, "fmi": 1}]})")
            .find("/dtcs/0/fsmState: the vehicle has no FSM") != std::string::npos);
}

TEST_CASE("DTC counts survive a save and load, and the save leaves no temporary file") {
  DiagnosticsFixture fixture;
  const std::string path = fixture.file("dtc_counts.json");
  const std::array saved{j1939::Dtc{520192, 12, 3, false}, j1939::Dtc{100, 1, 126, false}};
  REQUIRE(config::saveDtcCounts(path, saved));
  CHECK(readFile(path).find(R"("format": 1)") != std::string::npos);
  const config::DtcCountsLoad sut = config::loadDtcCounts(path);
  CHECK_FALSE(sut.rejected);
  REQUIRE(sut.counts.size() == 2);
  CHECK(sut.counts[0] == saved[0]);
  CHECK(sut.counts[1] == saved[1]);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(fs::path(path).parent_path())) ++files;
  CHECK(files == 1);  // the counts file alone: the temporary file was renamed onto it
}

TEST_CASE("a missing counts file is no counts and no error") {
  DiagnosticsFixture fixture;
  const config::DtcCountsLoad sut = config::loadDtcCounts(fixture.file("none.json"));
  CHECK(sut.counts.empty());
  CHECK_FALSE(sut.rejected);
}

TEST_CASE("a corrupt counts file is set aside as .rejected and the counts start at 0") {
  DiagnosticsFixture fixture;
  const std::string path = fixture.file("dtc_counts.json");
  SUBCASE("not JSON") {
    std::ofstream(path) << "{\"format\": 1, \"counts\": [ {";
  }
  SUBCASE("a count out of range") {
    std::ofstream(path) << R"({"format": 1, "counts": [{"spn": 100, "fmi": 1, "count": 200}]})";
  }
  SUBCASE("a DTC twice") {
    std::ofstream(path) << R"({"format": 1, "counts": [{"spn": 100, "fmi": 1, "count": 2},
                                                     {"spn": 100, "fmi": 1, "count": 3}]})";
  }
  const config::DtcCountsLoad sut = config::loadDtcCounts(path);
  CHECK(sut.counts.empty());
  REQUIRE(sut.rejected);
  const std::string message = sut.rejected->toString();
  CHECK(message.find(path) == 0);
  CHECK(message.find("the occurrence counts start at 0 and the file was moved to " + path + ".rejected") !=
        std::string::npos);
  CHECK_FALSE(fs::exists(path));
  CHECK(fs::exists(path + ".rejected"));
}
