// `vcu trace stats` in-process on generated candump logs: the JSON figures, the text
// tables, a missing DBC and malformed lines (issue 21).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "openvcu/can/wire_time.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;

namespace {

/// OBC (SA 0xE5) every 10 ms by GenMsgCycleTime; Status without a cycle.
constexpr const char* STATS_DBC = R"(VERSION ""
NS_ :
BS_:
BU_: VCU OBC
BO_ 2566869221 OBC: 8 OBC
 SG_ State : 0|8@1+ (1,0) [0|255] "" VCU
BO_ 291 Status: 2 VCU
 SG_ Mode : 0|8@1+ (1,0) [0|255] "" OBC
BA_DEF_ BO_ "GenMsgCycleTime" INT 0 65535;
BA_DEF_DEF_ "GenMsgCycleTime" 0;
BA_ "GenMsgCycleTime" BO_ 2566869221 10;
)";

constexpr int OBC_SLOTS = 101;        ///< 1.000 .. 2.000 s every 10 ms
constexpr int DROPPED_SLOT = 50;      ///< -> one 20 ms period: 1 gap, 1 missing
constexpr int STATUS_FRAMES = 10;     ///< 1.005 .. 1.905 s every 100 ms
constexpr int MALFORMED_LINE = 7;     ///< the 7th line of the log

/// The candump -L log: OBC and Status in time order, the malformed line at MALFORMED_LINE.
std::string statsLog() {
  std::vector<std::string> lines;
  char text[96];
  for (int slot = 0; slot < OBC_SLOTS; ++slot) {
    if (slot != DROPPED_SLOT) {
      std::snprintf(text, sizeof text, "(%.6f) can0 18FF50E5#0102030405060708", 1.0 + slot * 0.010);
      lines.emplace_back(text);
    }
    if (slot % 10 == 0 && slot / 10 < STATUS_FRAMES) {
      std::snprintf(text, sizeof text, "(%.6f) can0 123#0102", 1.005 + (slot / 10) * 0.100);
      lines.emplace_back(text);
    }
  }
  lines.insert(lines.begin() + (MALFORMED_LINE - 1), "(1.0xx) can0 garbage");
  std::string log;
  for (const std::string& line : lines) log += line + "\n";
  return log;
}

openvcu::can::Frame frameOf(std::uint32_t id, bool extended, std::uint8_t length) {
  openvcu::can::Frame frame;
  frame.id = id;
  frame.flags = extended ? openvcu::can::FLAG_EXTENDED : 0;
  frame.length = length;
  for (std::uint8_t i = 0; i < length; ++i) frame.data[i] = static_cast<std::uint8_t>(i + 1);
  return frame;
}

}  // namespace

TEST_CASE("vcu trace stats prints JSON figures of a generated log and reports the malformed line") {
  const std::string dbc = writeScratchFile("trace_stats.dbc", STATS_DBC);
  const std::string log = writeScratchFile("trace_stats.log", statsLog());
  const RunResult result = runVcu({"trace", "stats", "--dbc", dbc, log, "--format", "json"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);  // the malformed line
  CHECK(contains(result.err, log + ":" + std::to_string(MALFORMED_LINE) + ":"));
  const nlohmann::json json = nlohmann::json::parse(result.out);

  const int obcFrames = OBC_SLOTS - 1;
  CHECK(json["frames"] == obcFrames + STATUS_FRAMES);
  REQUIRE(json["buses"].size() == 1);
  const nlohmann::json& bus = json["buses"][0];
  CHECK(bus["bus"] == "can0");
  CHECK(bus["bitrate"] == 500000);
  // Wire time at 500 kbit/s (2 us a bit) over the 1.000 s from the first to the last frame.
  const double wireS = (obcFrames * openvcu::can::frameBits(frameOf(0x18FF50E5, true, 8)) +
                        STATUS_FRAMES * openvcu::can::frameBits(frameOf(0x123, false, 2))) * 2e-6;
  CHECK(std::abs(bus["load_mean_pct"].get<double>() - 100.0 * wireS / 1.0) <= 0.0051);
  // Less than 1 s + one step of traffic: the peak window holds it all.
  CHECK(bus["load_max_pct"].get<double>() <= bus["load_mean_pct"].get<double>() + 0.01);

  REQUIRE(json["nodes"].size() == 2);
  CHECK(json["nodes"][0]["sa"] == 0xE5);
  CHECK(json["nodes"][0]["name"] == "OBC");
  CHECK(json["nodes"][0]["frames"] == obcFrames);
  CHECK(json["nodes"][1]["standard"] == true);
  CHECK(json["nodes"][1]["frames"] == STATUS_FRAMES);
  const double shares = json["nodes"][0]["share_pct"].get<double>() + json["nodes"][1]["share_pct"].get<double>();
  CHECK(std::abs(shares - 100.0) <= 0.011);

  REQUIRE(json["messages"].size() == 2);
  const nlohmann::json& status = json["messages"][0];
  CHECK(status["id"] == "0x123");
  CHECK(status["name"] == "Status");
  CHECK(status["count"] == STATUS_FRAMES);
  CHECK(status["expected_ms"].is_null());
  CHECK(status["mean_ms"] == 100.0);
  CHECK(status["max_ms"] == 100.0);
  const nlohmann::json& obc = json["messages"][1];
  CHECK(obc["id"] == "0x18FF50E5");
  CHECK(obc["name"] == "OBC");
  CHECK(obc["count"] == obcFrames);
  CHECK(obc["expected_ms"] == 10.0);
  CHECK(obc["cycle_source"] == "GenMsgCycleTime");
  // 99 periods over 1000 ms: 98 x 10 ms and one 20 ms.
  CHECK(obc["mean_ms"] == std::round(1000.0 / 99.0 * 1000.0) / 1000.0);
  CHECK(obc["p50_ms"] == 10.0);
  CHECK(obc["p99_ms"] == 20.0);  // nearest rank ceil(0.99 x 99) = 99: the 20 ms period
  CHECK(obc["max_ms"] == 20.0);
  CHECK(obc["gaps"] == 1);
  CHECK(obc["missing"] == 1);
}

TEST_CASE("vcu trace stats text has the bus, node and message tables") {
  const std::string dbc = writeScratchFile("trace_stats_text.dbc", STATS_DBC);
  const std::string log = writeScratchFile("trace_stats_text.log", statsLog());
  const RunResult result = runVcu({"trace", "stats", "--dbc", dbc, log});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  for (const char* part : {"Buses", "Nodes", "Messages", "LOAD MEAN %", "LOAD PEAK %", "BIT/S", "SHARE %",
                           "EXPECTED", "P99", "MISSING", "0x18FF50E5  OBC", "500 kbit/s"}) {
    CHECK_MESSAGE(contains(result.out, part), part);
  }
  CHECK(contains(result.err, "1 malformed lines skipped"));
}

TEST_CASE("vcu trace stats without its DBC says so, exits 1 and still gives the statistics") {
  std::string log;
  for (int i = 0; i < 5; ++i) log += "(1." + std::to_string(i) + "00000) can0 18FF50E5#01\n";
  const std::string path = writeScratchFile("trace_stats_nodbc.log", log);
  const RunResult result = runVcu({"trace", "stats", "--dbc", "/nonexistent/vehicle.dbc", path, "-f", "json"});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "/nonexistent/vehicle.dbc"));
  CHECK(contains(result.err, "going on without a DBC"));
  const nlohmann::json json = nlohmann::json::parse(result.out);
  REQUIRE(json["messages"].size() == 1);
  CHECK(json["messages"][0]["name"].is_null());
  CHECK(json["messages"][0]["count"] == 5);
  CHECK(json["messages"][0]["mean_ms"] == 100.0);
}

TEST_CASE("vcu trace stats of a clean log exits 0") {
  const std::string path = writeScratchFile("trace_stats_clean.log", "(1.000000) can0 123#01\n(1.010000) can0 123#01\n");
  const RunResult result = runVcu({"trace", "stats", path});
  CHECK(result.exitCode == EXIT_OK);
  CHECK(result.err.empty());
  CHECK(contains(result.out, "Setup: no DBC"));
}

TEST_CASE("vcu trace stats of a log that does not exist exits 1 naming it") {
  const RunResult result = runVcu({"trace", "stats", "/nonexistent/drive.log"});
  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.err, "/nonexistent/drive.log"));
}

TEST_CASE("vcu trace stats of a vcu record folder reads its logs as one timeline, a bus per channel") {
  std::filesystem::create_directories(scratchFolder() / "record");
  const std::string vehicle = writeScratchFile("record/vehicle.log",
                                               "(1.000000) vehicle 18FF50E5#01\n(1.020000) vehicle 18FF50E5#01\n");
  writeScratchFile("record/powertrain.log", "(1.010000) powertrain 123#01\n(1.040000) powertrain 123#01\n");
  writeScratchFile("record/notes.txt", "not a log\n");
  const std::string folder = std::filesystem::path(vehicle).parent_path().string();
  const RunResult result = runVcu({"trace", "stats", folder, "--format", "json"});
  CHECK(result.exitCode == EXIT_OK);
  const nlohmann::json json = nlohmann::json::parse(result.out);
  CHECK(json["frames"] == 4);
  CHECK(json["duration_s"] == 0.04);
  REQUIRE(json["buses"].size() == 2);
  REQUIRE(json["messages"].size() == 2);
  for (const nlohmann::json& message : json["messages"]) {
    if (message["bus"] == "vehicle") {
      CHECK(message["id"] == "0x18FF50E5");
      CHECK(message["mean_ms"] == 20.0);
    } else {
      CHECK(message["bus"] == "powertrain");
      CHECK(message["id"] == "0x123");
      CHECK(message["mean_ms"] == 30.0);
    }
  }
}
