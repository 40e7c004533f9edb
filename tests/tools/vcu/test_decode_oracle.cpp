// End to end: the built `vcu` binary against the canmatrix oracle of the team kit
// (dbc-oracle.py decode --match j1939) on a generated synthetic J1939 log.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "vcu_test_support.hpp"
#include "skip.hpp"

using namespace openvcu::cli::test;
using nlohmann::json;

namespace {

constexpr int SYNTHETIC_FRAMES = 2000;
constexpr int SYNTHETIC_SEED = 1939;
constexpr double PHYSICAL_RELATIVE_TOLERANCE = 1e-9;
constexpr int MISMATCHES_SHOWN = 5;
const char* const PYTHON = "/usr/bin/python3";

/// Single-quoted for /bin/sh. Only paths this test controls (build and kit folders) pass here.
std::string quoted(const std::filesystem::path& path) {
  const std::string text = path.string();
  REQUIRE(text.find('\'') == std::string::npos);
  return "'" + text + "'";
}

int shell(const std::string& command) {
  return std::system(command.c_str());
}

std::vector<json> readJsonLines(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::vector<json> lines;
  std::string line;
  while (std::getline(file, line)) lines.push_back(json::parse(line));
  return lines;
}

double asNumber(const json& value) {
  if (value.is_string()) return std::strtod(value.get<std::string>().c_str(), nullptr);  // "nan", "inf", "-inf"
  return value.get<double>();
}

bool physicalClose(const json& mine, const json& oracle) {
  if (!mine.is_number() && !mine.is_string()) return false;
  const double a = asNumber(mine);
  const double b = asNumber(oracle);
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (a == b) return true;  // also equal infinities
  return std::fabs(a - b) <= PHYSICAL_RELATIVE_TOLERANCE * std::max(std::fabs(a), std::fabs(b));
}

/// Empty when the frames agree; else what differs.
std::string difference(const json& mine, const json& oracle) {
  if (mine["id"] != oracle["id"] || mine["ext"] != oracle["ext"] || mine["bus"] != oracle["ch"]) return "frame";
  if (mine["t"] != oracle["t"]) return "time";
  if (mine["msg"] != oracle["msg"]) return "msg";
  if (oracle.contains("error")) return "oracle error " + oracle["error"].dump();
  if (mine["raw"] != oracle["raw"]) return "raw";
  if (mine["signals"].size() != oracle["signals"].size()) return "signal names";
  for (const auto& [name, value] : oracle["signals"].items()) {
    if (!mine["signals"].contains(name) || !physicalClose(mine["signals"][name], value)) return "physical " + name;
  }
  return {};
}

}  // namespace

TEST_CASE("decode agrees with the canmatrix oracle on a synthetic J1939 log") {
  const std::filesystem::path kitTools = std::filesystem::path(OPENVCU_TEAM_KIT) / "tools";
  const std::filesystem::path generator = kitTools / "gen-j1939-log.py";
  const std::filesystem::path oracle = kitTools / "dbc-oracle.py";
  if (!std::filesystem::exists(generator) || !std::filesystem::exists(oracle)) {
    OPENVCU_SKIP("skipped: the team kit has no tools/ at " << OPENVCU_TEAM_KIT);
  }
  if (shell(std::string(PYTHON) + " -c 'import canmatrix' >/dev/null 2>&1") != 0) {
    OPENVCU_SKIP("skipped: " << PYTHON << " cannot import canmatrix");
  }
  const std::filesystem::path work = scratchFolder() / "oracle";
  std::filesystem::create_directories(work);
  const std::filesystem::path dbc = work / "synthetic_j1939.dbc";
  const std::filesystem::path log = work / "synthetic_j1939.log";
  const std::filesystem::path mineOut = work / "vcu.jsonl";
  const std::filesystem::path oracleOut = work / "oracle.jsonl";

  REQUIRE(shell(std::string(PYTHON) + " " + quoted(generator) + " --frames " + std::to_string(SYNTHETIC_FRAMES) +
                " --seed " + std::to_string(SYNTHETIC_SEED) + " --out-dir " + quoted(work) + " >/dev/null") == 0);
  REQUIRE(shell(quoted(VCU_BINARY) + " dbc decode " + quoted(dbc) + " " + quoted(log) + " > " + quoted(mineOut)) == 0);
  REQUIRE(shell(std::string(PYTHON) + " " + quoted(oracle) + " decode --match j1939 " + quoted(dbc) + " " +
                quoted(log) + " --out " + quoted(oracleOut)) == 0);

  const std::vector<json> mine = readJsonLines(mineOut);
  const std::vector<json> expected = readJsonLines(oracleOut);
  REQUIRE(mine.size() == static_cast<std::size_t>(SYNTHETIC_FRAMES));
  REQUIRE(expected.size() == mine.size());
  int mismatches = 0;
  int matched = 0;
  for (std::size_t i = 0; i < mine.size(); ++i) {
    if (!mine[i]["msg"].is_null()) ++matched;
    const std::string what = difference(mine[i], expected[i]);
    if (what.empty()) continue;
    if (++mismatches <= MISMATCHES_SHOWN) {
      MESSAGE("line " << i + 1 << ": " << what << "\n  vcu:    " << mine[i].dump()
                      << "\n  oracle: " << expected[i].dump());
    }
  }
  CHECK(mismatches == 0);
  CHECK(matched == SYNTHETIC_FRAMES);  // every synthetic frame belongs to a DBC message
}
