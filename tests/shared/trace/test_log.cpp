// A CAN log loaded, matched, exported through the one frame writer and turned into samples.
#include <doctest/doctest.h>

#include <atomic>
#include <fstream>
#include <sstream>

#include "openvcu/trace/log.hpp"
#include "trace_test_support.hpp"

using namespace openvcu;
using namespace openvcu::trace;

namespace {

/// Two OBC frames 30 ms apart, a Status frame on can1, an unknown frame, an error frame,
/// a remote request and one malformed line.
constexpr const char* DRIVE_LOG =
    "(1.000000) can0 18FF50E5#0110270000000000\n"
    "(1.010000) can1 123#05\n"
    "(1.020000) can0 7FF#00\n"
    "this line is broken\n"
    "(1.025000) can0 20000004#0004000000000000\n"
    "(1.027000) can0 123#R\n"
    "(1.030000) can0 18FF50E5#00E8030000000000\n";
constexpr std::size_t DRIVE_LOG_FRAMES = 6;

constexpr const char* DRIVE_CSV =
    "t,bus,id,ext,msg,signal,raw,physical\n"
    "1.000000,can0,419385573,true,OBC,State,1,1\n"
    "1.000000,can0,419385573,true,OBC,Voltage,10000,1000\n"
    "1.010000,can1,291,false,Status,Mode,5,5\n"
    "1.020000,can0,2047,false,,,,\n"
    "1.027000,can0,291,false,Status,,,\n"
    "1.030000,can0,419385573,true,OBC,State,0,0\n"
    "1.030000,can0,419385573,true,OBC,Voltage,1000,100\n";

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("loading a log keeps every frame with its message and channel and counts malformed lines") {
  const test::ScratchFolder folder;
  const dbc::Database database = test::smallDatabase();
  const FrameDecoder decoder(database, dbc::MatchMode::J1939);
  std::atomic<double> progress{0};

  auto loadResult = loadLog(folder.write("drive.log", DRIVE_LOG), decoder.matcher(), {.progress = &progress});

  REQUIRE(loadResult.ok());
  const LoadedLog& sut = *loadResult;
  REQUIRE(sut.frames.size() == DRIVE_LOG_FRAMES);
  CHECK(sut.malformedLines == 1);
  CHECK(sut.lastError.find("drive.log:4:") != std::string::npos);
  CHECK_FALSE(sut.truncated);
  CHECK(sut.matchedCount() == 4);
  CHECK(sut.frames[2].message == FrameDecoder::NO_MATCH);
  REQUIRE(sut.channels.size() == 2);
  CHECK(sut.channels[sut.frames[1].channel] == "can1");
  CHECK(sut.secondsFromStart(1) == doctest::Approx(0.01));
  CHECK(sut.duration() == doctest::Approx(0.03));
  CHECK(progress.load() == 1.0);
}

TEST_CASE("loading stops at the frame limit and says so") {
  const test::ScratchFolder folder;
  const dbc::Database database = test::smallDatabase();
  const FrameDecoder decoder(database, dbc::MatchMode::J1939);
  constexpr std::size_t LIMIT = 2;

  auto loadResult = loadLog(folder.write("drive.log", DRIVE_LOG), decoder.matcher(), {.maxFrames = LIMIT});

  REQUIRE(loadResult.ok());
  CHECK(loadResult->frames.size() == LIMIT);
  CHECK(loadResult->truncated);
}

TEST_CASE("loading a missing log fails with its path") {
  const dbc::Database database = test::smallDatabase();
  const FrameDecoder decoder(database, dbc::MatchMode::J1939);

  auto loadResult = loadLog("/nonexistent/drive.log", decoder.matcher());

  REQUIRE_FALSE(loadResult.ok());
  CHECK(loadResult.error().toString().find("/nonexistent/drive.log") != std::string::npos);
}

TEST_CASE("an ASC log keeps the times as the file writes them: offsets from the start") {
  const dbc::Database database = test::smallDatabase();
  const FrameDecoder decoder(database, dbc::MatchMode::J1939);

  auto loadResult = loadLog(OPENVCU_SOURCE_DIR "/tests/data/logs/vector.asc", decoder.matcher());

  REQUIRE(loadResult.ok());
  REQUIRE_FALSE(loadResult->frames.empty());
  CHECK(loadResult->frames[0].frame.timestampNs == 1'234'000);  // "0.001234 1 18FEF100x ..."
  CHECK(loadResult->channels[loadResult->frames[0].channel] == "1");
}

TEST_CASE("the CSV export writes the frame writer's rows for every frame but error frames") {
  const test::ScratchFolder folder;
  const dbc::Database database = test::smallDatabase();
  FrameDecoder decoder(database, dbc::MatchMode::J1939);
  auto loadResult = loadLog(folder.write("drive.log", DRIVE_LOG), decoder.matcher());
  REQUIRE(loadResult.ok());
  const std::string csv = folder.path("drive.csv");

  const Status exportResult = exportLog(csv, *loadResult, decoder, DecodeFormat::Csv);

  REQUIRE(exportResult.ok());
  CHECK(readFile(csv) == DRIVE_CSV);
  std::string appended;
  appendLog(appended, *loadResult, decoder, DecodeFormat::Csv);
  CHECK(appended == DRIVE_CSV);
}

TEST_CASE("the export into a folder that does not exist fails with the path") {
  const dbc::Database database = test::smallDatabase();
  FrameDecoder decoder(database, dbc::MatchMode::J1939);
  const LoadedLog empty;

  const Status exportResult = exportLog("/nonexistent/drive.csv", empty, decoder, DecodeFormat::Csv);

  REQUIRE_FALSE(exportResult.ok());
  CHECK(exportResult.error().toString() == "/nonexistent/drive.csv: cannot write");
}

TEST_CASE("a signal of the log becomes samples in seconds from the first frame") {
  const test::ScratchFolder folder;
  const dbc::Database database = test::smallDatabase();
  FrameDecoder decoder(database, dbc::MatchMode::J1939);
  auto loadResult = loadLog(folder.write("drive.log", DRIVE_LOG), decoder.matcher());
  REQUIRE(loadResult.ok());

  const std::vector<std::string> names = signalNames(*loadResult, database);
  const auto voltage = findSignal(database, "OBC.Voltage");
  REQUIRE(voltage.has_value());
  const SampleRing sut = extractSamples(*loadResult, decoder, *voltage);

  CHECK(names == std::vector<std::string>{"OBC.State", "OBC.Voltage", "Status.Mode"});
  REQUIRE(sut.size() == 2);
  CHECK(sut.time(0) == 0);
  CHECK(sut.value(0) == doctest::Approx(1000));
  CHECK(sut.time(1) == doctest::Approx(0.03));
  CHECK(sut.value(1) == doctest::Approx(100));
  CHECK_FALSE(findSignal(database, "OBC.NoSuch").has_value());
  CHECK_FALSE(findSignal(database, "NoDot").has_value());
}
