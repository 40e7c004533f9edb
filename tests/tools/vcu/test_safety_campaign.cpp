// `vcu safety campaign`'s judging and reports on measured data (no stack): the statistics,
// the FTTI verdict, coverage, and JSON / JUnit / HTML that say the same.

#include <doctest/doctest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "safety_campaign.hpp"

using namespace openvcu::cli;

namespace {

constexpr std::int64_t FTTI_MS = 1000;

Repetition repetition(int index, std::optional<double> fsmMs, std::optional<double> faultMs) {
  Repetition r;
  r.index = index;
  r.windowMs = 2 * FTTI_MS;
  r.injected = {"silent.VIC"};
  ItemResult fsm;
  fsm.kind = ItemKind::FsmState;
  fsm.item = "fsm Battery Timeout";
  fsm.reachedMs = fsmMs;
  fsm.reached = fsmMs ? "Battery Timeout" : "";
  r.items.push_back(fsm);
  ItemResult fault;
  fault.kind = ItemKind::Fault;
  fault.item = "fault rx_timeout.*.HVESSS1";
  fault.detection = "receiveTimeout";
  fault.reachedMs = faultMs;
  r.items.push_back(fault);
  r.timeline.push_back({0, "injected silent.VIC"});
  if (fsmMs) r.timeline.push_back({*fsmMs, "fsm Battery Timeout"});
  return r;
}

HazardResult hazard(std::vector<Repetition> repetitions) {
  HazardResult h;
  h.id = "H-BAT";
  h.description = "battery <silent> & gone";
  h.fttiMs = FTTI_MS;
  h.repetitions = std::move(repetitions);
  return h;
}

CampaignResult campaign(std::vector<HazardResult> hazards) {
  CampaignResult c;
  c.vehicle = "hhea/vehicle.json";
  c.safetyFile = "hhea/safety.json";
  c.host = "host";
  c.hazards = std::move(hazards);
  c.safeFsmStates = {"Battery Timeout", "Crash"};
  c.detectionKinds = {"receiveTimeout", "serviceWatchdog"};
  return c;
}

}  // namespace

TEST_CASE("summarize gives min, median, nearest-rank p99 and max per item over the repetitions") {
  const HazardResult sut =
      hazard({repetition(1, 300, 10), repetition(2, 100, 30), repetition(3, 200, 20), repetition(4, 400, 40)});
  const auto stats = summarize(sut);
  REQUIRE(stats.size() == 2);
  CHECK(stats[0].item == "fsm Battery Timeout");
  CHECK(stats[0].seen == 4);
  CHECK(stats[0].missed == 0);
  CHECK(stats[0].minMs == 100);
  CHECK(stats[0].medianMs == 250);
  CHECK(stats[0].p99Ms == 400);
  CHECK(stats[0].maxMs == 400);
  CHECK(verdictOf(sut) == Verdict::Pass);
}

TEST_CASE("a hazard fails when one item of one repetition is late or never seen") {
  CHECK(verdictOf(hazard({repetition(1, 300, 10), repetition(2, 1001, 10)})) == Verdict::Fail);
  CHECK(verdictOf(hazard({repetition(1, 300, std::nullopt)})) == Verdict::Fail);
  CHECK(verdictOf(hazard({})) == Verdict::Fail);
  Repetition broken = repetition(1, 300, 10);
  broken.error = "cannot bring the vehicle to Driving";
  CHECK(verdictOf(hazard({broken})) == Verdict::Fail);
  const auto stats = summarize(hazard({repetition(1, 300, 10), repetition(2, 1001, std::nullopt)}));
  CHECK(stats[0].missed == 1);
  CHECK(stats[1].seen == 1);
  CHECK(stats[1].missed == 1);
}

TEST_CASE("a hazard that cannot be injected is not run and fails the campaign only when strict") {
  HazardResult notRun = hazard({});
  notRun.notRunReasons = {"busOff: vcu inject has no bus-off of a link"};
  const CampaignResult sut = campaign({hazard({repetition(1, 300, 10)}), notRun});
  CHECK(verdictOf(notRun) == Verdict::NotRun);
  CHECK(campaignPassed(sut, false));
  CHECK_FALSE(campaignPassed(sut, true));
}

TEST_CASE("coverage lists the safe states reached and the detection kinds exercised, and those not") {
  const Coverage sut = coverageOf(campaign({hazard({repetition(1, 300, 10)})}));
  CHECK(sut.fsmStatesReached == std::vector<std::string>{"Battery Timeout"});
  CHECK(sut.fsmStatesMissed == std::vector<std::string>{"Crash"});
  CHECK(sut.detectionsExercised == std::vector<std::string>{"receiveTimeout"});
  CHECK(sut.detectionsMissed == std::vector<std::string>{"serviceWatchdog"});
}

TEST_CASE("text, JSON, JUnit and HTML reports name the miss of a failed hazard") {
  const CampaignResult sut = campaign({hazard({repetition(1, 1500, 10)})});
  const std::string text = formatSummary(sut);
  CHECK(text.find("H-BAT: FAIL") != std::string::npos);
  CHECK(text.find("miss #1: fsm Battery Timeout after 1500 ms > FTTI 1000 ms") != std::string::npos);
  CHECK(text.find("campaign FAILED: 0 passed, 1 failed, 0 not run") != std::string::npos);
  CHECK(formatRepetition(sut.hazards[0], sut.hazards[0].repetitions[0]) ==
        "H-BAT #1 FAIL fsm Battery Timeout 1500 ms (late), fault rx_timeout.*.HVESSS1 10 ms (FTTI 1000 ms)\n");

  const auto json = nlohmann::json::parse(toJson(sut).dump());
  CHECK(json["passed"] == false);
  CHECK(json["hazards"][0]["verdict"] == "FAIL");
  CHECK(json["hazards"][0]["items"][0]["maxMs"] == 1500);

  const std::string junit = toJunit(sut);
  CHECK(junit.find("tests=\"1\" failures=\"1\"") != std::string::npos);
  CHECK(junit.find("<testcase classname=\"safety.hhea/vehicle.json\" name=\"H-BAT\"") != std::string::npos);
  CHECK(junit.find("<failure message=\"FTTI 1000 ms missed\">#1: fsm Battery Timeout after 1500 ms") !=
        std::string::npos);

  const std::string html = toHtml(sut);
  CHECK(html.find("battery &lt;silent&gt; &amp; gone") != std::string::npos);  // escaped
  CHECK(html.find("<svg") != std::string::npos);
  CHECK(html.find("http") == std::string::npos);  // nothing fetched
  CHECK(html.find("<script") == std::string::npos);
}
