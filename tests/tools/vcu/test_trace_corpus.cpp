// `vcu trace stats|check|report` on the public logs of the team kit's corpus
// (../shared/corpus/logs/python-can, not copied into the repository), with canmatrix's
// J1939 DBC: no crash, a usable answer for every log the reader understands, and the
// frame count the statistics report equal to the frames can::LogReader delivers.

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../../skip.hpp"
#include "openvcu/can/log_reader.hpp"
#include "vcu_test_support.hpp"

using namespace openvcu::cli::test;

namespace {

/// Frames with a time that can::LogReader reads from `path` (the timeline skips untimed lines).
std::uint64_t timedFrames(const std::string& path) {
  auto openResult = openvcu::can::LogReader::open(path);
  REQUIRE(openResult.ok());
  std::uint64_t frames = 0;
  while (auto record = openResult->next()) {
    if (record->hasTime) ++frames;
  }
  return frames;
}

}  // namespace

TEST_CASE("vcu trace stats, check and report run on every python-can ASC log of the corpus") {
  const std::filesystem::path folder = OPENVCU_TEAM_KIT "/corpus/logs/python-can";
  const std::string dbc = OPENVCU_TEAM_KIT "/corpus/dbc/canmatrix/j1939.dbc";
  if (!std::filesystem::is_directory(folder) || !std::filesystem::exists(dbc)) {
    OPENVCU_SKIP("skipped: " << folder.string() << " or " << dbc << " not found (the team kit is not beside the repository)");
  }
  std::size_t logs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().extension() != ".asc") continue;
    const std::string log = entry.path().string();
    INFO(log);
    ++logs;
    const RunResult stats = runVcu({"trace", "stats", "--dbc", dbc, log, "--format", "json"});
    CHECK((stats.exitCode == EXIT_OK || stats.exitCode == EXIT_INPUT_ERROR));
    const nlohmann::json json = nlohmann::json::parse(stats.out, nullptr, false);
    REQUIRE_FALSE(json.is_discarded());
    CHECK(json.at("frames").get<std::uint64_t>() == timedFrames(log));

    const RunResult check = runVcu({"trace", "check", "--dbc", dbc, log, "--format", "json"});
    CHECK(check.exitCode != EXIT_USAGE);
    CHECK_FALSE(nlohmann::json::parse(check.out, nullptr, false).is_discarded());

    const std::string html = (scratchFolder() / "corpus_report.html").string();
    const RunResult report = runVcu({"trace", "report", "--dbc", dbc, log, "-o", html});
    CHECK(report.exitCode != EXIT_USAGE);
    std::ifstream file(html);
    std::stringstream text;
    text << file.rdbuf();
    CHECK(text.str().find("</html>") != std::string::npos);
  }
  CHECK(logs > 10);
  MESSAGE("analysed " << logs << " python-can ASC logs");
}
