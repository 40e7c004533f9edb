// TraceChecker (issue 21): J1939-76 pairs built with j1939::SafetyPairBuilder, fed as
// TraceFrames, each fault with its exact finding; requests answered, NACKed, unanswered.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "openvcu/dbc/parser.hpp"
#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/trace/check.hpp"

using namespace openvcu;
using namespace openvcu::trace;

namespace {

constexpr std::uint32_t S1_ES_ID = 0x0CEFF321;     // SDM, PDU1 to the VIC 0xF3 from the VCU 0x21
constexpr std::uint32_t PROPA_C4_ID = 0x18EFF321;  // same PGN, SA and DA at priority 6
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t US = 1'000;
constexpr std::int64_t START_NS = 1'700'000'000'000'000'000;
constexpr std::int64_t CYCLE_NS = 20 * MS;
constexpr std::int64_t DELTA_NS = 292 * US;
constexpr std::int64_t SRVT_NS = 10 * MS;
constexpr std::int64_t SCT_NS = 60 * MS;
const j1939::SafetyPayload THESIS_SDM{0xEF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};  // CRC 0x8100EFA3

constexpr const char* S1_ES_DBC = R"(VERSION ""
NS_ :
BS_:
BU_: VCU VIC
BO_ 2364535585 S1_ES: 8 VCU
 SG_ Relay : 0|8@1+ (1,0) [0|255] "" VIC
BA_DEF_ BO_ "GenMsgCycleTime" INT 0 65535;
BA_ "GenMsgCycleTime" BO_ 2364535585 20;
)";

/// S1_ES as a configured pair (message 0), or none (pairs found on the bus).
AnalysisSetup makeSetup(bool configured) {
  AnalysisSetup setup;
  dbc::ParseOutput parsed = dbc::parse(S1_ES_DBC, "s1.dbc");
  REQUIRE_FALSE(parsed.hasErrors());
  setup.database = std::move(parsed.database);
  setup.expectedCycleNs.assign(setup.database.messages.size(), CYCLE_NS);
  setup.cycleSource.assign(setup.database.messages.size(), CycleSource::Attribute);
  if (configured) setup.safetyPairs.push_back(SafetyPairSetup{0, S1_ES_ID, DELTA_NS, SRVT_NS, SCT_NS, {}});
  return setup;
}

TraceFrame frameAt(std::int64_t timeNs, std::uint32_t id, std::span<const std::uint8_t> data) {
  TraceFrame frame;
  frame.timeNs = timeNs;
  frame.frame.timestampNs = timeNs;
  frame.frame.id = id;
  frame.frame.flags = can::FLAG_EXTENDED;
  frame.frame.length = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), frame.frame.data.begin());
  return frame;
}

struct Collector final : FindingSink {
  std::vector<Finding> findings;
  void finding(const Finding& finding) override { findings.push_back(finding); }
  [[nodiscard]] std::vector<Finding> of(trace::Severity severity) const {
    std::vector<Finding> selected;
    for (const Finding& one : findings) {
      if (one.severity == severity) selected.push_back(one);
    }
    return selected;
  }
};

/// Sends pairs as can-tx does: SHM at the cycle start, the SDM `deltaNs` later.
struct PairSender {
  TraceChecker& sut;
  Collector& sink;
  j1939::SafetyPairBuilder builder{S1_ES_ID};
  std::int64_t timeNs{START_NS};

  void send(j1939::SafetyPayload data = THESIS_SDM, std::int64_t deltaNs = DELTA_NS,
            j1939::SafetyPayload* header = nullptr) {
    j1939::SafetyPayload shm = builder.nextHeader(data);
    if (header != nullptr) shm = *header;
    sut.add(frameAt(timeNs, builder.headerCanId(), shm), sink);
    sut.add(frameAt(timeNs + deltaNs, S1_ES_ID, data), sink);
    timeNs += CYCLE_NS;
  }
};

}  // namespace

TEST_CASE("good J1939-76 pairs give no finding and their delta statistics") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  for (int i = 0; i < 40; ++i) sender.send();  // 40 pairs: the sequence wraps 31 -> 0
  sut.finish(sender.timeNs, sink);

  CHECK(sink.findings.empty());
  CHECK(sut.counts().safetyPairs == 40);
  CHECK(sut.counts().safetyFaults == 0);
  CHECK(sut.counts().faults == 0);
  const std::vector<SafetyPairStats> pairs = sut.safetyPairs();
  REQUIRE(pairs.size() == 1);
  CHECK(pairs[0].ok == 39);  // the first pair synchronises
  CHECK(pairs[0].deltaCount == 40);
  CHECK(pairs[0].deltaMinNs == DELTA_NS);
  CHECK(pairs[0].deltaMaxNs == DELTA_NS);
  CHECK(pairs[0].deltaMeanNs() == doctest::Approx(static_cast<double>(DELTA_NS)));
  CHECK_FALSE(pairs[0].discovered);
}

TEST_CASE("an SDM whose data does not match the SHM's CRC is a CrcMismatch fault with both CRCs") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();
  sender.send();
  j1939::SafetyPayload shm = sender.builder.nextHeader(THESIS_SDM);  // CRC of EF FF .. FF
  j1939::SafetyPayload corrupted = THESIS_SDM;
  corrupted[7] = 0xFE;
  const std::int64_t sdmNs = sender.timeNs + DELTA_NS;
  sut.add(frameAt(sender.timeNs, sender.builder.headerCanId(), shm), sink);
  sut.add(frameAt(sdmNs, S1_ES_ID, corrupted), sink);

  REQUIRE(sink.findings.size() == 1);
  const Finding& finding = sink.findings[0];
  char expected[128];
  std::snprintf(expected, sizeof expected, "S1_ES (0x0CEFF321): CrcMismatch: SHM CRC 0x8100EFA3, SDM data CRC 0x%08X",
                j1939::crc32J1939_76(corrupted));
  CHECK(finding.text == expected);
  CHECK(finding.timeNs == sdmNs);
  CHECK(finding.severity == trace::Severity::Fault);
  CHECK(finding.check == Check::Safety);
  CHECK(sut.counts().safetyFaults == 1);
  CHECK(sut.counts().faults == 1);
}

TEST_CASE("an SHM with a wrong inverted source address is a HeaderMismatch naming the fields") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();
  j1939::SafetyPayload shm = j1939::buildSafetyHeader(S1_ES_ID, THESIS_SDM, sender.builder.sequence());
  shm[1] ^= 0x01;  // ~SA 0xDE -> 0xDF: SA 0x20
  sender.send(THESIS_SDM, DELTA_NS, &shm);

  REQUIRE(sink.findings.size() == 1);
  CHECK(sink.findings[0].text ==
        "S1_ES (0x0CEFF321): HeaderMismatch: SHM names EDP 0 DP 0 PF 0xEF PS 0xF3 SA 0x20, the SDM is 0x0CEFF321");
}

TEST_CASE("a lost pair is a SequenceError with the sequence expected") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();                                // 0: synchronises
  sender.send();                                // 1: ok
  (void)sender.builder.nextHeader(THESIS_SDM);  // 2 never sent
  sender.send();                                // 3

  REQUIRE(sink.findings.size() == 1);
  CHECK(sink.findings[0].text == "S1_ES (0x0CEFF321): SequenceError: sequence 3, expected 2 after 1");
}

TEST_CASE("an SDM later than the SRVT after its SHM is a Timeout with the delay") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();
  sender.send(THESIS_SDM, 12 * MS);

  REQUIRE(sink.findings.size() == 1);  // the delta is not warned about as well
  CHECK(sink.findings[0].text == "S1_ES (0x0CEFF321): Timeout: SDM 12000 us after its SHM (SRVT 10000 us)");
}

TEST_CASE("an SHM later than the SCT is found while it is missing and at its SDM") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();
  sender.send();
  sender.send();                  // last SHM at +40 ms
  sender.timeNs += 4 * CYCLE_NS;  // the next one at +140 ms: 100 ms after it
  const std::int64_t lateNs = sender.timeNs;
  sender.send();
  sender.send();  // synchronises again: no finding

  REQUIRE(sink.findings.size() == 2);
  CHECK(sink.findings[0].text ==
        "S1_ES (0x0CEFF321): no SHM for 100000 us (SCT 60000 us): the sender stopped or its SHMs are lost");
  CHECK(sink.findings[0].timeNs == lateNs);
  CHECK(sink.findings[1].text ==
        "S1_ES (0x0CEFF321): CycleTimeout: SHM 100000 us after the previous SHM (SCT 60000 us)");
  CHECK(sink.findings[1].timeNs == lateNs + DELTA_NS);
}

TEST_CASE("an SHM -> SDM delta beyond the tolerance is a warning, not a fault") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();
  sender.send(THESIS_SDM, 492 * US);  // 200 us over: within the tolerance of max(200 us, 50 %)
  sender.send(THESIS_SDM, 900 * US);
  sut.finish(sender.timeNs, sink);

  REQUIRE(sink.findings.size() == 1);
  CHECK(sink.findings[0].severity == trace::Severity::Warning);
  CHECK(sink.findings[0].text == "S1_ES (0x0CEFF321): SHM -> SDM delta 900 us, configured 292 us (tolerance 200 us)");
  CHECK(sut.counts().faults == 0);
  CHECK(sut.counts().warnings == 1);
  const std::vector<SafetyPairStats> pairs = sut.safetyPairs();
  REQUIRE(pairs.size() == 1);
  CHECK(pairs[0].deltaMinNs == DELTA_NS);
  CHECK(pairs[0].deltaMaxNs == 900 * US);
  CHECK(pairs[0].deltaMeanNs() == doctest::Approx((292.0 + 492.0 + 900.0) / 3.0 * US));
}

TEST_CASE("a frame of the SDM's identity between SHM and SDM is taken for the SDM") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();
  const j1939::SafetyPayload propA{0, 0, 0, 0, 0, 0, 0, 0};
  const j1939::SafetyPayload shm = sender.builder.nextHeader(THESIS_SDM);
  sut.add(frameAt(sender.timeNs, sender.builder.headerCanId(), shm), sink);
  sut.add(frameAt(sender.timeNs + 100 * US, PROPA_C4_ID, propA), sink);
  sut.add(frameAt(sender.timeNs + DELTA_NS, S1_ES_ID, THESIS_SDM), sink);  // judged already: no MissingHeader

  REQUIRE(sink.findings.size() == 1);
  char expected[160];
  std::snprintf(expected, sizeof expected,
                "S1_ES (0x0CEFF321): CrcMismatch: SHM CRC 0x8100EFA3, SDM data CRC 0x%08X (taken for the SDM: "
                "0x18EFF321)",
                j1939::crc32J1939_76(propA));
  CHECK(sink.findings[0].text == expected);
}

TEST_CASE("a configured pair absent from the log is an info, an SDM without SHM a MissingHeader") {
  const AnalysisSetup setup = makeSetup(true);
  SUBCASE("absent") {
    TraceChecker sut(setup);
    Collector sink;
    sut.finish(START_NS, sink);
    REQUIRE(sink.findings.size() == 1);
    CHECK(sink.findings[0].severity == trace::Severity::Info);
    CHECK(sink.findings[0].text == "S1_ES (0x0CEFF321): configured J1939-76 pair not in this log");
  }
  SUBCASE("missing header") {
    TraceChecker sut(setup);
    Collector sink;
    sut.add(frameAt(START_NS, S1_ES_ID, THESIS_SDM), sink);
    REQUIRE(sink.findings.size() == 1);
    CHECK(sink.findings[0].text == "S1_ES (0x0CEFF321): MissingHeader: SDM without an SHM before it");
  }
}

TEST_CASE("without configured pairs the SHM names its SDM and the DBC cycle sets the SCT") {
  const AnalysisSetup setup = makeSetup(false);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  sender.send();
  sender.send();
  j1939::SafetyPayload corrupted = THESIS_SDM;
  corrupted[0] = 0x00;
  j1939::SafetyPayload shm = j1939::buildSafetyHeader(S1_ES_ID, THESIS_SDM, sender.builder.sequence());
  sender.send(corrupted, DELTA_NS, &shm);

  REQUIRE(sink.findings.size() == 1);
  CHECK(sink.findings[0].text.starts_with("S1_ES (0x0CEFF321): CrcMismatch: SHM CRC 0x8100EFA3"));
  const std::vector<SafetyPairStats> pairs = sut.safetyPairs();
  REQUIRE(pairs.size() == 1);
  CHECK(pairs[0].discovered);
  CHECK(pairs[0].message == 0);
  CHECK(pairs[0].maxHeaderToDataNs == DEFAULT_SRVT_NS);
  CHECK(pairs[0].maxHeaderCycleNs == DEFAULT_SCT_CYCLES * CYCLE_NS);
  CHECK(pairs[0].deltaNs == 0);  // nothing configured: no delta warning
}

TEST_CASE("requests: an answer or a NACK closes them, none within 1.25 s is a fault") {
  const AnalysisSetup setup = makeSetup(false);
  TraceChecker sut(setup);
  Collector sink;
  constexpr std::uint8_t VCU = 0x21;
  constexpr std::uint8_t VIC = 0xF3;
  constexpr std::uint32_t HVESSHIST = 64606;  // 0xFC5E, PDU2
  constexpr std::uint32_t TIME_DATE = 65254;  // 0xFEE6
  constexpr std::uint32_t SOFT = 65242;       // 0xFEDA

  const j1939::RequestFrame answered = j1939::buildRequest(HVESSHIST, 6, VCU, VIC);
  sut.add(frameAt(START_NS, answered.canId, answered.payload), sink);
  const std::array<std::uint8_t, 8> history{1, 2, 3, 4, 5, 6, 7, 8};
  sut.add(frameAt(START_NS + 5 * MS, j1939::Id::fromPgn(HVESSHIST, 6, VIC).toCanId(), history), sink);

  const j1939::RequestFrame nacked = j1939::buildRequest(SOFT, 6, VCU, VIC);
  sut.add(frameAt(START_NS + 10 * MS, nacked.canId, nacked.payload), sink);
  const j1939::AcknowledgementPayload nack =
      j1939::encodeAcknowledgement(j1939::Acknowledgement{j1939::AckControl::Negative, 0xFF, VCU, SOFT});
  sut.add(frameAt(START_NS + 12 * MS, j1939::acknowledgementCanId(6, VIC, VCU), nack), sink);

  const j1939::RequestFrame unanswered = j1939::buildRequest(TIME_DATE, 6, VCU, VIC);
  sut.add(frameAt(START_NS + 20 * MS, unanswered.canId, unanswered.payload), sink);
  sut.add(frameAt(START_NS + 2000 * MS, 0x18FEF121, history), sink);  // time passes
  sut.finish(START_NS + 2000 * MS, sink);

  REQUIRE(sink.findings.size() == 2);
  CHECK(sink.findings[0].severity == trace::Severity::Info);
  CHECK(sink.findings[0].text == "request from 0x21 to 0xF3 for PGN 65242 (0xFEDA): answered NACK");
  CHECK(sink.findings[1].severity == trace::Severity::Fault);
  CHECK(sink.findings[1].check == Check::Request);
  CHECK(sink.findings[1].text == "request from 0x21 to 0xF3 for PGN 65254 (0xFEE6): no answer within 1250 ms");
  // at the request's own frame (found in the log by its time), not at the deadline
  CHECK(sink.findings[1].timeNs == START_NS + 20 * MS);
  CHECK(sut.counts().requests == 3);
  CHECK(sut.counts().unanswered == 1);
  CHECK(sut.counts().faults == 1);
  CHECK(sut.counts().infos == 1);
}

TEST_CASE("pairs found on the bus are capped and the SHMs beyond the cap are counted") {
  const AnalysisSetup setup = makeSetup(false);
  TraceChecker sut(setup);
  Collector sink;
  std::int64_t timeNs = START_NS;
  for (std::size_t i = 0; i <= MAX_DISCOVERED_SAFETY_PAIRS; ++i) {  // one pair more than the cap
    const auto destination = static_cast<std::uint8_t>(i % 256);
    const auto source = static_cast<std::uint8_t>(0x21 + i / 256);
    const std::uint32_t sdm = j1939::Id::fromPgn(0xEF00, 3, source, destination).toCanId();
    sut.add(frameAt(timeNs, j1939::safetyHeaderCanId(sdm), j1939::buildSafetyHeader(sdm, THESIS_SDM, 0)), sink);
    sut.add(frameAt(timeNs + DELTA_NS, sdm, THESIS_SDM), sink);
    timeNs += MS;
  }
  sut.finish(timeNs, sink);

  CHECK(sut.safetyPairs().size() == MAX_DISCOVERED_SAFETY_PAIRS);
  CHECK(sut.counts().safetyPairsSkipped == 1);
  CHECK(sut.counts().safetyPairs == MAX_DISCOVERED_SAFETY_PAIRS);  // the last SDM has no pair
  REQUIRE(sink.findings.size() == 2);
  CHECK(sink.findings[0].text ==
        "more than 256 J1939-76 pairs: SHMs of further SDMs are not checked (counted at the end)");
  CHECK(sink.findings[1].text == "1 SHMs of pairs beyond the first 256 not checked");
  CHECK(sut.counts().faults == 0);
}

TEST_CASE("requests beyond the open-request table are counted, not checked") {
  const AnalysisSetup setup = makeSetup(false);
  TraceChecker sut(setup);
  Collector sink;
  const j1939::RequestFrame request = j1939::buildRequest(65254, 6, 0x21, 0xF3);
  for (std::size_t i = 0; i <= MAX_OPEN_REQUESTS; ++i) {
    sut.add(frameAt(START_NS + static_cast<std::int64_t>(i) * 100 * US, request.canId, request.payload), sink);
  }
  const std::array<std::uint8_t, 8> timeDate{};
  sut.add(frameAt(START_NS + 200 * MS, j1939::Id::fromPgn(65254, 6, 0xF3).toCanId(), timeDate), sink);  // answers all
  sut.finish(START_NS + 3000 * MS, sink);

  CHECK(sut.counts().requests == MAX_OPEN_REQUESTS + 1);
  CHECK(sut.counts().requestsSkipped == 1);
  CHECK(sut.counts().unanswered == 0);
  REQUIRE(sink.findings.size() == 2);
  CHECK(sink.findings[0].text ==
        "more than 1024 requests waiting for an answer: further ones are not checked (counted at the end)");
  CHECK(sink.findings[1].text == "1 requests not checked (table full)");
}

TEST_CASE("a pair of a send group that falls silent is a warning naming the group, not a fault") {
  AnalysisSetup setup = makeSetup(true);
  setup.safetyPairs[0].switchedBy = "keepAlive";
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  for (int i = 0; i < 5; ++i) sender.send();  // the last SHM at +80 ms
  const std::array<std::uint8_t, 8> other{};
  for (std::int64_t t = 90 * MS; t <= 300 * MS; t += 10 * MS) sut.add(frameAt(START_NS + t, 0x18FEF100, other), sink);
  sut.finish(START_NS + 300 * MS, sink);

  REQUIRE(sink.findings.size() == 1);
  CHECK(sink.findings[0].severity == trace::Severity::Warning);
  CHECK(sink.findings[0].text ==
        "S1_ES (0x0CEFF321): no SHM for 70000 us (SCT 60000 us): stopped; it is in send group keepAlive, which "
        "switches it off");
  CHECK(sut.counts().faults == 0);
}

TEST_CASE("a sender that stops mid-log is found by polling within 10 ms of log time, once") {
  const AnalysisSetup setup = makeSetup(true);
  TraceChecker sut(setup);
  Collector sink;
  PairSender sender{sut, sink};
  for (int i = 0; i < 5; ++i) sender.send();  // the last SHM at +80 ms
  const std::array<std::uint8_t, 8> other{};
  for (std::int64_t t = 90 * MS; t <= 300 * MS; t += 10 * MS) sut.add(frameAt(START_NS + t, 0x18FEF100, other), sink);
  sut.finish(START_NS + 300 * MS, sink);

  // polls at +90, +100, ... ms: the first beyond the SCT of 60 ms is +150 ms
  REQUIRE(sink.findings.size() == 1);
  CHECK(sink.findings[0].timeNs == START_NS + 150 * MS);
  CHECK(sink.findings[0].text ==
        "S1_ES (0x0CEFF321): no SHM for 70000 us (SCT 60000 us): the sender stopped or its SHMs are lost");
  CHECK(sut.counts().faults == 1);
  CHECK(sut.counts().safetyFaults == 0);  // no SDM was judged faulty
}
