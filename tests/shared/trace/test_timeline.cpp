// LogTimeline (several logs merged by time, bad lines and backward steps reported) and the
// analysis setup from DBC files or the HHEA vehicle configuration (issue 21).
#include <doctest/doctest.h>

#include <vector>

#include "openvcu/trace/timeline.hpp"
#include "trace_test_support.hpp"

using namespace openvcu;
using namespace openvcu::trace;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0 = 1'000'000'000;  ///< (1.000000)
/// config/hhea/schedule.json: S1_ES, HVESSC1, CN, CCVS1 and AMB carry "safety.deltaUs".
constexpr std::size_t SCHEDULE_SAFETY_PAIRS = 5;

struct Collected {
  std::vector<TraceFrame> frames;
  std::vector<Error> errors;
};

Collected readAll(const std::vector<std::string>& paths, const AnalysisSetup& setup,
                  std::vector<std::string>* buses = nullptr, std::vector<LogCounts>* counts = nullptr) {
  Collected collected;
  auto timelineResult =
      LogTimeline::open(paths, setup, [&collected](const Error& error) { collected.errors.push_back(error); });
  REQUIRE(timelineResult);
  TraceFrame frame;
  while (timelineResult->next(frame)) collected.frames.push_back(frame);
  if (buses != nullptr) *buses = timelineResult->buses();
  if (counts != nullptr) *counts = timelineResult->counts();
  return collected;
}

/// OBC with GenMsgCycleTime 100 ms, Status without.
constexpr const char* CYCLE_DBC = R"(VERSION ""
NS_ :
BS_:
BU_: VCU OBC
BO_ 2566869221 OBC: 8 OBC
 SG_ State : 0|8@1+ (1,0) [0|255] "" VCU
BO_ 291 Status: 8 VCU
 SG_ Mode : 0|8@1+ (1,0) [0|255] "" OBC
BA_DEF_ BO_ "GenMsgCycleTime" INT 0 65535;
BA_DEF_DEF_ "GenMsgCycleTime" 0;
BA_ "GenMsgCycleTime" BO_ 2566869221 100;
)";

}  // namespace

TEST_CASE("timeline merges two logs in time order, the earlier log first on ties") {
  test::ScratchFolder folder;
  const std::string first = folder.write("a.log",
                                         "(1.000000) can0 18FF50E5#01\n"
                                         "(1.020000) can0 18FF50E5#02\n"
                                         "(1.050000) can0 18FF50E5#03\n");
  const std::string second = folder.write("b.log",
                                          "(1.010000) can1 123#01\n"
                                          "(1.030000) can1 123#02\n"
                                          "(1.050000) can1 123#03\n");
  AnalysisSetup setup = emptySetup();
  setup.database = test::smallDatabase();
  std::vector<std::string> buses;
  std::vector<LogCounts> counts;
  const Collected collected = readAll({first, second}, setup, &buses, &counts);

  REQUIRE(collected.frames.size() == 6);
  const std::int64_t times[] = {0, 10, 20, 30, 50, 50};
  const std::uint16_t logs[] = {0, 1, 0, 1, 0, 1};
  for (std::size_t i = 0; i < 6; ++i) {
    CHECK(collected.frames[i].timeNs == T0 + times[i] * MS);
    CHECK(collected.frames[i].log == logs[i]);
    CHECK(collected.frames[i].frame.timestampNs == collected.frames[i].timeNs);
  }
  CHECK(collected.frames[0].message == 0);  // OBC
  CHECK(collected.frames[1].message == 1);  // Status
  CHECK(collected.frames[1].bus == 1);
  CHECK(collected.frames[1].line == 1);
  CHECK(collected.frames[4].line == 3);
  CHECK(buses == std::vector<std::string>{"can0", "can1"});
  REQUIRE(counts.size() == 2);
  CHECK(counts[0].frames == 3);
  CHECK(counts[1].frames == 3);
  CHECK(collected.errors.empty());
}

TEST_CASE("timeline reports a malformed line with file and line and goes on") {
  test::ScratchFolder folder;
  const std::string log = folder.write("bad.log",
                                       "(1.000000) can0 123#01\n"
                                       "(1.010000) can0 123#01\n"
                                       "this is not a frame\n"
                                       "(1.030000) can0 123#01\n");
  std::vector<LogCounts> counts;
  const Collected collected = readAll({log}, emptySetup(), nullptr, &counts);
  CHECK(collected.frames.size() == 3);
  REQUIRE(collected.errors.size() == 1);
  CHECK(collected.errors[0].location.file == log);
  CHECK(collected.errors[0].location.line == 3);
  CHECK(counts.at(0).malformedLines == 1);
}

TEST_CASE("timeline keeps a frame older than its log's previous one, reports it once and counts each") {
  test::ScratchFolder folder;
  const std::string log = folder.write("back.log",
                                       "(2.000000) can0 123#01\n"
                                       "(3.000000) can0 123#01\n"
                                       "(2.500000) can0 123#01\n"
                                       "(2.400000) can0 123#01\n"
                                       "(2.600000) can0 123#01\n");
  std::vector<LogCounts> counts;
  const Collected collected = readAll({log}, emptySetup(), nullptr, &counts);
  CHECK(collected.frames.size() == 5);
  CHECK(counts.at(0).backwards == 2);
  REQUIRE(collected.errors.size() == 1);
  CHECK(collected.errors[0].location.line == 3);
  CHECK(collected.errors[0].message.find("backwards") != std::string::npos);
}

TEST_CASE("timeline names buses by the logs' channels, as vcu record writes them") {
  test::ScratchFolder folder;
  const std::string vehicle = folder.write("vehicle.log",
                                           "(1.000000) vehicle 18FF50E5#01\n"
                                           "(1.002000) vehicle 18FF50E5#01\n");
  const std::string powertrain = folder.write("powertrain.log", "(1.001000) powertrain 123#01\n");
  std::vector<std::string> buses;
  const Collected collected = readAll({vehicle, powertrain}, emptySetup(), &buses);
  CHECK(buses == std::vector<std::string>{"vehicle", "powertrain"});
  REQUIRE(collected.frames.size() == 3);
  CHECK(collected.frames[1].bus == 1);
  CHECK(collected.frames[2].bus == 0);
}

TEST_CASE("timeline open fails naming a log that does not exist") {
  auto timelineResult = LogTimeline::open({"/nonexistent/drive.log"}, emptySetup());
  REQUIRE_FALSE(timelineResult);
  CHECK(timelineResult.error().toString().find("/nonexistent/drive.log") != std::string::npos);
}

TEST_CASE("setup from DBC files takes GenMsgCycleTime and the transmitters as node names") {
  test::ScratchFolder folder;
  const std::string dbc = folder.write("cycle.dbc", CYCLE_DBC);
  auto setupResult = loadSetupFromDbc({dbc});
  REQUIRE(setupResult);
  const AnalysisSetup& setup = *setupResult;
  REQUIRE(setup.expectedCycleNs.size() == 2);
  CHECK(setup.expectedCycleNs[0] == 100 * MS);
  CHECK(setup.cycleSource[0] == CycleSource::Attribute);
  CHECK(setup.expectedCycleNs[1] == 0);
  CHECK(setup.cycleSource[1] == CycleSource::None);
  CHECK(setup.nodeNames[0xE5] == "OBC");
  CHECK(setup.nodeNames[0x00].empty());
  CHECK(setup.source == dbc);
  CHECK(setup.bus("can0").bitrate == 500'000);  // not configured: the defaults
}

TEST_CASE("setup from DBC files fails naming a missing file") {
  auto setupResult = loadSetupFromDbc({"/nonexistent/missing.dbc"});
  REQUIRE_FALSE(setupResult);
  CHECK(setupResult.error().toString().find("missing.dbc") != std::string::npos);
}

TEST_CASE("setup from the HHEA configuration has the schedule's cycles, bit rates and safety pairs") {
  auto setupResult = loadSetupFromConfig(std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json");
  REQUIRE(setupResult);
  const AnalysisSetup& setup = *setupResult;
  REQUIRE_FALSE(setup.buses.empty());
  CHECK(setup.bus(setup.buses[0].name).bitrate == setup.buses[0].bitrate);

  const dbc::Message* ignitionMessage = setup.database.findMessage("S1_ES_PGN61427");
  REQUIRE(ignitionMessage != nullptr);
  const auto index = static_cast<std::size_t>(ignitionMessage - setup.database.messages.data());
  const auto ignition = static_cast<std::int32_t>(index);
  CHECK(setup.cycleSource[index] == CycleSource::Schedule);
  CHECK(setup.expectedCycleNs[index] == 20 * MS);  // "J1939-76 SDM every 20 ms"

  // The schedule's SDMs with their deltas (0.292, 0.567, 1.427 and 2 ms), and the received
  // pairs of the receive configuration with its SRVT/SCT.
  std::size_t withDelta = 0;
  for (const SafetyPairSetup& pair : setup.safetyPairs) {
    if (pair.deltaNs > 0) ++withDelta;
    CHECK(pair.message >= 0);
    CHECK(pair.maxHeaderToDataNs > 0);
  }
  CHECK(withDelta == SCHEDULE_SAFETY_PAIRS);
  bool ignitionDelta = false;
  for (const SafetyPairSetup& pair : setup.safetyPairs) {
    if (pair.message == ignition && pair.deltaNs == 292'000) {
      ignitionDelta = true;
      CHECK(pair.switchedBy == "keepAlive");  // the schedule's send group
    }
  }
  CHECK(ignitionDelta);
  // hhea.dbc: the VCU's HC1_Demands and the HVLP string's HS2_Status_Feedback both use 0x71
  CHECK(setup.nodeNames[0x71] == "Vehicle_Control_Unit/HVLP_SA71");
  CHECK(setup.nodeNames[0xFD] == "Editron");
}
