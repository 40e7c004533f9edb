// The Trace tab's Statistics page model (TraceStatsModel, issue 21) on logs generated here
// with known answers: a message at an exact 10 ms period, another at 20 ms with one frame
// dropped, from two source addresses; logs that cannot be read; a folder of logs.
#include <doctest/doctest.h>

#include <QPointF>
#include <QTemporaryDir>
#include <QVariantMap>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "common/stack_connection.hpp"
#include "hmi_test_support.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/can/wire_time.hpp"
#include "trace/trace_stats_model.hpp"

using namespace openvcu;
using namespace openvcu::hmi;

namespace {

/// EEC1 (PGN 0xF004) from the engine (SA 0x00) every 10 ms, EBC1 (PGN 0xF001) from the
/// brakes (SA 0x0B) every 20 ms, both with GenMsgCycleTime.
constexpr const char* DBC_TEXT = R"(VERSION ""

NS_ :

BS_:

BU_: Engine Brake

BO_ 2364539904 EEC1: 8 Engine
 SG_ EngineSpeed : 24|16@1+ (0.125,0) [0|8031.875] "rpm" Vector__XXX

BO_ 2565865739 EBC1: 8 Brake
 SG_ BrakePedal : 8|8@1+ (0.4,0) [0|100] "%" Vector__XXX

BA_DEF_ BO_  "GenMsgCycleTime" INT 0 65535;
BA_DEF_DEF_  "GenMsgCycleTime" 0;
BA_ "GenMsgCycleTime" BO_ 2364539904 10;
BA_ "GenMsgCycleTime" BO_ 2565865739 20;
)";
constexpr std::uint32_t EEC1_ID = 0x0CF00400;
constexpr std::uint32_t EBC1_ID = 0x18F0010B;
constexpr int EEC1_FRAMES = 100;     // t = 0, 10, ..., 990 ms
constexpr int EBC1_SLOTS = 50;       // t = 5, 25, ..., 985 ms
constexpr int EBC1_DROPPED = 25;     // the frame at 505 ms is missing
constexpr double BITRATE = 500'000;  // the default of a bus no configuration names
constexpr double BIN_MS = static_cast<double>(trace::PERIOD_BIN_NS) / 1e6;
constexpr std::int64_t START_US = 1'700'000'000'000'000;

std::string candumpLine(std::int64_t us, std::uint32_t id, const char* data) {
  char line[96];
  std::snprintf(line, sizeof line, "(%lld.%06lld) can0 %08X#%s\n", static_cast<long long>(us / 1'000'000),
                static_cast<long long>(us % 1'000'000), id, data);
  return line;
}

constexpr const char* EEC1_DATA = "00112233445566FF";
constexpr const char* EBC1_DATA = "0102030405060708";

/// Writes the DBC and the log of the known answers into `folder`; returns the log's path.
std::string writeKnownLog(const QTemporaryDir& folder, const std::string& extraLine = {}) {
  std::ofstream(folder.filePath("vehicle.dbc").toStdString()) << DBC_TEXT;
  const std::string path = folder.filePath("drive.log").toStdString();
  std::ofstream out(path);
  for (int i = 0; i < EEC1_FRAMES; ++i) {
    out << candumpLine(START_US + i * 10'000, EEC1_ID, EEC1_DATA);
    if (i % 2 == 0 && i / 2 != EBC1_DROPPED) out << candumpLine(START_US + 5'000 + i / 2 * 20'000, EBC1_ID, EBC1_DATA);
    if (i == 10) out << extraLine;
  }
  return path;
}

/// The wire bits of one frame of the log (the figure can-rx and the analysis count).
double bitsOf(std::uint32_t id, const char* data) {
  std::istringstream line(candumpLine(START_US, id, data));
  can::LogReader reader(line);
  const auto record = reader.next();
  REQUIRE(record);
  return can::frameBits(record->frame);
}

std::unique_ptr<StackConnection> openStack() {
  test::ensureApplication("test_hmi_models");
  auto opened = StackConnection::open(test::memqSettings("hmi-stats"));
  REQUIRE_MESSAGE(opened, opened.error().toString());
  return std::move(*opened);
}

QVariant role(const QAbstractItemModel& model, int row, int which) {
  return model.data(model.index(row, 0), which);
}

}  // namespace

TEST_CASE("the statistics model gives the known cycle, gap, node and bus load figures of a generated log") {
  auto stack = openStack();
  QTemporaryDir folder;
  const std::string log = writeKnownLog(folder);
  TraceStatsModel sut;
  CHECK(sut.setupPath() == QString::fromStdString(test::HHEA_CONFIG));  // the configuration the HMI runs with
  sut.setSetupPath(folder.filePath("vehicle.dbc"));
  sut.compute({QString::fromStdString(log)});
  CHECK(sut.computing());
  sut.waitUntilComputed();
  REQUIRE_MESSAGE(sut.status() == ModelStatus::Ready, sut.errorString().toStdString());
  CHECK(sut.paths() == QStringList{QString::fromStdString(log)});
  CHECK(sut.framesRead() == EEC1_FRAMES + EBC1_SLOTS - 1);

  // messages, by identifier: EEC1 exact, EBC1 one frame missing
  REQUIRE(sut.rowCount() == 2);
  using R = TraceStatsModel::Role;
  CHECK(role(sut, 0, R::NameRole).toString() == "EEC1");
  CHECK(role(sut, 0, R::FrameIdRole).toString() == "0x0CF00400");
  CHECK(role(sut, 0, R::BusRole).toString() == "can0");
  CHECK(role(sut, 0, R::CountRole).toULongLong() == EEC1_FRAMES);
  CHECK(role(sut, 0, R::ExpectedMsRole).toDouble() == 10.0);
  CHECK(role(sut, 0, R::CycleSourceRole).toString() == "DBC");
  CHECK(role(sut, 0, R::MeanMsRole).toDouble() == doctest::Approx(10.0).epsilon(1e-9));
  CHECK(role(sut, 0, R::P50MsRole).toDouble() == doctest::Approx(10.0).epsilon(BIN_MS / 10));
  CHECK(role(sut, 0, R::P99MsRole).toDouble() == doctest::Approx(10.0).epsilon(BIN_MS / 10));
  CHECK(role(sut, 0, R::MaxMsRole).toDouble() == doctest::Approx(10.0).epsilon(1e-9));
  CHECK(role(sut, 0, R::DeviationMsRole).toDouble() == doctest::Approx(0.0).epsilon(1e-9));
  CHECK(role(sut, 0, R::GapsRole).toULongLong() == 0);
  CHECK(role(sut, 0, R::MissingRole).toULongLong() == 0);
  CHECK_FALSE(role(sut, 0, R::FlaggedRole).toBool());

  CHECK(role(sut, 1, R::NameRole).toString() == "EBC1");
  CHECK(role(sut, 1, R::CountRole).toULongLong() == EBC1_SLOTS - 1);
  CHECK(role(sut, 1, R::ExpectedMsRole).toDouble() == 20.0);
  // 48 periods over 980 ms: 47 x 20 ms and one of 40 ms where the frame is missing
  CHECK(role(sut, 1, R::MeanMsRole).toDouble() == doctest::Approx(980.0 / 48).epsilon(1e-9));
  CHECK(role(sut, 1, R::P50MsRole).toDouble() == doctest::Approx(20.0).epsilon(BIN_MS / 20));
  CHECK(role(sut, 1, R::MaxMsRole).toDouble() == doctest::Approx(40.0).epsilon(1e-9));
  CHECK(role(sut, 1, R::GapsRole).toULongLong() == 1);
  CHECK(role(sut, 1, R::MissingRole).toULongLong() == 1);
  CHECK(role(sut, 1, R::FlaggedRole).toBool());  // a missed cycle is highlighted

  // nodes: the engine sends more bits than the brakes; names from the DBC's transmitters
  const double engineBits = EEC1_FRAMES * bitsOf(EEC1_ID, EEC1_DATA);
  const double brakeBits = (EBC1_SLOTS - 1) * bitsOf(EBC1_ID, EBC1_DATA);
  const double seconds = 0.990;  // first to last frame on the bus
  QAbstractListModel* nodes = sut.nodes();
  REQUIRE(nodes->rowCount() == 2);
  using N = TraceNodeModel::Role;
  CHECK(role(*nodes, 0, N::SaRole).toInt() == 0x00);
  CHECK(role(*nodes, 0, N::SaTextRole).toString() == "0x00");
  CHECK(role(*nodes, 0, N::NameRole).toString() == "Engine");
  CHECK(role(*nodes, 0, N::FramesRole).toULongLong() == EEC1_FRAMES);
  CHECK(role(*nodes, 0, N::BitsPerSRole).toDouble() == doctest::Approx(engineBits / seconds).epsilon(1e-6));
  CHECK(role(*nodes, 0, N::SharePctRole).toDouble() ==
        doctest::Approx(100 * engineBits / (engineBits + brakeBits)).epsilon(1e-6));
  CHECK(role(*nodes, 1, N::SaRole).toInt() == 0x0B);
  CHECK(role(*nodes, 1, N::NameRole).toString() == "Brake");
  CHECK(role(*nodes, 1, N::FramesRole).toULongLong() == EBC1_SLOTS - 1);
  CHECK(role(*nodes, 1, N::SharePctRole).toDouble() ==
        doctest::Approx(100 * brakeBits / (engineBits + brakeBits)).epsilon(1e-6));

  // the bus: all wire bits over the duration at the default 500 kbit/s
  REQUIRE(sut.buses().size() == 1);
  const QVariantMap bus = sut.buses()[0].toMap();
  CHECK(bus["bus"].toString() == "can0");
  CHECK(bus["bitrate"].toUInt() == 500'000u);
  CHECK(bus["frames"].toULongLong() == EEC1_FRAMES + EBC1_SLOTS - 1);
  CHECK(bus["loadMeanPct"].toDouble() ==
        doctest::Approx(100 * (engineBits + brakeBits) / (seconds * BITRATE)).epsilon(1e-6));
  // the busiest 1 s window: at least about the mean (the log is shorter than a window)
  CHECK(bus["loadMaxPct"].toDouble() >= bus["loadMeanPct"].toDouble() * 0.95);
  const QVariantList series = bus["series"].toList();
  REQUIRE_FALSE(series.isEmpty());
  CHECK(series.size() <= static_cast<qsizetype>(trace::LOAD_SERIES_POINTS));
  CHECK(series.front().toPointF().x() >= 0);
  CHECK(bus["seriesMaxPct"].toDouble() >= bus["loadMaxPct"].toDouble() * 0.95);  // buckets are shorter than the window
  CHECK(sut.summary().contains("149 frames"));
}

TEST_CASE("the statistics model reports skipped lines, a log it cannot open and a configuration that does not load") {
  auto stack = openStack();
  QTemporaryDir folder;
  const std::string log = writeKnownLog(folder, "this line is broken\n");
  TraceStatsModel sut;
  sut.setSetupPath(folder.filePath("vehicle.dbc"));
  sut.compute({QString::fromStdString(log)});
  sut.waitUntilComputed();
  CHECK(sut.status() == ModelStatus::Stale);  // computed, with a note
  CHECK_MESSAGE(sut.errorString().contains("1 malformed line"), sut.errorString().toStdString());
  CHECK_MESSAGE(sut.errorString().contains("drive.log:"), sut.errorString().toStdString());  // file:line of the reason
  CHECK(sut.rowCount() == 2);                                                                // the analysis went on

  sut.compute({QString::fromStdString(log), QStringLiteral("/nonexistent/body.log")});
  sut.waitUntilComputed();
  CHECK(sut.status() == ModelStatus::Error);
  CHECK(sut.errorString().contains("/nonexistent/body.log"));

  TraceStatsModel noConfig;
  noConfig.setSetupPath(folder.filePath("missing.json"));
  noConfig.compute({QString::fromStdString(log)});
  noConfig.waitUntilComputed();
  CHECK(noConfig.status() == ModelStatus::Stale);
  CHECK_MESSAGE(noConfig.errorString().contains("without a DBC"), noConfig.errorString().toStdString());
  REQUIRE(noConfig.rowCount() == 2);  // measured, but unnamed and without an expectation
  CHECK(role(noConfig, 0, TraceStatsModel::NameRole).toString().isEmpty());
  CHECK(role(noConfig, 0, TraceStatsModel::ExpectedMsRole).toDouble() == 0.0);
  CHECK_FALSE(role(noConfig, 1, TraceStatsModel::FlaggedRole).toBool());  // nothing to deviate from
}

TEST_CASE("the statistics model lists a recording folder's logs and computes the logs asked for last") {
  auto stack = openStack();
  QTemporaryDir folder;
  const std::string log = writeKnownLog(folder);
  std::ofstream(folder.filePath("body.log").toStdString()) << candumpLine(START_US, 0x123, "11");
  std::ofstream(folder.filePath("notes.txt").toStdString()) << "not a log\n";
  const QStringList logs = TraceStatsModel::logsInFolder(folder.path());
  CHECK(logs == QStringList{folder.filePath("body.log"), folder.filePath("drive.log")});
  CHECK(TraceStatsModel::logsInFolder(folder.filePath("notes.txt")).isEmpty());
  CHECK(TraceStatsModel::logsInFolder("").isEmpty());

  TraceStatsModel sut;
  sut.setSetupPath(folder.filePath("vehicle.dbc"));
  sut.compute({QString::fromStdString(log)});
  sut.compute(logs);  // while the first runs: it is cancelled, the second wins
  sut.waitUntilComputed();
  CHECK(sut.paths() == logs);
  CHECK(sut.rowCount() == 3);  // 0x123 from body.log and the two of drive.log, one timeline
  CHECK(sut.report().frames == 1 + EEC1_FRAMES + EBC1_SLOTS - 1);
}
