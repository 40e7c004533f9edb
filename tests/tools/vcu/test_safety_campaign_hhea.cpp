// `vcu safety campaign` with the shipped HHEA safety case (config/hhea/safety.json: every
// hazard, --repeat 3, --strict) on the stack as ./run.sh runs it: config/supervisor/openvcu.conf
// under supervisord in the sandbox (iox-roudi, vcu-can-rx, vcu-can-tx, vcu-fsm, vcu-gpio,
// vcu-watchdog, vcu-ecu-sim), so that a service vcu-watchdog kills is started again.
// One campaign that must pass: every hazard run, every fault of each list injected and every
// item of its safe state and detection seen within its FTTI. One fault is not injectable on a
// simulated bus and must be listed as such: HHEA-BUS-LOSS's babbling node (the sim bus does
// not arbitrate, so babble delays no frame); its bus-off is injected.
// HHEA-SVC-FSM's FTTI (6000 ms) is set by the restart; its bus and Cl15 items are also held
// to the dead-man's own bound, so that the longer FTTI hides no slower dead-man.
// About 60 s per repetition on a quiet machine; the test prints its wall time and each
// hazard's slowest item.
// The campaign's HTML evidence report is then opened in Debian's headless chromium (inside the
// sandbox: no network): the document the browser built names every hazard with its PASS verdict
// and holds one timeline per injection, and it requested no network resource (chromium's net log). The JUnit XML
// names every hazard as a testcase without a failure.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "integration_support.hpp"

namespace {

/// Injections per fault: the short campaign of every commit (the long one, 30 with stress-ng,
/// is bench/stack/safety_campaign.sh).
constexpr int REPETITIONS = 3;
/// One repetition took 60-215 s on the 2-core test machine (quiet to loaded); the bound
/// leaves room for load.
constexpr auto CAMPAIGN_TIMEOUT = std::chrono::seconds(720);
/// HHEA-SVC-FSM's bus commands and Cl15: schedule.json's dead-man (1500 ms after the last
/// beat, which lies up to 1 s before the hang) + one 100 ms check, with 400 ms for a loaded host.
constexpr double DEAD_MAN_BOUND_MS = 3000;

/// Until every program of openvcu.conf beats and vcu-watchdog sees its four services.
constexpr auto STACK_UP_TIMEOUT = std::chrono::seconds(30);

std::string readAll(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

/// config/supervisor/openvcu.conf with `user=root` when run as root, as ./run.sh writes it.
fs::path writeSupervisorConf(const fs::path& folder) {
  std::string conf = readAll(fs::path(OPENVCU_SOURCE_DIR) / "config" / "supervisor" / "openvcu.conf");
  if (::geteuid() == 0) conf = std::regex_replace(conf, std::regex(R"(\n;user=root[^\n]*)"), "\nuser=root");
  const fs::path path = folder / "openvcu.conf";
  std::ofstream(path) << conf;
  return path;
}

/// The HHEA stack under supervisord, on a copy of config/hhea.
struct SupervisedHhea : ConfiguredStack {
  fs::path run = fs::temp_directory_path() / "run";
  harness::Process* supervisor{};

  SupervisedHhea() : ConfiguredStack(copyHheaConfig(fs::temp_directory_path() / "hhea")) {
    fs::create_directories(run);
    const std::string bin = fs::path(VCU).parent_path().string();
    auto started = sut.start(harness::ProcessSpec{
        .name = "supervisord",
        .argv = {"supervisord", "-n", "-c", writeSupervisorConf(run).string()},
        .environment = {"OPENVCU_BIN=" + bin, "OPENVCU_CONFIG=" + config.string(), "OPENVCU_RUN=" + run.string(),
                        "OPENVCU_ROUDI=" + (fs::path(OPENVCU_SOURCE_DIR) / "config/iceoryx/iox-roudi.sh").string()}});
    REQUIRE_STATUS(started);
    supervisor = *started;
    const auto end = std::chrono::steady_clock::now() + STACK_UP_TIMEOUT;
    harness::CommandResult status;
    for (;;) {
      status = vcu({"status", "--wait", "1.2"});
      const bool watchdogHappy = contains(status.out, "all 4 services beating");
      const bool all = contains(status.out, "vcu-can-rx ") && contains(status.out, "vcu-can-tx ") &&
                       contains(status.out, "vcu-fsm ") && contains(status.out, "vcu-gpio ") &&
                       contains(status.out, "vcu-ecu-sim ") && watchdogHappy;
      if (all) break;
      REQUIRE_MESSAGE(
          std::chrono::steady_clock::now() < end,
          "the supervised stack did not come up: " << status.describe() << readAll(run / "supervisord.log"));
    }
  }
  ~SupervisedHhea() {
    if (harness::currentTestFailed()) {
      for (const char* name : {"fsm", "can-tx", "can-rx", "gpio", "watchdog", "ecu-sim"}) {
        MESSAGE(name << ".log:\n" << readAll(run / (std::string(name) + ".log")));
      }
    }
  }
};

/// `vcu safety campaign --repeat REPETITIONS --strict --json FILE --html FILE --junit FILE --hazard ID...`
/// on the stack; the HTML report is NAME.html and the JUnit XML NAME.xml in the run folder.
nlohmann::json runCampaign(SupervisedHhea& stack, const std::vector<std::string>& hazards, const std::string& name,
                           int* exitCode) {
  const fs::path report = stack.run / (name + ".json");
  std::vector<std::string> argv{VCU,
                                "safety",
                                "campaign",
                                "--config",
                                stack.config.string(),
                                "--repeat",
                                std::to_string(REPETITIONS),
                                "--strict",
                                "--json",
                                report.string(),
                                "--html",
                                (stack.run / (name + ".html")).string(),
                                "--junit",
                                (stack.run / (name + ".xml")).string()};
  for (const std::string& id : hazards) {
    argv.emplace_back("--hazard");
    argv.push_back(id);
  }
  const auto started = std::chrono::steady_clock::now();
  const auto result = stack.sut.run(argv, CAMPAIGN_TIMEOUT);
  MESSAGE(name << ": campaign wall time "
               << std::chrono::duration_cast<std::chrono::seconds>(std::chrono::steady_clock::now() - started).count()
               << " s\n"
               << result.out << result.err);
  *exitCode = result.exitCode();
  const nlohmann::json json = nlohmann::json::parse(readAll(report), nullptr, false);
  REQUIRE_MESSAGE(!json.is_discarded(), result.describe());
  return json;
}

/// Checks that every fault of the shipped hazard was injected (but a babble on the sim bus)
/// and prints its slowest item.
void checkInjected(const nlohmann::json& hazard, const nlohmann::json& shipped) {
  const std::string id = hazard["id"];
  CHECK_MESSAGE(hazard["notRun"].empty(), id << ": " << hazard["notRun"].dump());
  const bool babbles = id == "HHEA-BUS-LOSS";
  if (babbles) {
    REQUIRE_MESSAGE(hazard["notInjected"].size() == 1, hazard["notInjected"].dump());
    CHECK(hazard["notInjected"][0].get<std::string>().starts_with(
        "babble on bus vehicle: the simulated bus does not arbitrate"));
  } else {
    CHECK_MESSAGE(hazard["notInjected"].empty(), id << ": " << hazard["notInjected"].dump());
  }
  // REPETITIONS per fault of the list
  CHECK_MESSAGE(hazard["repetitions"].size() == REPETITIONS * (shipped["faults"].size() - (babbles ? 1 : 0)), id);
  double slowest = 0;
  std::string slowestItem;
  for (const auto& repetition : hazard["repetitions"]) {
    CHECK_MESSAGE(!repetition.contains("error"), id << ": " << repetition.dump());
    for (const auto& item : repetition["items"]) {
      if (item["reachedMs"].is_number() && item["reachedMs"].get<double>() >= slowest) {
        slowest = item["reachedMs"].get<double>();
        slowestItem = item["item"];
      }
    }
  }
  MESSAGE(id << ": slowest " << slowestItem << " " << slowest << " ms of FTTI " << hazard["fttiMs"].dump() << " ms");
}

/// Occurrences of `needle` in `text`.
std::size_t count(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

/// Opens the HTML report in headless chromium (--dump-dom: the document as the browser built
/// it) with a net log, and checks what a reader sees: every hazard's heading with PASS, one
/// timeline (svg) per injection, and no request but the file itself.
void checkReportInBrowser(SupervisedHhea& stack, const fs::path& html, const nlohmann::json& campaign) {
  const std::string chromium = "/usr/bin/chromium";
  REQUIRE_MESSAGE(fs::exists(chromium), "no " << chromium << " (scripts/install-deps.sh installs Debian's chromium)");
  const fs::path home = stack.run / "chromium-home";
  const fs::path netLog = stack.run / "chromium-net.json";
  fs::create_directories(home);
  const auto browser =
      stack.sut.run({chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-sync",
                     "--disable-extensions", "--user-data-dir=" + (home / "profile").string(),
                     "--log-net-log=" + netLog.string(), "--dump-dom", "file://" + html.string()},
                    std::chrono::seconds(60), {"HOME=" + home.string()});
  REQUIRE_MESSAGE(browser.exitCode() == 0, browser.describe());
  const std::string& dom = browser.out;
  REQUIRE_MESSAGE(contains(dom, "</html>"), "chromium printed no document:\n" << browser.describe());
  std::size_t injections = 0;
  for (const auto& hazard : campaign["hazards"]) {
    const std::string id = hazard["id"];
    CHECK_MESSAGE(contains(dom, "<h2 id=\"" + id + "\">" + id + " <span class=\"PASS\">PASS</span></h2>"),
                  id << ": no PASS heading in the browser's document");
    injections += hazard["repetitions"].size();
  }
  CHECK(count(dom, "<svg") == injections);
  CHECK(contains(dom, "<p id=\"verdict\" class=\"PASS\">campaign passed</p>"));
  CHECK(count(dom, "class=\"FAIL\"") == 0);
  // the net log lists every URL requested; tests/tools/report/check_screenshot.py tells the
  // document's requests from the browser's own background ones (component updater)
  const auto netCheck = stack.sut.run(
      {"/usr/bin/python3", (fs::path(OPENVCU_SOURCE_DIR) / "tests/tools/report/check_screenshot.py").string(), "netlog",
       netLog.string()});
  CHECK_MESSAGE(netCheck.exitCode() == 0, "the report requested a network resource: " << netCheck.describe());
}

/// The JUnit XML: one testcase per hazard, none failed.
void checkJunit(const fs::path& xml, const nlohmann::json& campaign) {
  const std::string text = readAll(xml);
  REQUIRE_MESSAGE(!text.empty(), "no JUnit XML at " << xml);
  CHECK(count(text, "<testcase ") == campaign["hazards"].size());
  CHECK(count(text, "<failure") == 0);
  for (const auto& hazard : campaign["hazards"]) {
    CHECK_MESSAGE(contains(text, "name=\"" + hazard["id"].get<std::string>() + "\""), hazard["id"].dump());
  }
}

}  // namespace

TEST_CASE("the shipped HHEA safety case: every fault injected, every hazard within its FTTI") {
  SKIP_UNLESS_ISOLATED();
  std::ifstream shippedFile(fs::path(OPENVCU_SOURCE_DIR) / "config" / "hhea" / "safety.json");
  const nlohmann::json shipped = nlohmann::json::parse(shippedFile);
  std::vector<std::string> all;
  std::map<std::string, nlohmann::json> shippedById;
  for (const auto& hazard : shipped["hazards"]) {
    const std::string id = hazard["id"];
    shippedById[id] = hazard;
    all.push_back(id);
  }
  SupervisedHhea stack;

  int exitCode = -1;
  const nlohmann::json campaign = runCampaign(stack, all, "hazards", &exitCode);
  CHECK(exitCode == 0);
  CHECK(campaign["passed"] == true);
  REQUIRE(campaign["hazards"].size() == all.size());
  for (const auto& hazard : campaign["hazards"]) {
    const std::string id = hazard["id"];
    CHECK_MESSAGE(hazard["verdict"] == "PASS", id << ": " << hazard.dump());
    checkInjected(hazard, shippedById[id]);
    if (id != "HHEA-SVC-FSM") continue;
    for (const auto& repetition : hazard["repetitions"]) {
      for (const auto& item : repetition["items"]) {
        const std::string what = item["item"];
        if (!what.starts_with("bus ") && !what.starts_with("gpio ")) continue;
        REQUIRE_MESSAGE(item["reachedMs"].is_number(), id << ": " << what << " not seen");
        CHECK_MESSAGE(item["reachedMs"].get<double>() < DEAD_MAN_BOUND_MS, id << ": " << item.dump());
      }
    }
  }
  checkJunit(stack.run / "hazards.xml", campaign);
  checkReportInBrowser(stack, stack.run / "hazards.html", campaign);
}
