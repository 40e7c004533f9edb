// TransportAnalysis (issue 21): TP session findings, DM1 DTCs raised and cleared with their
// intervals, reassembled messages handed on; TraceFrames fed directly.
#include "openvcu/trace/transport_analysis.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "openvcu/dbc/parser.hpp"

using openvcu::can::FLAG_EXTENDED;
namespace dbc = openvcu::dbc;
using namespace openvcu::trace;

namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t T0 = 1'700'000'000'000 * MS;
constexpr std::uint16_t VEHICLE_BUS = 0;
constexpr std::uint16_t BODY_BUS = 1;

struct Collector final : FindingSink {
  std::vector<Finding> findings;
  void finding(const Finding& finding) override { findings.push_back(finding); }
};

TraceFrame frameOf(std::uint16_t bus, std::int64_t timeNs, std::uint32_t id, const Bytes& data) {
  TraceFrame frame;
  frame.frame.id = id;
  frame.frame.flags = FLAG_EXTENDED;
  frame.frame.length = static_cast<std::uint8_t>(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) frame.frame.data[i] = data[i];
  frame.frame.timestampNs = timeNs;
  frame.timeNs = timeNs;
  frame.bus = bus;
  return frame;
}

// DM1 from 0x21, amber lamp on, three DTCs:
//   SPN 100 FMI 1 OC 3         64 00 01 03
//   SPN 110 FMI 0 OC 1         6E 00 00 01
//   SPN 520192 FMI 31 OC 126   00 F0 FF 7E   (SPN bits 18..16 = 7 in byte 2 bits 7-5)
const Bytes THREE_DTCS = {0x04, 0xFF, 0x64, 0x00, 0x01, 0x03, 0x6E, 0x00, 0x00, 0x01, 0x00, 0xF0, 0xFF, 0x7E};
constexpr std::uint32_t DM1_BAM_CM = 0x1CECFF21;
constexpr std::uint32_t DM1_BAM_DT = 0x1CEBFF21;
constexpr std::uint32_t DM1_SINGLE = 0x18FECA21;

std::string listOf(const std::vector<Finding>& findings) {
  std::string text;
  for (const Finding& finding : findings) text += finding.text + "\n";
  return text;
}

}  // namespace

TEST_CASE("transport analysis reports a DM1 by BAM, its three DTCs, a clear, an abort and a truncated BAM") {
  AnalysisSetup setup;
  std::vector<ReassembledMessage> messages;
  std::vector<Bytes> messageData;
  TransportAnalysis sut(setup, [&](const ReassembledMessage& message) {
    messages.push_back(message);
    messageData.emplace_back(message.data.begin(), message.data.end());
  });
  Collector out;

  // DM1 by BAM: 14 bytes in 2 packets, 50 ms apart.
  const std::int64_t bamNs = T0;
  const std::int64_t lastPacketNs = T0 + 100 * MS;
  sut.add(frameOf(VEHICLE_BUS, bamNs, DM1_BAM_CM, {0x20, 14, 0x00, 2, 0xFF, 0xCA, 0xFE, 0x00}), out);
  sut.add(frameOf(VEHICLE_BUS, T0 + 50 * MS, DM1_BAM_DT, {1, 0x04, 0xFF, 0x64, 0x00, 0x01, 0x03, 0x6E}), out);
  sut.add(frameOf(VEHICLE_BUS, lastPacketNs, DM1_BAM_DT, {2, 0x00, 0x00, 0x01, 0x00, 0xF0, 0xFF, 0x7E}), out);

  INFO(listOf(out.findings));
  REQUIRE(out.findings.size() == 4);
  CHECK(out.findings[0].check == Check::Dtc);
  CHECK(out.findings[0].severity == Severity::Warning);
  CHECK(out.findings[0].text == "0x21 DM1: DTC raised SPN 100 FMI 1 OC 3 (lamps: amber on)");
  CHECK(out.findings[1].text == "0x21 DM1: DTC raised SPN 110 FMI 0 OC 1 (lamps: amber on)");
  CHECK(out.findings[2].text == "0x21 DM1: DTC raised SPN 520192 FMI 31 OC 126 (lamps: amber on)");
  CHECK(out.findings[3].check == Check::Transport);
  CHECK(out.findings[3].severity == Severity::Info);
  CHECK(out.findings[3].text == "BAM 0x21 -> all PGN 65226 (0xFECA) DM1 14 bytes in 2 packets, 100.0 ms");
  CHECK(out.findings[3].timeNs == lastPacketNs);
  REQUIRE(messages.size() == 1);
  CHECK(messages[0].pgn == 0xFECA);
  CHECK(messages[0].source == 0x21);
  CHECK(messages[0].broadcast);
  CHECK(messages[0].message == -1);
  CHECK(messageData[0] == THREE_DTCS);

  REQUIRE(sut.dtcIntervals().size() == 3);
  const DtcInterval& first = sut.dtcIntervals()[0];
  CHECK(first.bus == VEHICLE_BUS);
  CHECK(first.source == 0x21);
  CHECK_FALSE(first.previouslyActive);
  CHECK(first.spn == 100);
  CHECK(first.fmi == 1);
  CHECK(first.occurrenceCount == 3);
  CHECK(first.raisedNs == lastPacketNs);
  CHECK(sut.dtcIntervals()[1].spn == 110);
  CHECK(sut.dtcIntervals()[1].fmi == 0);
  CHECK(sut.dtcIntervals()[1].occurrenceCount == 1);
  CHECK(sut.dtcIntervals()[2].spn == 520192);
  CHECK(sut.dtcIntervals()[2].fmi == 31);
  CHECK(sut.dtcIntervals()[2].occurrenceCount == 126);
  for (const DtcInterval& interval : sut.dtcIntervals()) CHECK_FALSE(interval.clearedNs.has_value());

  // One second later a single-frame DM1: only SPN 100 FMI 1 left, OC now 4.
  out.findings.clear();
  const std::int64_t clearNs = T0 + 1'100 * MS;
  sut.add(frameOf(VEHICLE_BUS, clearNs, DM1_SINGLE, {0x04, 0xFF, 0x64, 0x00, 0x01, 0x04, 0xFF, 0xFF}), out);
  REQUIRE(out.findings.size() == 2);
  CHECK(out.findings[0].severity == Severity::Info);
  CHECK(out.findings[0].text == "0x21 DM1: DTC cleared SPN 110 FMI 0 (last OC 1) (lamps: amber on)");
  CHECK(out.findings[1].text == "0x21 DM1: DTC cleared SPN 520192 FMI 31 (last OC 126) (lamps: amber on)");
  CHECK(out.findings[1].timeNs == clearNs);
  CHECK_FALSE(sut.dtcIntervals()[0].clearedNs.has_value());
  CHECK(sut.dtcIntervals()[0].occurrenceCount == 4);
  CHECK(sut.dtcIntervals()[1].clearedNs == clearNs);
  CHECK(sut.dtcIntervals()[2].clearedNs == clearNs);
  REQUIRE(messages.size() == 2);
  CHECK(messages[1].data.size() == 8);

  // Lamps off and no DTC: the last one cleared and the lamp change reported.
  out.findings.clear();
  const std::int64_t allClearNs = T0 + 2'100 * MS;
  sut.add(frameOf(VEHICLE_BUS, allClearNs, DM1_SINGLE, {0x00, 0xFF, 0x00, 0x00, 0x00, 0x00, 0xFF, 0xFF}), out);
  REQUIRE(out.findings.size() == 2);
  CHECK(out.findings[0].text == "0x21 DM1: DTC cleared SPN 100 FMI 1 (last OC 4) (lamps: all off)");
  CHECK(out.findings[1].text == "0x21 DM1: lamps amber on -> all off");
  CHECK(sut.dtcIntervals()[0].clearedNs == allClearNs);

  // An RTS/CTS session on the other bus, refused by the responder with an Abort.
  out.findings.clear();
  const std::int64_t rtsNs = T0 + 3'000 * MS;
  sut.add(frameOf(BODY_BUS, rtsNs, 0x1CEC2120, {0x10, 20, 0x00, 3, 0xFF, 0xEB, 0xFE, 0x00}), out);
  sut.add(frameOf(BODY_BUS, rtsNs + 5 * MS, 0x1CEC2021, {0xFF, 1, 0xFD, 0xFF, 0xFF, 0xEB, 0xFE, 0x00}), out);
  REQUIRE(out.findings.size() == 1);
  CHECK(out.findings[0].bus == BODY_BUS);
  CHECK(out.findings[0].severity == Severity::Fault);
  CHECK(out.findings[0].check == Check::Transport);
  CHECK(out.findings[0].timeNs == rtsNs + 5 * MS);
  CHECK(out.findings[0].text ==
        "RTS/CTS 0x20 -> 0x21 PGN 65259 (0xFEEB) 20 bytes: aborted by the responder, reason 1 AlreadyInSession, "
        "after 0 of 3 packets");

  // A BAM cut off by the end of the log.
  out.findings.clear();
  const std::int64_t truncatedNs = T0 + 4'000 * MS;
  sut.add(frameOf(VEHICLE_BUS, truncatedNs, 0x1CECFF00, {0x20, 20, 0x00, 3, 0xFF, 0xE3, 0xFE, 0x00}), out);
  sut.add(frameOf(VEHICLE_BUS, truncatedNs + 50 * MS, 0x1CEBFF00, {1, 1, 2, 3, 4, 5, 6, 7}), out);
  const std::int64_t endNs = truncatedNs + 60 * MS;
  sut.finish(endNs, out);
  REQUIRE(out.findings.size() == 1);
  CHECK(out.findings[0].severity == Severity::Fault);
  CHECK(out.findings[0].timeNs == endNs);
  CHECK(out.findings[0].text ==
        "BAM 0x00 -> all PGN 65251 (0xFEE3) 20 bytes: incomplete at the end of the log, 1 of 3 packets");

  const TransportCounts& counts = sut.counts();
  CHECK(counts.sessions == 3);
  CHECK(counts.bam == 2);
  CHECK(counts.rtsCts == 1);
  CHECK(counts.completed == 1);
  CHECK(counts.aborted == 1);
  CHECK(counts.incomplete == 1);
  CHECK(counts.timedOut == 0);
  CHECK(counts.dm1Messages == 3);
  CHECK(messages.size() == 3);
}

TEST_CASE("transport analysis times out a session on a quiet bus when frames arrive on another") {
  AnalysisSetup setup;
  TransportAnalysis sut(setup);
  Collector out;
  sut.add(frameOf(VEHICLE_BUS, T0, 0x1CECFF00, {0x20, 20, 0x00, 3, 0xFF, 0xE3, 0xFE, 0x00}), out);
  sut.add(frameOf(BODY_BUS, T0 + 749 * MS, 0x18FEF100, {0, 0, 0, 0, 0, 0, 0, 0}), out);
  CHECK(out.findings.empty());
  sut.add(frameOf(BODY_BUS, T0 + 750 * MS, 0x18FEF100, {0, 0, 0, 0, 0, 0, 0, 0}), out);
  REQUIRE(out.findings.size() == 1);
  CHECK(out.findings[0].bus == VEHICLE_BUS);
  CHECK(out.findings[0].timeNs == T0 + 750 * MS);
  CHECK(out.findings[0].text ==
        "BAM 0x00 -> all PGN 65251 (0xFEE3) 20 bytes: timed out (T1, 750 ms between packets) after 0 of 3 packets");
  CHECK(sut.counts().timedOut == 1);
}

TEST_CASE("transport analysis names a reassembled message by the DBC message its PGN matches") {
  dbc::ParseOutput parsed = dbc::parse(R"(VERSION ""
BU_: ENG
BO_ 2566841342 CVW: 20 ENG
 SG_ Weight : 0|16@1+ (1,0) [0|65535] "kg" Vector__XXX
)");
  REQUIRE_FALSE(parsed.hasErrors());
  AnalysisSetup setup;
  setup.database = std::move(parsed.database);
  std::int32_t matched = -2;
  TransportAnalysis sut(setup, [&](const ReassembledMessage& message) { matched = message.message; });
  Collector out;
  sut.add(frameOf(VEHICLE_BUS, T0, 0x1CECFF00, {0x20, 20, 0x00, 3, 0xFF, 0xE3, 0xFE, 0x00}), out);
  for (std::uint8_t sequence = 1; sequence <= 3; ++sequence) {
    sut.add(frameOf(VEHICLE_BUS, T0 + sequence * 10 * MS, 0x1CEBFF00, {sequence, 1, 2, 3, 4, 5, 6, 7}), out);
  }
  CHECK(matched == 0);
  REQUIRE(out.findings.size() == 1);
  CHECK(out.findings[0].text == "BAM 0x00 -> all PGN 65251 (0xFEE3) CVW 20 bytes in 3 packets, 30.0 ms");
}
