// DiagnosticState (diagnostic_state.hpp) on a set clock: occurrence counts, DM1/DM2 content,
// lamps, DM3/DM11 clears, persistence and DM1 timing. Issue 24.
#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "openvcu/j1939/diagnostic_state.hpp"

using namespace openvcu::j1939;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t SECOND = 1000 * MS;
constexpr std::uint32_t SPN_BATTERY = 520192;
constexpr std::uint32_t SPN_CRASH = 520193;
constexpr std::uint32_t SPN_SOC_LOW = 520194;
constexpr std::uint8_t FMI_BAD_DEVICE = 12;
constexpr std::uint8_t FMI_CONDITION_EXISTS = 31;
constexpr std::uint8_t FMI_LOW_MODERATE = 18;
constexpr std::size_t BATTERY = 0;
constexpr std::size_t CRASH = 1;
constexpr std::size_t SOC_LOW = 2;

DiagnosticState makeState() {
  std::vector<DtcDefinition> definitions{
      {SPN_BATTERY, FMI_BAD_DEVICE, {.redStop = true}},
      {SPN_CRASH, FMI_CONDITION_EXISTS, {.redStop = true, .redStopFlash = LampFlash::Fast}},
      {SPN_SOC_LOW, FMI_LOW_MODERATE, {.amberWarning = true, .amberWarningFlash = LampFlash::Slow}},
  };
  auto created = DiagnosticState::create(std::move(definitions));
  REQUIRE(created);
  return std::move(*created);
}

/// Sets which of the three definitions are active.
bool set(DiagnosticState& sut, bool battery, bool crash, bool socLow, std::int64_t now = 0) {
  const std::array<bool, 3> active{battery, crash, socLow};
  return sut.update(active, now);
}

}  // namespace

TEST_CASE("nothing active: DM1 is empty with every lamp off") {
  const DiagnosticState sut = makeState();
  CHECK(sut.activeDtcs().empty());
  CHECK(sut.previouslyActiveDtcs().empty());
  CHECK(sut.lamps().redStop == LampStatus::Off);
  CHECK(sut.lamps().amberWarning == LampStatus::Off);
  CHECK(sut.lamps().protect == LampStatus::Off);
  CHECK(sut.lamps().malfunction == LampStatus::Off);
  std::array<std::uint8_t, 8> out{};
  REQUIRE(sut.encodeDm1(out) == 8);
  CHECK(out == std::array<std::uint8_t, 8>{0x00, 0xFF, 0x00, 0x00, 0x00, 0x00, 0xFF, 0xFF});
}

TEST_CASE("an activation is a change with count 1 and its lamps, the same input again is no change") {
  DiagnosticState sut = makeState();
  CHECK(set(sut, true, false, false, 5 * MS));
  REQUIRE(sut.activeDtcs().size() == 1);
  CHECK(sut.activeDtcs()[0] == Dtc{SPN_BATTERY, FMI_BAD_DEVICE, 1, false});
  CHECK(sut.lamps().redStop == LampStatus::On);
  CHECK(sut.lamps().redStopFlash == LampFlash::NotFlashing);
  CHECK(sut.lamps().amberWarning == LampStatus::Off);
  CHECK(sut.lastChangeNs() == 5 * MS);
  CHECK_FALSE(set(sut, true, false, false, 6 * MS));
  CHECK(sut.counts()[BATTERY] == 1);
}

TEST_CASE("lamps are the OR of the active definitions, fast flash over none") {
  DiagnosticState sut = makeState();
  set(sut, true, true, true);
  CHECK(sut.lamps().redStop == LampStatus::On);
  CHECK(sut.lamps().redStopFlash == LampFlash::Fast);
  CHECK(sut.lamps().amberWarning == LampStatus::On);
  CHECK(sut.lamps().amberWarningFlash == LampFlash::Slow);
  CHECK(sut.activeDtcs().size() == 3);
  std::array<std::uint8_t, 64> out{};
  CHECK(sut.encodeDm1(out) == 14);  // 2 + 3 x 4: sent by transport protocol
  set(sut, false, false, true);
  CHECK(sut.lamps().redStop == LampStatus::Off);
  CHECK(sut.lamps().redStopFlash == LampFlash::NotFlashing);
}

TEST_CASE("a definition that goes inactive moves to DM2, each new activation counts once") {
  DiagnosticState sut = makeState();
  for (int i = 0; i < 3; ++i) {
    CHECK(set(sut, true, false, false));
    CHECK(set(sut, false, false, false));
  }
  CHECK(sut.activeDtcs().empty());
  REQUIRE(sut.previouslyActiveDtcs().size() == 1);
  CHECK(sut.previouslyActiveDtcs()[0] == Dtc{SPN_BATTERY, FMI_BAD_DEVICE, 3, false});
  std::array<std::uint8_t, 8> out{};
  REQUIRE(sut.encodeDm2(out) == 8);
  CHECK(out == std::array<std::uint8_t, 8>{0x00, 0xFF, 0x00, 0xF0, 0xEC, 0x03, 0xFF, 0xFF});
}

TEST_CASE("the occurrence count stops at 126") {
  DiagnosticState sut = makeState();
  for (int i = 0; i < 200; ++i) {
    set(sut, false, true, false);
    set(sut, false, false, false);
  }
  CHECK(sut.counts()[CRASH] == DTC_MAX_COUNTED_OCCURRENCES);
}

TEST_CASE("DM3 clears the previously active DTCs only") {
  DiagnosticState sut = makeState();
  set(sut, true, true, false);
  set(sut, true, false, false);  // crash was active, battery still is
  CHECK(sut.clearPreviouslyActive());
  CHECK(sut.previouslyActiveDtcs().empty());
  CHECK(sut.counts()[CRASH] == 0);
  CHECK(sut.counts()[BATTERY] == 1);
  REQUIRE(sut.activeDtcs().size() == 1);
  CHECK_FALSE(sut.clearPreviouslyActive());  // nothing left to clear
}

TEST_CASE("DM11 resets every count and DM2, a condition still present stays active with count 1") {
  DiagnosticState sut = makeState();
  for (int i = 0; i < 4; ++i) {
    set(sut, true, true, false);
    set(sut, false, true, false);
  }
  CHECK(sut.counts()[BATTERY] == 4);
  CHECK(sut.counts()[CRASH] == 1);
  set(sut, false, false, false);
  set(sut, false, true, false);  // crash again: count 2, battery previously active
  REQUIRE(sut.counts()[CRASH] == 2);
  CHECK(sut.clearActive());
  CHECK(sut.previouslyActiveDtcs().empty());
  CHECK(sut.counts()[BATTERY] == 0);
  REQUIRE(sut.activeDtcs().size() == 1);
  CHECK(sut.activeDtcs()[0] == Dtc{SPN_CRASH, FMI_CONDITION_EXISTS, 1, false});
  CHECK(sut.lamps().redStop == LampStatus::On);
  CHECK_FALSE(sut.clearActive());  // already cleared
}

TEST_CASE("restored counts match by SPN and FMI, are capped at 126 and fill DM2") {
  DiagnosticState sut = makeState();
  const std::array saved{Dtc{SPN_SOC_LOW, FMI_LOW_MODERATE, 7, false}, Dtc{SPN_BATTERY, FMI_BAD_DEVICE, 127, false},
                         Dtc{SPN_BATTERY, 3, 9, false}};  // no definition has FMI 3
  CHECK(sut.restoreCounts(saved) == 2);
  CHECK(sut.counts()[SOC_LOW] == 7);
  CHECK(sut.counts()[BATTERY] == DTC_MAX_COUNTED_OCCURRENCES);
  CHECK(sut.counts()[CRASH] == 0);
  CHECK(sut.previouslyActiveDtcs().size() == 2);
  set(sut, false, false, true);
  CHECK(sut.activeDtcs()[0].occurrenceCount == 8);
}

TEST_CASE("create refuses out-of-range, duplicate and 'no DTC' definitions") {
  CHECK_FALSE(DiagnosticState::create({{DTC_MAX_SPN + 1, 1, {}}}));
  CHECK_FALSE(DiagnosticState::create({{100, 32, {}}}));
  CHECK_FALSE(DiagnosticState::create({{0, 0, {}}}));
  const auto duplicate = DiagnosticState::create({{100, 1, {}}, {100, 1, {.amberWarning = true}}});
  REQUIRE_FALSE(duplicate);
  CHECK(duplicate.error().message.find("already DTC definition 0") != std::string::npos);
  CHECK_FALSE(DiagnosticState::create({{100, 1, {}}}, 0));
  CHECK(DiagnosticState::create({{100, 1, {}}, {100, 2, {}}}));
}

TEST_CASE("DM1 is due at once, then once per period while nothing changes") {
  DiagnosticState sut = makeState();
  CHECK(sut.dm1Due(0));
  sut.dm1Sent(0);
  CHECK_FALSE(sut.dm1Due(999 * MS));
  CHECK(sut.nextDm1DueNs() == SECOND);
  CHECK(sut.dm1Due(SECOND));
  sut.dm1Sent(SECOND);
  CHECK_FALSE(sut.dm1Due(SECOND + 500 * MS));
}

TEST_CASE("a change makes DM1 due at once, further changes within the period wait for it") {
  DiagnosticState sut = makeState();
  sut.dm1Sent(0);
  set(sut, true, false, false, 100 * MS);
  CHECK(sut.dm1Due(100 * MS));
  sut.dm1Sent(100 * MS);                    // the on-change DM1; the period restarts
  set(sut, false, false, false, 300 * MS);  // a second change 200 ms later
  CHECK_FALSE(sut.dm1Due(300 * MS));
  CHECK_FALSE(sut.dm1Due(1099 * MS));
  CHECK(sut.nextDm1DueNs() == 1100 * MS);
  CHECK(sut.dm1Due(1100 * MS));
  sut.dm1Sent(1100 * MS);
  set(sut, true, false, false, 2500 * MS);  // more than a period after the last on-change DM1
  CHECK(sut.dm1Due(2500 * MS));
}

TEST_CASE("a DM11 that changes DM1 makes it due at once, a DM3 does not") {
  DiagnosticState sut = makeState();
  set(sut, true, false, false);
  set(sut, false, false, false);
  set(sut, true, false, false);  // count 2, active
  sut.dm1Sent(0);
  set(sut, true, true, false, 2 * SECOND);
  set(sut, true, false, false, 2 * SECOND);
  sut.dm1Sent(2 * SECOND);  // on-change DM1 at 2 s: the next on-change one waits until 3 s
  CHECK(sut.clearPreviouslyActive());
  CHECK_FALSE(sut.dm1Due(3 * SECOND - 1));
  CHECK(sut.clearActive());  // battery count 2 -> 1: the DM1 content changed
  CHECK(sut.dm1Due(3 * SECOND));
  CHECK_FALSE(sut.dm1Due(3 * SECOND - 1));
}
