// TraceStats on generated frames with known answers: exact periods, injected jitter,
// dropped frames, two source addresses, a known bus load, error frames, an unknown id,
// time going backwards, the stream cap; and the text/JSON forms (issue 21).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "openvcu/can/wire_time.hpp"
#include "openvcu/trace/stats.hpp"
#include "trace_test_support.hpp"

using namespace openvcu;
using namespace openvcu::trace;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t US = 1'000;
constexpr std::int64_t START_NS = 1'700'000'000'000'000'000;
/// Half a histogram bin: how close p50/p99 are below 200 ms.
constexpr double HALF_BIN_MS = 0.05;

constexpr std::uint32_t OBC_ID = 0x18FF50E5;  ///< message 0 of smallDatabase(), SA 0xE5
constexpr std::int32_t OBC_MESSAGE = 0;
constexpr std::uint32_t STATUS_ID = 0x123;    ///< message 1, 11-bit
constexpr std::int32_t STATUS_MESSAGE = 1;
constexpr std::int64_t OBC_CYCLE_NS = 10 * MS;
constexpr std::int64_t STATUS_CYCLE_NS = 100 * MS;

/// smallDatabase() with OBC every 10 ms (GenMsgCycleTime) and Status every 100 ms (schedule).
AnalysisSetup cyclicSetup() {
  AnalysisSetup setup = emptySetup();
  setup.database = test::smallDatabase();
  setup.expectedCycleNs = {OBC_CYCLE_NS, STATUS_CYCLE_NS};
  setup.cycleSource = {CycleSource::Attribute, CycleSource::Schedule};
  setup.nodeNames[0xE5] = "OBC";
  return setup;
}

TraceFrame makeFrame(std::uint32_t id, bool extended, std::int64_t timeNs, std::int32_t message = -1,
                     std::uint16_t bus = 0, std::uint8_t length = 8, std::uint8_t fill = 0xA5) {
  TraceFrame frame;
  frame.frame.id = id;
  frame.frame.flags = extended ? can::FLAG_EXTENDED : 0;
  frame.frame.length = length;
  std::fill_n(frame.frame.data.begin(), length, fill);
  frame.frame.timestampNs = timeNs;
  frame.timeNs = timeNs;
  frame.bus = bus;
  frame.message = message;
  return frame;
}

const MessageStats& findMessage(const StatsReport& report, std::uint32_t id) {
  const auto it = std::find_if(report.messages.begin(), report.messages.end(),
                               [id](const MessageStats& message) { return message.id == id; });
  REQUIRE(it != report.messages.end());
  return *it;
}

const NodeStats& findNode(const StatsReport& report, std::uint8_t sa, bool standard = false) {
  const auto it = std::find_if(report.nodes.begin(), report.nodes.end(), [&](const NodeStats& node) {
    return node.standard == standard && (standard || node.sa == sa);
  });
  REQUIRE(it != report.nodes.end());
  return *it;
}

/// Nearest-rank quantile of exact values (the reference for the histogram's).
double nearestRank(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  return values[std::max<std::size_t>(rank, 1) - 1];
}

const std::vector<std::string> BUS_NAMES{"can0", "can1"};

}  // namespace

TEST_CASE("stats measure exact periods of a 10 ms and a 100 ms message") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  constexpr int OBC_FRAMES = 1000;
  for (int i = 0; i < OBC_FRAMES; ++i) {
    const std::int64_t t = START_NS + i * OBC_CYCLE_NS;
    sut.add(makeFrame(OBC_ID, true, t, OBC_MESSAGE));
    if (i % 10 == 0) sut.add(makeFrame(STATUS_ID, false, t + 1 * MS, STATUS_MESSAGE));
  }
  const StatsReport report = sut.finish(BUS_NAMES);

  CHECK(report.frames == OBC_FRAMES + OBC_FRAMES / 10);
  CHECK(report.durationS == doctest::Approx(9.99));  // the last OBC at 9.99 s (the last Status at 9.901 s)
  REQUIRE(report.messages.size() == 2);
  CHECK(report.messages[0].id == STATUS_ID);  // by identifier
  const MessageStats& obc = findMessage(report, OBC_ID);
  CHECK(obc.name == "OBC");
  CHECK(obc.bus == "can0");
  CHECK(obc.sa == 0xE5);
  CHECK(obc.count == OBC_FRAMES);
  CHECK(obc.periods == OBC_FRAMES - 1);
  CHECK(obc.expectedMs == 10.0);
  CHECK(obc.cycleSource == CycleSource::Attribute);
  CHECK(obc.meanMs == doctest::Approx(10.0));
  CHECK(obc.p50Ms == doctest::Approx(10.0));
  CHECK(obc.p99Ms == doctest::Approx(10.0));
  CHECK(obc.maxMs == doctest::Approx(10.0));
  CHECK(obc.minMs == doctest::Approx(10.0));
  CHECK(obc.deviationMs == doctest::Approx(0.0));
  CHECK(obc.gaps == 0);
  CHECK(obc.missing == 0);
  const MessageStats& status = findMessage(report, STATUS_ID);
  CHECK(status.count == 100);
  CHECK(status.cycleSource == CycleSource::Schedule);
  CHECK(status.meanMs == doctest::Approx(100.0));
  CHECK(status.p99Ms == doctest::Approx(100.0));
  CHECK(status.gaps == 0);
}

TEST_CASE("stats give p50 and p99 of jittered periods within half a bin and the exact max") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  // 100 periods: 60 x 9.83 ms, 30 x 10.27 ms, 9 x 11.42 ms, 1 x 14.0 ms, interleaved.
  std::vector<double> periodsMs;
  for (int i = 0; i < 100; ++i) {
    double period = 9.83;
    if (i % 10 >= 6) period = 10.27;
    if (i % 11 == 5 && i < 99) period = 11.42;
    if (i == 99) period = 14.0;
    periodsMs.push_back(period);
  }
  std::int64_t t = START_NS;
  sut.add(makeFrame(OBC_ID, true, t, OBC_MESSAGE));
  double sumMs = 0;
  for (double periodMs : periodsMs) {
    t += static_cast<std::int64_t>(std::llround(periodMs * MS));
    sumMs += periodMs;
    sut.add(makeFrame(OBC_ID, true, t, OBC_MESSAGE));
  }
  const MessageStats obc = findMessage(sut.finish(BUS_NAMES), OBC_ID);
  const double p50 = nearestRank(periodsMs, 0.50);
  const double p99 = nearestRank(periodsMs, 0.99);
  REQUIRE(p99 == doctest::Approx(11.42));  // the data is what the test means it to be
  CHECK(std::abs(obc.p50Ms - p50) <= HALF_BIN_MS);
  CHECK(std::abs(obc.p99Ms - p99) <= HALF_BIN_MS);
  CHECK(obc.maxMs == doctest::Approx(14.0));
  CHECK(obc.minMs == doctest::Approx(9.83));
  CHECK(obc.meanMs == doctest::Approx(sumMs / 100.0));
  CHECK(obc.deviationMs == doctest::Approx(sumMs / 100.0 - 10.0));
  CHECK(obc.gaps == 0);  // 14 ms < 1.5 x 10 ms
}

TEST_CASE("stats count gaps over 1.5 cycles and the cycles missing in them") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  // OBC every 10 ms for k = 0..99 but k = 20 and k = 50..52 dropped: periods 20 ms and 40 ms.
  int sent = 0;
  for (int k = 0; k < 100; ++k) {
    if (k == 20 || (k >= 50 && k <= 52)) continue;
    sut.add(makeFrame(OBC_ID, true, START_NS + k * OBC_CYCLE_NS, OBC_MESSAGE));
    ++sent;
  }
  // Status (100 ms): periods 150 (not a gap), 151 (gap, 1 missing), 249 (round 2: 1 missing),
  // 250 (round half up to 3: 2 missing).
  std::int64_t t = START_NS;
  sut.add(makeFrame(STATUS_ID, false, t, STATUS_MESSAGE));
  for (std::int64_t periodMs : {150, 151, 249, 250}) {
    t += periodMs * MS;
    sut.add(makeFrame(STATUS_ID, false, t, STATUS_MESSAGE));
  }
  const StatsReport report = sut.finish(BUS_NAMES);
  const MessageStats& obc = findMessage(report, OBC_ID);
  CHECK(obc.count == static_cast<std::uint64_t>(sent));
  CHECK(obc.gaps == 2);
  CHECK(obc.missing == 1 + 3);
  CHECK(obc.maxMs == doctest::Approx(40.0));
  const MessageStats& status = findMessage(report, STATUS_ID);
  CHECK(status.gaps == 3);
  CHECK(status.missing == 1 + 1 + 2);
  CHECK(status.maxMs == doctest::Approx(250.0));
  CHECK(status.minMs == doctest::Approx(150.0));
}

TEST_CASE("stats measure an unknown identifier without expectation, gaps or name") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  sut.add(makeFrame(0x7FF, false, START_NS));
  sut.add(makeFrame(0x7FF, false, START_NS + 500 * MS));
  sut.add(makeFrame(0x7FF, false, START_NS + 5000 * MS));
  const MessageStats unknown = findMessage(sut.finish(BUS_NAMES), 0x7FF);
  CHECK(unknown.name.empty());
  CHECK(unknown.expectedMs == 0.0);
  CHECK(unknown.cycleSource == CycleSource::None);
  CHECK(unknown.count == 3);
  CHECK(unknown.gaps == 0);
  CHECK(unknown.missing == 0);
  CHECK(unknown.maxMs == doctest::Approx(4500.0));
  // Above 200 ms the bins are 1/128 of an octave wide: 4500 ms within 0.4 %.
  CHECK(std::abs(unknown.p99Ms - 4500.0) <= 4500.0 / 256.0);
  CHECK(std::abs(unknown.p50Ms - 500.0) <= 500.0 / 256.0);
}

TEST_CASE("stats skip a period across time going backwards and count it") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  for (std::int64_t ms : {0, 10, 20, 15, 25, 35}) sut.add(makeFrame(OBC_ID, true, START_NS + ms * MS, OBC_MESSAGE));
  const StatsReport report = sut.finish(BUS_NAMES);
  CHECK(report.backwardSteps == 1);
  const MessageStats& obc = findMessage(report, OBC_ID);
  CHECK(obc.count == 6);
  CHECK(obc.periods == 4);
  CHECK(obc.meanMs == doctest::Approx(10.0));
  CHECK(obc.minMs == doctest::Approx(10.0));
  CHECK(obc.gaps == 0);
}

TEST_CASE("stats give each source address its share of the bus' wire bits") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  const TraceFrame fromEngine = makeFrame(0x18FEF100, true, 0);
  const TraceFrame fromObc = makeFrame(OBC_ID, true, 0, OBC_MESSAGE);
  const TraceFrame standard = makeFrame(STATUS_ID, false, 0, STATUS_MESSAGE, 0, 2);
  // Every 10 ms: the engine (SA 0x00) 3 frames, OBC (SA 0xE5) 1, Status (11-bit) 1; 100 rounds.
  constexpr int ROUNDS = 100;
  for (int i = 0; i < ROUNDS; ++i) {
    const std::int64_t t = START_NS + i * 10 * MS;
    for (int j = 0; j < 3; ++j) {
      TraceFrame frame = fromEngine;
      frame.timeNs = t + j * MS;
      sut.add(frame);
    }
    TraceFrame obc = fromObc;
    obc.timeNs = t + 4 * MS;
    sut.add(obc);
    TraceFrame status = standard;
    status.timeNs = t + 5 * MS;
    sut.add(status);
  }
  const StatsReport report = sut.finish(BUS_NAMES);
  const double engineBits = 3.0 * ROUNDS * can::frameBits(fromEngine.frame);
  const double obcBits = 1.0 * ROUNDS * can::frameBits(fromObc.frame);
  const double standardBits = 1.0 * ROUNDS * can::frameBits(standard.frame);
  const double allBits = engineBits + obcBits + standardBits;
  const double durationS = 0.99 + 0.005;  // first frame at 0 ms, last at 990 + 5 ms

  REQUIRE(report.nodes.size() == 3);
  CHECK(report.nodes[0].sa == 0x00);  // most bits first
  const NodeStats& engine = findNode(report, 0x00);
  CHECK(engine.frames == 3 * ROUNDS);
  CHECK(engine.name.empty());
  CHECK(engine.sharePct == doctest::Approx(100.0 * engineBits / allBits));
  CHECK(engine.bitsPerS == doctest::Approx(engineBits / durationS));
  const NodeStats& obcNode = findNode(report, 0xE5);
  CHECK(obcNode.name == "OBC");
  CHECK(obcNode.frames == ROUNDS);
  CHECK(obcNode.sharePct == doctest::Approx(100.0 * obcBits / allBits));
  const NodeStats& standardNode = findNode(report, 0, true);
  CHECK(standardNode.frames == ROUNDS);
  CHECK(standardNode.sharePct == doctest::Approx(100.0 * standardBits / allBits));
  CHECK(engine.sharePct + obcNode.sharePct + standardNode.sharePct == doctest::Approx(100.0));
}

TEST_CASE("stats give the mean and the peak bus load from exact wire bits") {
  // ISO 11898-1: standard 0x555, DLC 8, A5 x 8 = 108 frame bits, 0 stuff bits, 3 intermission
  // = 111 bits = 222 us at 500 kbit/s.
  constexpr double FRAME_US = 222.0;
  const AnalysisSetup setup = emptySetup();
  TraceStats sut(setup);
  REQUIRE(can::frameBits(makeFrame(0x555, false, 0).frame) == 111);
  // One frame every 10 ms for 5 s (500), and a burst of one every 1 ms in [2.0 s, 2.5 s) (500).
  for (int i = 0; i < 500; ++i) sut.add(makeFrame(0x555, false, START_NS + i * 10 * MS));
  for (int i = 0; i < 500; ++i) sut.add(makeFrame(0x555, false, START_NS + 2000 * MS + i * MS + 500 * US));
  sut.add(makeFrame(0x555, false, START_NS + 5000 * MS));  // the end: duration exactly 5 s
  const StatsReport report = sut.finish(BUS_NAMES);

  REQUIRE(report.buses.size() == 1);
  const BusStats& bus = report.buses[0];
  CHECK(bus.bus == "can0");
  CHECK(bus.bitrate == 500'000);
  CHECK(bus.frames == 1001);
  CHECK(bus.durationS == doctest::Approx(5.0));
  CHECK(bus.loadMeanPct == doctest::Approx(100.0 * 1001 * FRAME_US * 1e-6 / 5.0));
  // The busiest 1 s holds the whole burst and 100 regular frames.
  CHECK(bus.loadMaxPct == doctest::Approx(100.0 * 600 * FRAME_US * 1e-6));
  // Series: 10 ms buckets from the first frame; [2.00, 2.01) s holds 1 regular + 10 burst frames.
  CHECK(bus.loadBucketS == doctest::Approx(0.01));
  REQUIRE(bus.loadSeries.size() == 501);
  CHECK(bus.loadSeries[200].first == doctest::Approx(2.0));
  CHECK(bus.loadSeries[200].second == doctest::Approx(100.0 * 11 * FRAME_US / 10'000.0));
  CHECK(bus.loadSeries[100].second == doctest::Approx(100.0 * FRAME_US / 10'000.0));
}

TEST_CASE("stats merge the load series pairwise when it is full") {
  const AnalysisSetup setup = emptySetup();
  TraceStats sut(setup);
  // 25 s of one 222 us frame per ms: 2,500 buckets of 10 ms -> width 40 ms, 625 points.
  constexpr int FRAMES = 25'000;
  for (int i = 0; i < FRAMES; ++i) sut.add(makeFrame(0x555, false, START_NS + i * MS));
  const BusStats bus = sut.finish(BUS_NAMES).buses.at(0);
  CHECK(bus.loadBucketS == doctest::Approx(0.04));
  CHECK(bus.loadSeries.size() == 625);
  CHECK(bus.loadSeries.size() <= LOAD_SERIES_POINTS);
  CHECK(bus.loadSeries[300].first == doctest::Approx(12.0));
  CHECK(bus.loadSeries[300].second == doctest::Approx(22.2));
  CHECK(bus.loadMeanPct == doctest::Approx(100.0 * FRAMES * 222e-6 / 24.999));
  CHECK(bus.loadMaxPct == doctest::Approx(22.2));
}

TEST_CASE("stats measure each bus at its configured bit rates") {
  AnalysisSetup setup = emptySetup();
  setup.buses = {AnalysisBus{"slow", 250'000, 0}, AnalysisBus{"fd", 500'000, 2'000'000}};
  const std::vector<std::string> names{"slow", "fd"};
  TraceStats sut(setup, names);
  TraceFrame fd = makeFrame(0x18FEF100, true, 0, -1, 1, 64);
  fd.frame.flags |= can::FLAG_FD | can::FLAG_BRS;
  for (int i = 0; i <= 100; ++i) {
    sut.add(makeFrame(0x555, false, START_NS + i * 10 * MS));
    fd.timeNs = START_NS + i * 10 * MS;
    sut.add(fd);
  }
  const StatsReport report = sut.finish(names);
  REQUIRE(report.buses.size() == 2);
  CHECK(report.buses[0].bitrate == 250'000);
  // 101 x 111 bits at 250 kbit/s (444 us) over 1 s.
  CHECK(report.buses[0].loadMeanPct == doctest::Approx(100.0 * 101 * 444e-6 / 1.0));
  const double fdFrameNs = static_cast<double>(can::wireTimeNs(fd.frame, 500'000, 2'000'000));
  CHECK(fdFrameNs < static_cast<double>(can::frameBits(fd.frame)) * 2000.0);  // the data phase is faster
  CHECK(report.buses[1].loadMeanPct == doctest::Approx(100.0 * 101 * fdFrameNs / 1e9));
}

TEST_CASE("stats count error frames on the bus as 17 bits, not as a message or node") {
  const AnalysisSetup setup = emptySetup();
  TraceStats sut(setup);
  sut.add(makeFrame(0x555, false, START_NS));
  TraceFrame error = makeFrame(0x004, false, START_NS + 100 * MS, -1, 0, 8, 0);
  error.frame.flags = can::FLAG_ERROR;
  sut.add(error);
  sut.add(makeFrame(0x555, false, START_NS + 200 * MS));
  const StatsReport report = sut.finish(BUS_NAMES);
  CHECK(report.buses[0].frames == 3);
  CHECK(report.buses[0].errorFrames == 1);
  CHECK(report.buses[0].loadMeanPct == doctest::Approx(100.0 * (2 * 111 + can::ERROR_FRAME_BITS) * 2e-6 / 0.2));
  CHECK(report.messages.size() == 1);
  REQUIRE(report.nodes.size() == 1);
  CHECK(report.nodes[0].sharePct == doctest::Approx(100.0 * 222 / (222 + can::ERROR_FRAME_BITS)));
}

TEST_CASE("stats track at most MAX_STREAMS identifiers and count the frames of further ones") {
  const AnalysisSetup setup = emptySetup();
  TraceStats sut(setup);
  for (std::uint32_t i = 0; i <= MAX_STREAMS; ++i) sut.add(makeFrame(0x10000000u + i, true, START_NS + i * US));
  sut.add(makeFrame(0x10000000u, true, START_NS + 10 * MS));  // a tracked stream still counts
  const StatsReport report = sut.finish(BUS_NAMES);
  CHECK(report.messages.size() == MAX_STREAMS);
  CHECK(report.skippedFrames == 1);
  CHECK(report.messages[0].count == 2);
  CHECK(report.buses[0].frames == MAX_STREAMS + 2);  // the bus load still counts every frame
}

TEST_CASE("stats keep the same identifier on two buses apart") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  sut.add(makeFrame(OBC_ID, true, START_NS, OBC_MESSAGE, 0));
  sut.add(makeFrame(OBC_ID, true, START_NS + 1 * MS, OBC_MESSAGE, 1));
  sut.add(makeFrame(OBC_ID, true, START_NS + 10 * MS, OBC_MESSAGE, 0));
  sut.add(makeFrame(OBC_ID, true, START_NS + 21 * MS, OBC_MESSAGE, 1));
  const StatsReport report = sut.finish(BUS_NAMES);
  REQUIRE(report.messages.size() == 2);
  CHECK(report.messages[0].bus == "can0");
  CHECK(report.messages[0].meanMs == doctest::Approx(10.0));
  CHECK(report.messages[1].bus == "can1");
  CHECK(report.messages[1].meanMs == doctest::Approx(20.0));
  CHECK(report.buses.size() == 2);
}

TEST_CASE("stats JSON holds the required names with their figures") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  for (int i = 0; i < 11; ++i) sut.add(makeFrame(OBC_ID, true, START_NS + i * OBC_CYCLE_NS, OBC_MESSAGE));
  sut.add(makeFrame(0x7FF, false, START_NS + 3 * MS));
  std::string text;
  appendStatsJson(text, sut.finish(BUS_NAMES));
  const nlohmann::json json = nlohmann::json::parse(text);
  REQUIRE(json["buses"].size() == 1);
  CHECK(json["buses"][0]["bus"] == "can0");
  CHECK(json["buses"][0].contains("load_mean_pct"));
  CHECK(json["buses"][0].contains("load_max_pct"));
  REQUIRE(json["nodes"].size() == 2);
  CHECK(json["nodes"][0]["sa"] == 0xE5);
  CHECK(json["nodes"][0]["name"] == "OBC");
  CHECK(json["nodes"][0]["frames"] == 11);
  CHECK(json["nodes"][1]["sa"].is_null());
  CHECK(json["nodes"][1]["standard"] == true);
  for (const char* key : {"bits_per_s", "share_pct"}) CHECK(json["nodes"][0].contains(key));
  REQUIRE(json["messages"].size() == 2);
  const nlohmann::json& unknown = json["messages"][0];
  CHECK(unknown["id"] == "0x7FF");
  CHECK(unknown["name"].is_null());
  CHECK(unknown["expected_ms"].is_null());
  CHECK(unknown["mean_ms"].is_null());  // one frame: no period
  const nlohmann::json& obc = json["messages"][1];
  CHECK(obc["id"] == "0x18FF50E5");
  CHECK(obc["name"] == "OBC");
  CHECK(obc["count"] == 11);
  CHECK(obc["expected_ms"] == 10.0);
  CHECK(obc["cycle_source"] == "GenMsgCycleTime");
  for (const char* key : {"mean_ms", "p50_ms", "p99_ms", "max_ms"}) CHECK(obc[key] == 10.0);
  CHECK(obc["gaps"] == 0);
  CHECK(obc["missing"] == 0);
  CHECK(json["period_resolution"]["bin_ms"] == 0.1);
}

TEST_CASE("stats text has the three tables with units") {
  const AnalysisSetup setup = cyclicSetup();
  TraceStats sut(setup);
  for (int i = 0; i < 11; ++i) sut.add(makeFrame(OBC_ID, true, START_NS + i * OBC_CYCLE_NS, OBC_MESSAGE));
  std::string text;
  appendStatsText(text, sut.finish(BUS_NAMES));
  CHECK(text.find("LOAD MEAN %") != std::string::npos);
  CHECK(text.find("BIT/S") != std::string::npos);
  CHECK(text.find("SHARE %") != std::string::npos);
  CHECK(text.find("EXPECTED") != std::string::npos);
  CHECK(text.find("periods in ms") != std::string::npos);
  CHECK(text.find("0x18FF50E5  OBC") != std::string::npos);
  CHECK(text.find("500 kbit/s") != std::string::npos);
}
