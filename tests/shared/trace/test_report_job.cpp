// makeReport / summarize / jobForFolder (report_job.hpp): the report pipeline as a library
// call, on the candump -L fixture of tests/data/logs and the vcu tests' vehicle.dbc.
//
// candump_l.log: 10 frames; can0: CCVS1 (18FEF100, WheelSpeed raw 0x0302), 123#R twice,
// an error frame, and a last frame (001#00) earlier than the one before it; can1: 3 frames;
// vcan0: 2 frames.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/trace/report_job.hpp"
#include "trace_test_support.hpp"

using namespace openvcu;
using namespace openvcu::trace;

namespace {

const std::string FIXTURE_LOG = OPENVCU_SOURCE_DIR "/tests/data/logs/candump_l.log";
const std::string FIXTURE_DBC = OPENVCU_SOURCE_DIR "/tests/tools/vcu/data/vehicle.dbc";
constexpr std::uint64_t FIXTURE_FRAMES = 10;
constexpr std::uint64_t FIXTURE_CAN0_FRAMES = 5;
constexpr std::uint64_t FIXTURE_CAN1_FRAMES = 3;
constexpr std::uint64_t FIXTURE_VCAN0_FRAMES = 2;
constexpr std::int64_t EVENTS_START_NS = 1'436'509'052'249'713'000;  ///< the fixture's first frame

ReportJob fixtureJob() {
  auto setupResult = loadSetupFromDbc({FIXTURE_DBC});
  REQUIRE_MESSAGE(setupResult, (setupResult ? "" : setupResult.error().toString()));
  ReportJob job;
  job.setup = std::move(*setupResult);
  job.logs = {FIXTURE_LOG};
  return job;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// The input error whose location is `file`, or null.
const Error* errorAbout(const std::vector<Error>& errors, const std::string& file) {
  const auto it =
      std::find_if(errors.begin(), errors.end(), [&file](const Error& e) { return e.location.file == file; });
  return it == errors.end() ? nullptr : &*it;
}

}  // namespace

TEST_CASE("trace::makeReport of a candump log counts its frames per bus and draws the figures and the message table") {
  ReportJob job = fixtureJob();
  job.signals = {"CCVS1.WheelSpeed"};

  auto sut = makeReport(job);

  REQUIRE_MESSAGE(sut, (sut ? "" : sut.error().toString()));
  const ReportSummary& summary = sut->summary;
  CHECK(summary.frames == FIXTURE_FRAMES);
  CHECK(summary.buses == std::vector<std::string>{"can0", "can1", "vcan0"});
  REQUIRE(summary.busLoad.size() == 3);
  CHECK(summary.busLoad[0].frames == FIXTURE_CAN0_FRAMES);
  CHECK(summary.busLoad[1].frames == FIXTURE_CAN1_FRAMES);
  CHECK(summary.busLoad[2].frames == FIXTURE_VCAN0_FRAMES);
  CHECK(summary.errorFrames == 1);
  CHECK(summary.malformedLines == 0);
  CHECK(summary.logs == std::vector<std::string>{FIXTURE_LOG});
  CHECK(summary.unreadableLogs.empty());
  CHECK_FALSE(summary.truncated);
  // the backward step: warnings, not errors
  REQUIRE_FALSE(sut->inputErrors.empty());
  for (const Error& error : sut->inputErrors) {
    CAPTURE(error.toString());
    CHECK(error.severity == openvcu::Severity::Warning);
    CHECK(error.location.file == FIXTURE_LOG);
  }
  CHECK(contains(sut->inputErrors.front().message, "time goes backwards"));

  const std::string& html = sut->html;
  CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
  CHECK(contains(html, "<title>candump_l.log"));  // the title: the log's name
  CHECK(contains(html, "logs: " + FIXTURE_LOG));  // the source line
  CHECK(contains(html, "<div class=\"chart\" data-chart=\"bus-load\">"));
  CHECK(contains(html, "<div class=\"chart\" data-chart=\"node-rate\">"));
  CHECK(contains(html, "<div class=\"chart\" data-chart=\"signals-1\">"));
  CHECK(contains(html, "CCVS1.WheelSpeed"));
  CHECK(contains(html, "<td class=\"l\">CCVS1</td>"));        // the message table
  CHECK(contains(html, "<td class=\"l\">vcan0</td>"));        // the bus table
  CHECK_FALSE(contains(html, "data-chart=\"event-lanes\""));  // no events log
}

TEST_CASE("trace::summarize gives the summary of makeReport without the signal pass") {
  ReportJob job = fixtureJob();
  auto reportResult = makeReport(job);
  REQUIRE(reportResult);

  std::vector<Error> inputErrors;
  auto sut = summarize(job, &inputErrors);

  REQUIRE_MESSAGE(sut, (sut ? "" : sut.error().toString()));
  CHECK(sut->frames == reportResult->summary.frames);
  CHECK(sut->durationS == reportResult->summary.durationS);
  CHECK(sut->buses == reportResult->summary.buses);
  CHECK(sut->errors == reportResult->summary.errors);
  CHECK(sut->warnings == reportResult->summary.warnings);
  CHECK(sut->messages == reportResult->summary.messages);
  CHECK(inputErrors.size() == reportResult->inputErrors.size());
}

TEST_CASE("trace::makeReport fails naming the log when its only log cannot be opened") {
  ReportJob job = fixtureJob();
  job.logs = {"/nonexistent/drive.log"};

  auto sut = makeReport(job);

  REQUIRE_FALSE(sut);
  CHECK(sut.error().location.file == "/nonexistent/drive.log");
  CHECK_FALSE(summarize(job));
}

TEST_CASE("trace::makeReport leaves out a log that cannot be opened, names it and reports the others") {
  ReportJob job = fixtureJob();
  job.logs = {FIXTURE_LOG, "/nonexistent/drive.log"};
  job.signals = {"CCVS1.NoSuchSignal"};

  auto sut = makeReport(job);

  REQUIRE(sut);
  CHECK(sut->summary.frames == FIXTURE_FRAMES);
  CHECK(sut->summary.unreadableLogs == std::vector<std::string>{"/nonexistent/drive.log"});
  const Error* missing = errorAbout(sut->inputErrors, "/nonexistent/drive.log");
  REQUIRE(missing != nullptr);
  CHECK(missing->severity == openvcu::Severity::Error);
  const auto unknownSignal = std::find_if(sut->inputErrors.begin(), sut->inputErrors.end(), [](const Error& e) {
    return contains(e.message, "CCVS1.NoSuchSignal: no such signal");
  });
  CHECK(unknownSignal != sut->inputErrors.end());
  CHECK_FALSE(contains(sut->html, "data-chart=\"signals-1\""));
  CHECK(contains(sut->html, "</html>"));
}

TEST_CASE("trace::makeReport stops at maxFrames and says so, and returns cancelled when its cancel flag is set") {
  constexpr std::uint64_t LIMIT = 4;
  ReportJob job = fixtureJob();
  job.maxFrames = LIMIT;

  auto limited = makeReport(job);

  REQUIRE(limited);
  CHECK(limited->summary.frames == LIMIT);
  CHECK(limited->summary.truncated);
  const auto note = std::find_if(limited->inputErrors.begin(), limited->inputErrors.end(),
                                 [](const Error& e) { return contains(e.message, "stopped after 4 frames"); });
  CHECK(note != limited->inputErrors.end());

  const std::atomic<bool> cancel{true};
  job.cancel = &cancel;
  auto cancelled = makeReport(job);
  REQUIRE_FALSE(cancelled);
  CHECK(cancelled.error().message == "cancelled");
}

TEST_CASE("trace::jobForFolder takes a recording's *.log files in order, its events log and its name") {
  test::ScratchFolder folder;
  const std::string vehicle = folder.write("vehicle.log", "(1436509052.249713) vehicle 18FEF100#0102030405060708\n");
  const std::string body = folder.write("body.log", "(1436509052.300000) body 123#01\n");
  (void)folder.write("notes.txt", "not a log\n");
  {
    auto busResult = ipc::EventBus::open("file://" + folder.path("events.lcmlog") + "?mode=w", "hhea");
    REQUIRE_MESSAGE(busResult.ok(), (busResult.ok() ? "" : busResult.error().toString()));
    CHECK(busResult->publish(ipc::FsmTransition{EVENTS_START_NS + 10'000'000, "Off", "KeepAliveState", "StartStop"}));
  }

  auto sut = jobForFolder(folder.path(""), emptySetup());

  REQUIRE_MESSAGE(sut, (sut ? "" : sut.error().toString()));
  CHECK(sut->logs == std::vector<std::string>{body, vehicle});
  CHECK(sut->eventsLog == folder.path("events.lcmlog"));
  CHECK(sut->title.rfind("openvcu-trace-", 0) == 0);  // the folder's name, also with a trailing slash
  auto reportResult = makeReport(*sut);
  REQUIRE(reportResult);
  // LogTimeline::buses(): channels as the logs are read (each log's first frame at open)
  CHECK(reportResult->summary.buses == std::vector<std::string>{"body", "vehicle"});
  CHECK(contains(reportResult->html, "data-chart=\"event-lanes\""));
  CHECK(contains(reportResult->html, "KeepAliveState"));
}

TEST_CASE("trace::jobForFolder fails on a folder without logs, and an unreadable events log is an input error") {
  test::ScratchFolder folder;
  auto empty = jobForFolder(folder.path(""), emptySetup());
  REQUIRE_FALSE(empty);
  CHECK(contains(empty.error().message, "no *.log file"));

  (void)folder.write("vehicle.log", "(1.000000) vehicle 123#01\n");
  const std::string events = folder.write("events.lcmlog", "not an LCM log\n");
  auto sut = jobForFolder(folder.path(""), emptySetup());
  REQUIRE(sut);
  auto reportResult = makeReport(*sut);
  REQUIRE(reportResult);
  const Error* eventsError = errorAbout(reportResult->inputErrors, events);
  REQUIRE(eventsError != nullptr);
  CHECK(eventsError->severity == openvcu::Severity::Error);
  CHECK(reportResult->summary.frames == 1);
}
