// Issue 21: `vcu trace check` on candump logs generated here with the HHEA configuration:
// S1_ES_PGN61427 pairs as vcu-can-tx sends them (SHM, the SDM 292 us later, every 20 ms),
// PropA_C4 between the pairs and a request answered; one log with a broken pair.
#include <doctest/doctest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "openvcu/j1939/safety.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu;
using namespace openvcu::cli::test;

namespace {

const std::string HHEA_CONFIG = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
constexpr std::uint32_t S1_ES_ID = 0x0CEFF321;
constexpr std::int64_t START_US = 1'700'000'000'000'000;
constexpr std::int64_t CYCLE_US = 20'000;
constexpr std::int64_t DELTA_US = 292;  // schedule.json: S1_ES_PGN61427 safety.deltaUs
constexpr int PAIRS = 50;
constexpr int BROKEN_PAIR = 10;
const j1939::SafetyPayload SDM_DATA{0xEF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};  // the thesis' trace

std::string line(std::int64_t timeUs, std::uint32_t id, std::span<const std::uint8_t> data) {
  char text[96];
  int length =
      std::snprintf(text, sizeof text, "(%lld.%06lld) vehicle %08X#", static_cast<long long>(timeUs / 1'000'000),
                    static_cast<long long>(timeUs % 1'000'000), id);
  for (const std::uint8_t byte : data) length += std::snprintf(text + length, sizeof text - length, "%02X", byte);
  return std::string(text, static_cast<std::size_t>(length)) + '\n';
}

/// 50 S1_ES pairs; with `broken`, the SDM of pair 10 has its last byte changed.
std::string hheaLog(bool broken) {
  j1939::SafetyPairBuilder builder(S1_ES_ID);
  const std::array<std::uint8_t, 8> propA{0, 0, 0, 0, 0, 0, 0, 0};
  const std::array<std::uint8_t, 3> request{0x5E, 0xFC, 0x00};  // PGN 64606 HVESSHIST
  const std::array<std::uint8_t, 8> history{1, 2, 3, 4, 5, 6, 7, 8};
  std::string log;
  for (int i = 0; i < PAIRS; ++i) {
    const std::int64_t t = START_US + i * CYCLE_US;
    log += line(t, builder.headerCanId(), builder.nextHeader(SDM_DATA));
    j1939::SafetyPayload data = SDM_DATA;
    if (broken && i == BROKEN_PAIR) data[7] = 0xFE;
    log += line(t + DELTA_US, S1_ES_ID, data);
    if (i == 0) log += line(t + 5'000, 0x18EAF321, request);   // RQST_ES: VCU -> VIC
    log += line(t + CYCLE_US / 2, 0x18EFF321, propA);          // PropA_C4, never between SHM and SDM
    if (i == 0) log += line(t + 15'000, 0x18FC5EF3, history);  // the VIC's answer
  }
  return log;
}

}  // namespace

TEST_CASE("vcu trace check passes a clean HHEA log with correct S1_ES pairs") {
  const std::string log = writeScratchFile("trace_check_clean.log", hheaLog(false));
  const RunResult result = runVcu({"trace", "check", "--config", HHEA_CONFIG, log, "--quiet"});

  CHECK(result.exitCode == EXIT_OK);
  CHECK(result.err.empty());
  CHECK_FALSE(contains(result.out, " fault "));
  CHECK(contains(result.out, "1 requests (0 unanswered)"));
  CHECK(contains(result.out,
                 "S1_ES_PGN61427 (0x0CEFF321) on vehicle: 50 SDMs, 0 faulty, SHM -> SDM delta "
                 "min/mean/max 292/292/292 us (configured 292 us)\n"));
  CHECK(contains(result.out, "findings: 0 faults, 0 warnings, 4 infos\n"));  // the 4 other pairs: not in this log
}

TEST_CASE("vcu trace check exits 1 on a broken J1939-76 pair and names it with its time") {
  const std::string log = writeScratchFile("trace_check_broken.log", hheaLog(true));
  const RunResult result = runVcu({"trace", "check", "--config", HHEA_CONFIG, log});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err.empty());  // exit 1 for the fault alone
  j1939::SafetyPayload broken = SDM_DATA;
  broken[7] = 0xFE;
  char expected[192];
  std::snprintf(expected, sizeof expected,
                "\n1700000000.200292 fault j1939-76 vehicle: S1_ES_PGN61427 (0x0CEFF321): CrcMismatch: SHM CRC "
                "0x8100EFA3, "
                "SDM data CRC 0x%08X\n",
                j1939::crc32J1939_76(broken));
  CHECK(contains("\n" + result.out, expected));  // a whole line: the log's time, not a part of it
  CHECK(contains(result.out, "info j1939-76 vehicle: HVESSC1_PGN6912 (0x18"));  // configured, not in this log
  CHECK(contains(result.out, "findings: 1 faults, 0 warnings, 4 infos; faults by check: j1939-76 1\n"));
}

TEST_CASE("vcu trace check --format json lists the finding, the pair's delta and the summary") {
  const std::string log = writeScratchFile("trace_check_json.log", hheaLog(true));
  const RunResult result = runVcu({"trace", "check", "--config", HHEA_CONFIG, log, "--format", "json", "--quiet"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  const nlohmann::json document = nlohmann::json::parse(result.out);
  REQUIRE(document["findings"].size() == 1);
  CHECK(document["findings"][0]["t"].get<double>() == doctest::Approx(1700000000.200292).epsilon(1e-15));
  CHECK(document["findings"][0]["t_rel"].get<double>() == doctest::Approx(0.200292));
  CHECK(document["findings"][0]["severity"] == "fault");
  CHECK(document["findings"][0]["check"] == "j1939-76");
  REQUIRE(document["pairs"].size() == 1);
  CHECK(document["pairs"][0]["name"] == "S1_ES_PGN61427 (0x0CEFF321)");
  CHECK(document["pairs"][0]["sdms"] == PAIRS);
  CHECK(document["pairs"][0]["faults"] == 1);
  CHECK(document["pairs"][0]["delta_mean_us"] == DELTA_US);
  CHECK(document["summary"]["faults_by_check"]["j1939-76"] == 1);
}

TEST_CASE("vcu trace check finds the pairs by their SHMs without a configuration") {
  const std::string log = writeScratchFile("trace_check_nodbc.log", hheaLog(true));
  const RunResult result = runVcu({"trace", "check", log});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(contains(result.out, "fault j1939-76 vehicle: SDM 0x0CEFF321: CrcMismatch: SHM CRC 0x8100EFA3"));
  CHECK(contains(result.out, "SDM 0x0CEFF321 on vehicle: 50 SDMs, 1 faulty"));
  CHECK(contains(result.out, "(found on the bus)"));
}

TEST_CASE("vcu trace check --dbc FILE LOG names the pairs it finds from the DBC") {
  const std::string log = writeScratchFile("trace_check_dbc.log", hheaLog(true));
  const RunResult result =
      runVcu({"trace", "check", "--dbc", std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/hhea.dbc", log, "--quiet"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  CHECK(result.err.empty());
  CHECK(contains("\n" + result.out,
                 "\n1700000000.200292 fault j1939-76 vehicle: S1_ES_PGN61427 (0x0CEFF321): CrcMismatch: "));
  CHECK(contains(result.out, "S1_ES_PGN61427 (0x0CEFF321) on vehicle: 50 SDMs, 1 faulty"));
}

namespace {

/// The first field of the first line of `out` that holds `part`; empty when none does.
std::string firstFieldOfLineWith(const std::string& out, const std::string& part) {
  for (const std::string& text : splitLines(out)) {
    if (contains(text, part)) return text.substr(0, text.find(' '));
  }
  return {};
}

}  // namespace

TEST_CASE("vcu trace check names a finding by the log's own time, which grep finds in the log") {
  const std::string logText = hheaLog(true);
  const std::string log = writeScratchFile("trace_check_logtime.log", logText);
  const RunResult result = runVcu({"trace", "check", "--config", HHEA_CONFIG, log, "--quiet"});

  CHECK(result.exitCode == EXIT_INPUT_ERROR);
  const std::string time = firstFieldOfLineWith(result.out, " fault j1939-76 ");
  REQUIRE_FALSE(time.empty());
  CHECK(time == "1700000000.200292");
  // as `grep -F '(TIME)' LOG` would: the broken SDM's line, a whole candump -L time stamp
  const std::size_t at = logText.find("(" + time + ") vehicle 0CEFF321#");
  CHECK(at != std::string::npos);

  // the configuration's folder names the same setup as its vehicle.json
  const std::string folder = HHEA_CONFIG.substr(0, HHEA_CONFIG.rfind('/'));
  CHECK(runVcu({"trace", "check", "--config", folder, log, "--quiet"}).out == result.out);
}

TEST_CASE("vcu trace check --time relative gives seconds from the first frame, --time both gives both") {
  const std::string log = writeScratchFile("trace_check_reltime.log", hheaLog(true));
  const RunResult relative = runVcu({"trace", "check", "--config", HHEA_CONFIG, log, "--quiet", "--time", "relative"});
  CHECK(firstFieldOfLineWith(relative.out, " fault j1939-76 vehicle: S1_ES_PGN61427") == "0.200292");
  const RunResult both = runVcu({"trace", "check", "--config", HHEA_CONFIG, log, "--quiet", "--time", "both"});
  CHECK(contains(both.out, "1700000000.200292 +0.200292 fault j1939-76 vehicle: S1_ES_PGN61427"));
  CHECK(runVcu({"trace", "check", log, "--time", "utc"}).exitCode == EXIT_USAGE);
}

TEST_CASE("vcu trace check --format json gives each finding's log time and its time from the first frame") {
  const std::string log = writeScratchFile("trace_check_json_time.log", hheaLog(true));
  const RunResult result = runVcu({"trace", "check", "--config", HHEA_CONFIG, log, "--format", "json", "--quiet"});

  CHECK(contains(result.out, "{\"t\":1700000000.200292,\"t_rel\":0.200292,\"severity\":\"fault\""));
  const nlohmann::json document = nlohmann::json::parse(result.out);
  REQUIRE(document["findings"].size() == 1);
  CHECK(document["findings"][0]["t_rel"].get<double>() == doctest::Approx(0.200292));
}

TEST_CASE("vcu trace report lists each finding at the log's own time") {
  const std::string log = writeScratchFile("trace_report_logtime.log", hheaLog(true));
  const std::string html = (scratchFolder() / "trace_report_logtime.html").string();
  const RunResult result = runVcu({"trace", "report", "--config", HHEA_CONFIG, log, "-o", html});
  INFO(result.err);
  REQUIRE(result.exitCode == EXIT_OK);
  std::ifstream file(html);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::size_t findings = text.find("<section id=\"findings\">");
  REQUIRE(findings != std::string::npos);
  const std::size_t row = text.find("CrcMismatch", findings);
  REQUIRE(row != std::string::npos);
  const std::size_t rowStart = text.rfind("<tr", row);
  REQUIRE(rowStart != std::string::npos);
  const std::string cells = text.substr(rowStart, row - rowStart);
  CHECK(contains(cells, ">1700000000.200292<"));  // the log's time
  CHECK(contains(cells, ">0.200292<"));           // and seconds from the first frame beside it
}

TEST_CASE("vcu trace check without a log is a usage error") {
  CHECK(runVcu({"trace", "check"}).exitCode == EXIT_USAGE);
}
