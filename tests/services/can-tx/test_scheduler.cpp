// cantx::Scheduler with a fake clock on the HHEA configuration: the J1939-76 worked
// example byte for byte, SHM-before-SDM with the configured delta, absolute deadlines
// without catch-up, send groups, computed fields, value precedence, requests, runtime
// changes and the bus plane.

#include <doctest/doctest.h>

#include "vehicle_fixture.hpp"
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <string>
#include <vector>

#include "openvcu/config/catalog.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/j1939/time_date.hpp"
#include "scheduler.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t US = 1'000;
constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START = 5'000 * MS;
const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";

constexpr std::uint32_t S1_ES = 0x0CEFF321;
constexpr std::uint32_t S1_ES_SHM = 0x0C0EF321;
constexpr std::uint32_t CMD_SYS_1 = 0x0CFF1127;  // 10 ms, no group

struct Sent {
  std::size_t bus;
  can::Frame frame;
  std::int64_t atNs;
};

struct FakeClock final : cantx::Clock {
  std::int64_t now{START};
  std::int64_t realtime{1'795'268'730'750'000'000};  // time_date.hpp's example instant
  std::int64_t monotonicNs() noexcept override { return now; }
  std::int64_t realtimeNs() noexcept override { return realtime; }
};

struct Recorder final : cantx::TxPort {
  FakeClock* clock{};
  std::int64_t sendTakesNs{};  ///< the fake clock advances this much per frame sent
  std::vector<Sent> sent;
  can::SendStatus send(std::size_t bus, const can::Frame& frame) noexcept override {
    sent.push_back(Sent{bus, frame, clock->now});
    clock->now += sendTakesNs;
    return can::SendStatus::Sent;
  }
  [[nodiscard]] std::vector<Sent> withId(std::uint32_t id) const {
    std::vector<Sent> matching;
    for (const Sent& item : sent) {
      if (item.frame.id == id) matching.push_back(item);
    }
    return matching;
  }
};

std::vector<std::uint8_t> bytes(const can::Frame& frame) { return {frame.data.begin(), frame.data.begin() + frame.length}; }

struct Fixture : openvcu::testing::VehicleTable {
  cantx::Schedule schedule;
  FakeClock clock;
  Recorder port;
  std::unique_ptr<cantx::Scheduler> sut;

  Fixture() : VehicleTable(HHEA, "txunit-" + std::to_string(::getpid())) {
    auto scheduleResult = cantx::loadSchedule(vehicle, catalog);
    REQUIRE_MESSAGE(scheduleResult, (scheduleResult ? "" : scheduleResult.error().toString()));
    schedule = std::move(*scheduleResult);
    port.clock = &clock;
  }

  void start() {
    auto created = cantx::Scheduler::create(vehicle, schedule, catalog, *table, port, clock, START);
    REQUIRE_MESSAGE(created, (created ? "" : created.error().toString()));
    sut = std::move(*created);
  }
  signals::SignalIndex key(const std::string& name) {
    const auto index = catalog.indexOf(name);
    REQUIRE_MESSAGE(index, name);
    return *index;
  }
  void command(const std::string& name, double value) { table->writeCommand(key(name), value, clock.now, 3); }
  /// Runs the scheduler at each of its deadlines up to `untilNs` (a perfect clock).
  void runUntil(std::int64_t untilNs) {
    for (;;) {
      const std::int64_t next = std::max(sut->nextDeadlineNs(), clock.now);
      if (next > untilNs) break;
      clock.now = next;
      sut->run(clock.now);
    }
    clock.now = untilNs;
  }
  std::size_t scheduledIndex(const std::string& message) {
    auto found = cantx::findScheduled(schedule, vehicle, message);
    REQUIRE(found);
    return *found;
  }
};

}  // namespace

TEST_CASE("the S1_ES pair reproduces the thesis' worked example byte for byte (sequence 15)") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.command("Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay", 3);
  f.start();
  f.runUntil(START + 15 * 20 * MS + 1 * MS);  // pairs 0..15
  const auto headers = f.port.withId(S1_ES_SHM);
  const auto data = f.port.withId(S1_ES);
  REQUIRE(headers.size() == 16);
  REQUIRE(data.size() == 16);
  CHECK(bytes(data[15].frame) == std::vector<std::uint8_t>{0xEF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF});
  CHECK(bytes(headers[15].frame) == std::vector<std::uint8_t>{0x7F, 0xDE, 0x0C, 0x10, 0xA3, 0xEF, 0x00, 0x81});
  // the first pair carries sequence 0: byte 0 = 0 << 3 | 0b111, same CRC
  CHECK(bytes(headers[0].frame) == std::vector<std::uint8_t>{0x07, 0xDE, 0x0C, 0x10, 0xA3, 0xEF, 0x00, 0x81});
  CHECK(headers[0].frame.extended());
}

TEST_CASE("each SHM goes out first and its SDM exactly the configured delta later, on absolute deadlines") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.start();
  f.runUntil(START + 999 * MS);
  const auto headers = f.port.withId(S1_ES_SHM);
  const auto data = f.port.withId(S1_ES);
  REQUIRE(headers.size() == 50);
  REQUIRE(data.size() == 50);
  for (std::size_t i = 0; i < headers.size(); ++i) {
    CHECK(headers[i].atNs == START + static_cast<std::int64_t>(i) * 20 * MS);  // no drift
    CHECK(data[i].atNs - headers[i].atNs == 292 * US);                       // schedule.json deltaUs
  }
  // the SHM precedes its SDM in the sent order
  const auto firstHeader = std::find_if(f.port.sent.begin(), f.port.sent.end(),
                                        [](const Sent& s) { return s.frame.id == S1_ES_SHM; });
  const auto firstData = std::find_if(f.port.sent.begin(), f.port.sent.end(),
                                      [](const Sent& s) { return s.frame.id == S1_ES; });
  CHECK(firstHeader < firstData);
  const auto& stats = f.sut->stats(f.scheduledIndex("S1_ES_PGN61427"));
  CHECK(stats.frames.load() == 50);
  CHECK(stats.periodError.summary().maxUs == 0);
  CHECK(stats.deltaError.summary().maxUs == 0);
  CHECK(stats.missed.load() == 0);
}

TEST_CASE("issue 27: an SDM falling due during a burst of frames leaves between two of them, not after the burst") {
  Fixture f;
  constexpr std::int64_t FRAME_TAKES = 50 * US;  // 30-odd frames due at once: a burst of over 1.5 ms
  f.command("internal.tx.keepAlive", 1);
  f.port.sendTakesNs = FRAME_TAKES;
  f.start();
  f.sut->run(START);  // one call: the whole burst due at START
  const auto headers = f.port.withId(S1_ES_SHM);
  const auto data = f.port.withId(S1_ES);
  REQUIRE(headers.size() == 1);
  REQUIRE(data.size() == 1);
  const std::int64_t late = data[0].atNs - headers[0].atNs - 292 * US;
  CHECK(late >= 0);
  CHECK(late <= 2 * FRAME_TAKES);  // the SHM's own send time and one frame at most
  CHECK(f.port.sent.back().atNs > data[0].atNs);  // the burst went on after the SDM
}

TEST_CASE("the sequence number advances per pair and wraps at 32") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.start();
  f.runUntil(START + 34 * 20 * MS);
  const auto headers = f.port.withId(S1_ES_SHM);
  REQUIRE(headers.size() >= 34);
  for (std::size_t i = 0; i < 34; ++i) {
    const auto header = j1939::parseSafetyHeader(headers[i].frame.payload());
    REQUIRE(header);
    CHECK(header->sequence == i % 32);
  }
}

TEST_CASE("after a stall the past cycles are skipped and counted, never sent in a burst") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.start();
  f.runUntil(START);  // first cycle at START
  f.port.sent.clear();
  f.clock.now = START + 125 * MS;  // stalled through the deadlines at 20, 40, 60, 80, 100, 120 ms
  f.sut->run(f.clock.now);
  CHECK(f.port.withId(S1_ES_SHM).size() == 1);
  const auto& stats = f.sut->stats(f.scheduledIndex("S1_ES_PGN61427"));
  CHECK(stats.missed.load() == 5);  // 20..100 skipped; the one at 120 goes out late, once
  CHECK(f.sut->nextDeadlineNs() <= START + 125 * MS + 292 * US);  // the SDM
  f.runUntil(START + 150 * MS);
  const auto headers = f.port.withId(S1_ES_SHM);
  REQUIRE(headers.size() == 2);
  CHECK(headers[1].atNs == START + 140 * MS);  // back on the original grid
}

TEST_CASE("a send group switched off keeps the messages silent, ungrouped messages go on") {
  Fixture f;
  f.start();  // internal.tx.keepAlive never commanded: its initial value 0
  f.runUntil(START + 100 * MS);
  CHECK(f.port.withId(S1_ES).empty());
  CHECK(f.port.withId(S1_ES_SHM).empty());
  CHECK(f.port.withId(CMD_SYS_1).size() == 11);
  f.command("internal.tx.keepAlive", 1);
  f.runUntil(START + 200 * MS);
  CHECK(f.port.withId(S1_ES_SHM).size() == 5);  // 120, 140, 160, 180, 200 (phase kept)
  CHECK(f.port.withId(S1_ES).size() == 4);      // the fifth SDM is due 292 us after 200 ms
  CHECK(f.port.withId(S1_ES_SHM).front().atNs == START + 120 * MS);
  CHECK(f.sut->stats(f.scheduledIndex("S1_ES_PGN61427")).missed.load() == 0);
}

TEST_CASE("override wins over command, command over the schedule default, default over the DBC start value") {
  Fixture f;
  const std::size_t hc1 = f.scheduledIndex("HC1_Demands");
  const std::uint32_t controlWord = 1;  // HC1_Demands signal order: Torque_Request, ControlWord, ...
  REQUIRE(f.vehicle.database.messages[f.schedule.messages[hc1].message].signals[controlWord].name == "ControlWord");
  const std::uint32_t hc1Id = f.schedule.messages[hc1].canId;
  f.start();
  auto controlWordSent = [&] {
    const auto frames = f.port.withId(hc1Id);
    REQUIRE(!frames.empty());
    return frames.back().frame.data[2] | (frames.back().frame.data[3] << 8);
  };
  f.runUntil(START);
  CHECK(controlWordSent() == 6);  // DBC GenSigStartValue
  f.sut->setDefault(hc1, controlWord, 3);
  f.runUntil(START + 20 * MS);
  CHECK(controlWordSent() == 3);
  f.command("Vehicle_Control_Unit.HC1_Demands.ControlWord", 5);
  f.runUntil(START + 40 * MS);
  CHECK(controlWordSent() == 5);
  f.table->setOverride(f.key("Vehicle_Control_Unit.HC1_Demands.ControlWord"), 6, f.clock.now, 9);
  f.runUntil(START + 60 * MS);
  CHECK(controlWordSent() == 6);
  // what went out is on the bus plane, with the frame's source address
  const auto bus = f.table->readBus(f.key("Vehicle_Control_Unit.HC1_Demands.ControlWord"));
  REQUIRE(bus);
  CHECK(bus->value == 6);
  CHECK(bus->source == 0x71);  // the low byte of HC1_Demands 0x19107171 (H-protocol node ID)
  CHECK(bus->quality == signals::Quality::Valid);
}

TEST_CASE("computed fields: the HVLP SEQ counts per frame and CS is the sum of the other bytes") {
  Fixture f;
  const std::size_t hc1 = f.scheduledIndex("HC1_Demands");
  const std::uint32_t hc1Id = f.schedule.messages[hc1].canId;
  f.start();
  f.runUntil(START + 260 * MS * 5);  // 66 frames at 20 ms: the 8-bit counter goes past 63
  const auto frames = f.port.withId(hc1Id);
  REQUIRE(frames.size() > 64);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto& data = frames[i].frame.data;
    CHECK(data[7] == i % 256);  // SEQ_Command1: byte 7
    std::uint8_t sum = 0;
    for (std::size_t b = 0; b < 8; ++b) {
      if (b != 6) sum = static_cast<std::uint8_t>(sum + data[b]);
    }
    CHECK(data[6] == sum);  // CS_Command1: byte 6, covers the counter
  }
}

TEST_CASE("requests: Time/Date from the clock, a scheduled PGN at once, a NACK for an unknown specific one") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.start();
  f.sut->answerRequest(0, j1939::Request{j1939::PGN_TIME_DATE, 0xF3, false});
  const auto timeDate = f.port.withId(0x18FEE621);
  REQUIRE(timeDate.size() == 1);
  CHECK(bytes(timeDate[0].frame) == std::vector<std::uint8_t>{0x7B, 0x2D, 0x0D, 0x0B, 0x54, 0x29, 0x7D, 0x7D});
  const auto seconds = f.table->readBus(f.key("Vehicle_Control_Unit.TD_PGN65254.TD_Seconds"));
  REQUIRE(seconds);
  CHECK(seconds->value == doctest::Approx(30.75));

  f.sut->answerRequest(0, j1939::Request{0xFEF1, 0xF3, true});  // CCVS1: a safety SDM, so its SHM first
  REQUIRE(f.port.sent.size() == 2);
  CHECK(f.port.sent[1].frame.id == 0x180EFF21);
  f.runUntil(START + 3 * MS);
  CHECK(f.port.withId(0x18FEF121).size() >= 1);

  f.port.sent.clear();
  f.sut->answerRequest(0, j1939::Request{0xFECA, 0xF3, true});  // unknown, global: silence
  CHECK(f.port.sent.empty());
  f.sut->answerRequest(0, j1939::Request{0xFECA, 0xF3, false});  // unknown, to us: NACK
  REQUIRE(f.port.sent.size() == 1);
  CHECK(f.port.sent[0].frame.id == 0x18E8FF21);
  CHECK(bytes(f.port.sent[0].frame) == std::vector<std::uint8_t>{0x01, 0xFF, 0xFF, 0xFF, 0xF3, 0xCA, 0xFE, 0x00});
  CHECK(f.sut->counters().requestsNacked.load() == 1);
}

TEST_CASE("runtime changes: a new cycle keeps the phase, a disabled message stops, a one-shot goes out once") {
  Fixture f;
  const std::size_t sys1 = f.scheduledIndex("CMD_SYS_1");
  f.start();
  f.runUntil(START + 50 * MS);
  f.port.sent.clear();
  f.sut->setCycle(sys1, 25 * MS, f.clock.now);  // last deadline 50 ms -> next 75 ms
  f.runUntil(START + 130 * MS);
  auto frames = f.port.withId(CMD_SYS_1);
  REQUIRE(frames.size() == 3);
  CHECK(frames[0].atNs == START + 75 * MS);
  CHECK(frames[2].atNs == START + 125 * MS);
  f.sut->setEnabled(sys1, false);
  f.port.sent.clear();
  f.runUntil(START + 300 * MS);
  CHECK(f.port.withId(CMD_SYS_1).empty());
  can::Frame oneShot;
  oneShot.id = 0x123;
  oneShot.length = 2;
  f.sut->sendOnce(0, oneShot);
  CHECK(f.port.withId(0x123).size() == 1);
  CHECK(f.sut->counters().oneShots.load() == 1);
}

TEST_CASE("a message added at run time goes out at once and then every cycle, with its start values and stats") {
  Fixture f;
  f.start();
  f.runUntil(START + 30 * MS);
  auto entry = cantx::runtimeMessage(f.schedule, f.vehicle, f.catalog, "HVESSD2_PGN61585", 40);
  REQUIRE(entry);
  entry->defaults[0] = 50.0;  // HS_FastUpdSOC 50 % -> raw 20000 = 0x4E20
  auto prepared = f.sut->prepare(*entry);
  REQUIRE(prepared);
  const cantx::MessageStats& stats = cantx::Scheduler::statsOf(**prepared);
  const std::size_t before = f.schedule.messages.size();  // the scheduler holds these
  REQUIRE(f.sut->capacity() > before);
  REQUIRE(f.sut->add(*prepared, f.clock.now));
  CHECK(!*prepared);  // taken
  CHECK(&f.sut->stats(before) == &stats);  // appended as the last one
  f.port.sent.clear();
  f.runUntil(START + 150 * MS);
  const auto frames = f.port.withId(0x18F091F3);
  REQUIRE(frames.size() == 4);  // 30, 70, 110, 150 ms
  CHECK(frames[0].atNs == START + 30 * MS);
  CHECK(frames[3].atNs == START + 150 * MS);
  CHECK(frames[0].frame.data[0] == 0x20);
  CHECK(frames[0].frame.data[1] == 0x4E);
  CHECK(stats.frames.load() == 4);
  // the room is every DBC message: exactly capacity - (before + 1) more fit (so the add above
  // made before + 1), adding beyond it is refused and leaves the entry to the caller
  for (std::size_t held = before + 1; held < f.sut->capacity(); ++held) {
    auto filler = f.sut->prepare(*entry);
    REQUIRE(filler);
    REQUIRE(f.sut->add(*filler, f.clock.now));
  }
  auto extra = f.sut->prepare(*entry);
  REQUIRE(extra);
  CHECK(!f.sut->add(*extra, f.clock.now));
  CHECK(*extra);
}

// ---- issue 18: J1939-76 pairs unambiguous on the wire --------------------------------------

namespace {

constexpr std::uint32_t PROPA_C4 = 0x18EFF321;  // not an SDM: S1_ES's PGN 0xEF00, SA 0x21, DA 0xF3 at priority 6

/// Frames a J1939-76 receiver would take for an SDM although they are not one: after each
/// SHM, the first frame with the PGN, SA and DA the SHM names (priority not compared) is
/// its SDM; counted when that frame is not one of the schedule's SDMs.
std::size_t ambiguousFrames(const std::vector<Sent>& sent, const cantx::Schedule& schedule) {
  std::vector<std::uint32_t> sdms;
  for (const cantx::ScheduledMessage& message : schedule.messages) {
    if (message.safetyDeltaNs) sdms.push_back(message.canId);
  }
  std::vector<std::uint32_t> waiting;  // identities (29-bit ID without the priority) of SHMs waiting
  std::size_t ambiguous = 0;
  for (const Sent& item : sent) {
    const std::uint32_t identity = item.frame.id & 0x03FFFFFFu;
    if (j1939::pgnOf(item.frame.id) == j1939::PGN_SAFETY_HEADER) {
      const auto header = j1939::parseSafetyHeader(item.frame.payload());
      REQUIRE(header);
      j1939::Id named;
      named.extendedDataPage = header->sdmExtendedDataPage;
      named.dataPage = header->sdmDataPage;
      named.pduFormat = header->sdmPduFormat;
      named.pduSpecific = header->sdmPduSpecific;
      named.sourceAddress = header->sdmSourceAddress;
      waiting.push_back(named.toCanId() & 0x03FFFFFFu);
      continue;
    }
    const auto found = std::find(waiting.begin(), waiting.end(), identity);
    if (found == waiting.end()) continue;
    waiting.erase(found);
    if (std::find(sdms.begin(), sdms.end(), item.frame.id) == sdms.end()) ++ambiguous;
  }
  return ambiguous;
}

can::Frame extendedFrame(std::uint32_t id, std::uint8_t firstByte) {
  can::Frame frame;
  frame.id = id;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = 8;
  frame.data.fill(0xFF);
  frame.data[0] = firstByte;
  return frame;
}

}  // namespace

TEST_CASE("issue 18: PropA_C4, due with the S1_ES SHM, goes out right after the S1_ES SDM, never between") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.start();
  f.runUntil(START + 999 * MS);
  CHECK(ambiguousFrames(f.port.sent, f.schedule) == 0);
  const auto propA = f.port.withId(PROPA_C4);
  const auto data = f.port.withId(S1_ES);
  REQUIRE(propA.size() == 50);  // every cycle, none dropped
  REQUIRE(data.size() == 50);
  for (std::size_t i = 0; i < propA.size(); ++i) {
    CHECK(propA[i].atNs == data[i].atNs);  // held for the 292 us of the pair, no longer
  }
  for (std::size_t i = 0; i + 1 < f.port.sent.size(); ++i) {
    if (f.port.sent[i].frame.id == S1_ES_SHM) CHECK(f.port.sent[i + 1].frame.id != PROPA_C4);
  }
  CHECK(f.sut->counters().held.load() == 50);
  CHECK(f.sut->counters().sdmsEarly.load() == 0);
  CHECK(f.sut->stats(f.scheduledIndex("S1_ES_PGN61427")).deltaError.summary().maxUs == 0);  // the SDM keeps its delta
}

TEST_CASE("issue 18: a one-shot with a pending SDM's PGN, SA and DA waits for the SDM, any other goes at once") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.start();
  f.sut->run(START);  // the S1_ES SHM is out, its SDM due 292 us later
  REQUIRE(f.port.withId(S1_ES_SHM).size() == 1);
  REQUIRE(f.port.withId(S1_ES).empty());
  f.port.sent.clear();
  constexpr std::uint32_t SAME_AT_PRIORITY_7 = 0x1CEFF321;
  constexpr std::uint32_t OTHER_DESTINATION = 0x18EFF421;
  f.sut->sendOnce(0, extendedFrame(SAME_AT_PRIORITY_7, 0x01));
  f.sut->sendOnce(0, extendedFrame(OTHER_DESTINATION, 0x02));
  f.sut->sendOnce(0, extendedFrame(SAME_AT_PRIORITY_7, 0x03));
  REQUIRE(f.port.sent.size() == 1);
  CHECK(f.port.sent[0].frame.id == OTHER_DESTINATION);
  CHECK(f.sut->counters().oneShots.load() == 1);  // counted when sent

  f.runUntil(START + 1 * MS);
  std::vector<Sent> sameIdentity;  // what a J1939-76 receiver of S1_ES looks at
  for (const Sent& item : f.port.sent) {
    if (j1939::sameSafetyIdentity(item.frame.id, S1_ES)) sameIdentity.push_back(item);
  }
  // the SDM at its delta, then the held frames in the order they came (PropA_C4 was held first)
  REQUIRE(sameIdentity.size() == 4);
  CHECK(sameIdentity[0].frame.id == S1_ES);
  CHECK(sameIdentity[0].atNs == START + 292 * US);
  CHECK(sameIdentity[1].frame.id == PROPA_C4);
  CHECK(sameIdentity[2].frame.id == SAME_AT_PRIORITY_7);
  CHECK(sameIdentity[2].frame.data[0] == 0x01);
  CHECK(sameIdentity[3].frame.id == SAME_AT_PRIORITY_7);
  CHECK(sameIdentity[3].frame.data[0] == 0x03);
  for (const Sent& item : sameIdentity) CHECK(item.atNs == START + 292 * US);
  CHECK(f.sut->counters().oneShots.load() == 3);
}

TEST_CASE("issue 18: with the hold full the SDM goes out early and the frame after it, nothing is lost") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.start();
  f.sut->run(START);
  constexpr std::size_t ONE_SHOTS = 100;  // more than the hold's room
  for (std::size_t i = 0; i < ONE_SHOTS; ++i) f.sut->sendOnce(0, extendedFrame(PROPA_C4, static_cast<std::uint8_t>(i)));
  CHECK(ambiguousFrames(f.port.sent, f.schedule) == 0);
  CHECK(f.sut->counters().sdmsEarly.load() == 1);
  CHECK(f.port.withId(S1_ES).size() == 1);  // before its delta, at the moment the hold was full
  f.runUntil(START + 1 * MS);
  CHECK(f.port.withId(PROPA_C4).size() == ONE_SHOTS + 1);  // the cyclic one too
  CHECK(f.sut->counters().oneShots.load() == ONE_SHOTS);
  CHECK(ambiguousFrames(f.port.sent, f.schedule) == 0);
}

TEST_CASE("issue 18: the checker of these tests counts PropA_C4 sent between the S1_ES SHM and SDM") {
  can::Frame header = extendedFrame(S1_ES_SHM, 0);
  const std::array<std::uint8_t, 8> sdmData{0xE3, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
  const auto bytesOfHeader = j1939::buildSafetyHeader(S1_ES, sdmData, 0);
  std::copy(bytesOfHeader.begin(), bytesOfHeader.end(), header.data.begin());
  cantx::Schedule declared;
  cantx::ScheduledMessage s1;
  s1.canId = S1_ES;
  s1.safetyDeltaNs = 292 * US;
  declared.messages.push_back(s1);
  const std::vector<Sent> oldOrder{{0, header, 0}, {0, extendedFrame(PROPA_C4, 0), 0}, {0, extendedFrame(S1_ES, 0xE3), 0}};
  const std::vector<Sent> newOrder{{0, header, 0}, {0, extendedFrame(S1_ES, 0xE3), 0}, {0, extendedFrame(PROPA_C4, 0), 0}};
  CHECK(ambiguousFrames(oldOrder, declared) == 1);
  CHECK(ambiguousFrames(newOrder, declared) == 0);
}

// Issue 18: the table truncated under can-tx (docs/design/signal-table.md, "Damage").
TEST_CASE("after the table lost its values commands and send groups keep their last command for the grace window") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.command("Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay", 3);
  f.start();
  f.runUntil(START + 100 * MS);
  const auto before = f.port.withId(S1_ES);
  REQUIRE_FALSE(before.empty());
  const std::vector<std::uint8_t> commanded = bytes(before.back().frame);

  REQUIRE(::truncate(signals::SignalTable::segmentPath(f.instance).c_str(), 0) == 0);
  const std::int64_t wipedNs = f.clock.now;
  f.port.sent.clear();
  f.runUntil(wipedNs + cantx::TABLE_DAMAGE_GRACE_NS - MS);
  const auto during = f.port.withId(S1_ES);
  REQUIRE(during.size() >= 70);  // every 20 ms: the keep-alive group stayed on
  for (const Sent& item : during) CHECK(bytes(item.frame) == commanded);
  const auto relay = f.table->readCommand(f.key("Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay"));
  REQUIRE(relay);
  CHECK(relay->updates == 0);  // the table really lost it: the frames carry the kept command

  // The window counts from the first read that met the damage (within one 20 ms cycle).
  f.runUntil(wipedNs + cantx::TABLE_DAMAGE_GRACE_NS + 20 * MS);
  f.port.sent.clear();
  f.runUntil(wipedNs + cantx::TABLE_DAMAGE_GRACE_NS + 200 * MS);
  CHECK(f.port.withId(S1_ES).empty());  // never commanded again: the group's initial value (off)
}

TEST_CASE("a command written again during the grace window is sent at once") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.command("Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay", 3);
  f.start();
  f.runUntil(START + 100 * MS);
  const std::vector<std::uint8_t> relayClosed = bytes(f.port.withId(S1_ES).back().frame);
  REQUIRE(::truncate(signals::SignalTable::segmentPath(f.instance).c_str(), 0) == 0);
  f.runUntil(f.clock.now + 100 * MS);

  f.command("internal.tx.keepAlive", 1);  // the FSM writes its commands back
  f.command("Vehicle_Control_Unit.S1_ES_PGN61427.Control_Es_Relay", 0);
  f.port.sent.clear();
  f.runUntil(f.clock.now + 100 * MS);
  const auto after = f.port.withId(S1_ES);
  REQUIRE_FALSE(after.empty());
  CHECK(bytes(after.back().frame) != relayClosed);
  f.runUntil(f.clock.now + cantx::TABLE_DAMAGE_GRACE_NS);
  CHECK_FALSE(f.port.withId(S1_ES).empty());  // commanded again: the group stays on after the window
}

TEST_CASE("issue 27: messages due together go out shortest cycle first, so a shared slot does not shift a period") {
  Fixture f;
  f.command("internal.tx.keepAlive", 1);
  f.port.sendTakesNs = 3 * US;  // about what a frame costs on the sim link
  f.start();
  f.runUntil(START + 1'000 * MS);
  // 10 ms, 20 ms and 100 ms messages: each listed in the schedule after longer-cycle ones,
  // whose slots they share every 100 ms (or 1 s)
  for (const char* name : {"CMD_SYS_1", "HC1_Demands_4", "CMD_MOT_9", "PDU_Rx_1"}) {
    CAPTURE(name);
    const std::size_t scheduled = f.scheduledIndex(name);
    const std::int64_t cycle = f.schedule.messages[scheduled].cycleNs;
    const auto frames = f.port.withId(f.schedule.messages[scheduled].canId);
    REQUIRE(frames.size() >= 2);
    for (std::size_t i = 1; i < frames.size(); ++i) CHECK(frames[i].atNs - frames[i - 1].atNs == cycle);
  }
  // and within the first burst (every message due at START) the cycles never get shorter
  std::int64_t previous = 0;
  for (const Sent& item : f.port.sent) {
    if (item.frame.id == S1_ES) break;  // the first SDM, 292 us after its SHM: the burst is over
    for (const cantx::ScheduledMessage& message : f.schedule.messages) {
      if (message.canId != item.frame.id || message.cycleNs <= 0) continue;
      CHECK(message.cycleNs >= previous);
      previous = message.cycleNs;
    }
  }
}
