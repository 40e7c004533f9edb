// The spin check (machine_cycles.hpp, issue 18): transitions that can fire in a cycle with
// no input change are an error naming the states; cycles that need an input change, a
// timer, or that their own commands stop are accepted; the HHEA machine is accepted.

#include <doctest/doctest.h>

#include <chrono>

#include "fsm_test_support.hpp"

using namespace openvcu;
using fsmtest::count;
using fsmtest::listing;

namespace {

const std::string SPIN = "transitions can fire in a cycle without any input change";

/// A -> B by `aToB`, B -> A by `bToA` (JSON text of the two transitions' bodies without
/// nextState).
std::string twoStates(const std::string& aToB, const std::string& bToA) {
  return R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{)" +
         aToB + R"(, "nextState": "B"}]},
    {"name": "B", "transitions": [{)" +
         bToA + R"(, "nextState": "A"}]}]})";
}

std::size_t spinErrors(const std::vector<Error>& diagnostics) {
  std::size_t found = 0;
  for (const Error& diagnostic : diagnostics) {
    if (diagnostic.severity == Severity::Error && diagnostic.message.find(SPIN) != std::string::npos) ++found;
  }
  return found;
}

}  // namespace

TEST_CASE("two always-true transitions A -> B -> A are refused with the states and the transitions named") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(twoStates(R"("condition": {})", R"("condition": {})"), &diagnostics);
  INFO(listing(diagnostics));
  REQUIRE_FALSE(result);
  CHECK(count(diagnostics, Severity::Error, "/states/0/transitions/0",
              SPIN + ": 'A' -> 'B' -> 'A' (/states/0/transitions/0, /states/1/transitions/0): their conditions "
                     "are always true") == 1);
  CHECK(spinErrors(diagnostics) == 1);
  CHECK(result.error().message.find("'A' -> 'B' -> 'A'") != std::string::npos);
}

TEST_CASE("one input value that holds both ways is refused, with that value named") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(twoStates(R"("condition": {"key": "internal.operator.StartStop", "eq": "Start"})",
                                             R"("condition": {"key": "internal.operator.StartStop", "ne": "Stop"})"),
                                   &diagnostics);
  INFO(listing(diagnostics));
  REQUIRE_FALSE(result);
  CHECK(count(diagnostics, Severity::Error, "/states/0/transitions/0", "e.g. with internal.operator.StartStop = 1 (Start)") ==
        1);
}

TEST_CASE("a longer cycle is named state by state, and every state's edge is checked") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 50}, "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "lt": 80}, "nextState": "C"}]},
    {"name": "C", "transitions": [{"condition": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "quality": "stale"},
                                   "nextState": "A"}]}]})",
                                   &diagnostics);
  INFO(listing(diagnostics));
  REQUIRE_FALSE(result);
  CHECK(count(diagnostics, Severity::Error, "/states/0/transitions/0", "'A' -> 'B' -> 'C' -> 'A'") == 1);
  CHECK(count(diagnostics, Severity::Error, "/states/0/transitions/0", "HS_HiUBusCnctnSts") == 1);
  CHECK(count(diagnostics, Severity::Error, "/states/0/transitions/0", "Stale") == 1);
  // the same ring where C needs a SOC the ring never has in B: accepted
  std::vector<Error> settled;
  const auto accepted = hhea.compile(R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 50}, "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "lt": 80}, "nextState": "C"}]},
    {"name": "C", "transitions": [{"condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "le": 50}, "nextState": "A"}]}]})",
                                     &settled);
  INFO(listing(settled));
  CHECK(accepted);
  CHECK(spinErrors(settled) == 0);
}

TEST_CASE("a signal with a value table takes whole numbers only: gt 0 and lt 1 never hold together") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(twoStates(R"("condition": {"key": "internal.operator.StartStop", "gt": 0})",
                                             R"("condition": {"key": "internal.operator.StartStop", "lt": 1})"),
                                   &diagnostics);
  INFO(listing(diagnostics));
  CHECK(result);
  CHECK(spinErrors(diagnostics) == 0);
  // a signal without a value table can be 0.5
  std::vector<Error> real;
  CHECK_FALSE(hhea.compile(twoStates(R"("condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "gt": 50})",
                                     R"("condition": {"key": "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "lt": 51})"),
                           &real));
  CHECK(count(real, Severity::Error, "/states/0/transitions/0", "HS_FastUpdSOC = 50.5") == 1);
}

TEST_CASE("a cycle that needs an input to change is accepted") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(twoStates(R"("condition": {"key": "internal.operator.StartStop", "eq": "Start"})",
                                             R"("condition": {"key": "internal.operator.StartStop", "eq": "Stop"})"),
                                   &diagnostics);
  INFO(listing(diagnostics));
  CHECK(result);
  CHECK(spinErrors(diagnostics) == 0);
}

TEST_CASE("a timer in the cycle (after, for) makes it legal") {
  const fsmtest::Hhea hhea;
  for (const std::string& back : {std::string(R"("after": "1s")"),
                                  std::string(R"("condition": {"key": "internal.operator.StartStop", "eq": 0, "for": "1s"})"),
                                  std::string(R"("condition": {"all": [{}], "for": "10ms"})")}) {
    std::vector<Error> diagnostics;
    const auto result = hhea.compile(twoStates(R"("condition": {})", back), &diagnostics);
    INFO(back);
    INFO(listing(diagnostics));
    CHECK(result);
    CHECK(spinErrors(diagnostics) == 0);
  }
}

TEST_CASE("the machine's own commands: a cycle they keep true is refused, one they make false is accepted") {
  const fsmtest::Hhea hhea;
  // A sets Cl15 1 on the way to B, B sets it 0 on the way back: each enables the other.
  std::vector<Error> oscillating;
  const auto refused = hhea.compile(
      twoStates(R"("condition": {"key": "internal.relay.Cl15", "eq": 0}, "actions": [{"signal": "internal.relay.Cl15", "value": 1}])",
                R"("condition": {"key": "internal.relay.Cl15", "eq": 1}, "actions": [{"signal": "internal.relay.Cl15", "value": 0}])"),
      &oscillating);
  INFO(listing(oscillating));
  CHECK_FALSE(refused);
  CHECK(spinErrors(oscillating) == 1);
  // B waits for Cl15 0, but the way to B set it 1: B stays until someone else changes it.
  std::vector<Error> consumed;
  const auto accepted = hhea.compile(
      twoStates(R"("condition": {"key": "internal.relay.Cl15", "eq": 0}, "actions": [{"signal": "internal.relay.Cl15", "value": 1}])",
                R"("condition": {"key": "internal.relay.Cl15", "eq": 0})"),
      &consumed);
  INFO(listing(consumed));
  CHECK(accepted);
  CHECK(spinErrors(consumed) == 0);
  // the entry action of a state counts as well
  std::vector<Error> entry;
  const auto byEntry = hhea.compile(R"({"initialState": "A", "states": [
    {"name": "A", "entry": [{"signal": "internal.relay.Cl15", "value": 0}],
     "transitions": [{"condition": {"key": "internal.relay.Cl15", "eq": 1}, "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {}, "nextState": "A"}]}]})",
                                    &entry);
  INFO(listing(entry));
  CHECK(byEntry);
  CHECK(spinErrors(entry) == 0);
}

TEST_CASE("an earlier transition that must be taken instead breaks the cycle (file order is priority)") {
  const fsmtest::Hhea hhea;
  // In A, Stop goes to C first; the cycle's way back from B needs Stop: never both.
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [
      {"condition": {"key": "internal.operator.StartStop", "eq": "Stop"}, "nextState": "C"},
      {"condition": {}, "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": "Stop"}, "nextState": "A"}]},
    {"name": "C", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": "Start"}, "nextState": "A"}]}]})",
                                   &diagnostics);
  INFO(listing(diagnostics));
  CHECK(result);
  CHECK(spinErrors(diagnostics) == 0);
}

TEST_CASE("ageGt: never received is old, so an ageGt both ways spins, but ageGt one way and not ageGt back does not") {
  const fsmtest::Hhea hhea;
  const std::string old = R"("condition": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "ageGt": "3s"})";
  std::vector<Error> both;
  CHECK_FALSE(hhea.compile(twoStates(old, old), &both));
  CHECK(count(both, Severity::Error, "/states/0/transitions/0", "HS_HiUBusCnctnSts never received") == 1);
  std::vector<Error> recovering;
  const auto accepted = hhea.compile(
      twoStates(old, R"("condition": {"not": {"key": "VIC.HVESSS1_PGN61590.HS_HiUBusCnctnSts", "ageGt": "3s"}})"),
      &recovering);
  INFO(listing(recovering));
  CHECK(accepted);
  CHECK(spinErrors(recovering) == 0);
}

TEST_CASE("self-transitions are no cycle, and a self-transition's command is not assumed") {
  const fsmtest::Hhea hhea;
  std::vector<Error> diagnostics;
  const auto result = hhea.compile(R"({"initialState": "A", "states": [
    {"name": "A", "transitions": [
      {"condition": {}, "actions": [{"signal": "internal.relay.Cl15", "value": 1}], "nextState": "A"},
      {"condition": {"key": "internal.relay.Cl15", "eq": 0}, "nextState": "B"}]},
    {"name": "B", "transitions": [{"condition": {"key": "internal.relay.Cl15", "eq": 0}, "nextState": "A"}]}]})",
                                   &diagnostics);
  INFO(listing(diagnostics));
  CHECK(result);
  CHECK(spinErrors(diagnostics) == 0);
}

TEST_CASE("the HHEA machine is accepted without a cycle error") {
  const fsmtest::Hhea hhea;
  REQUIRE_FALSE(hhea.vehicle.fsmFile.empty());
  std::vector<Error> diagnostics;
  const auto result = fsm::loadMachine(hhea.vehicle.fsmFile, hhea.vehicle, hhea.catalog, &diagnostics);
  INFO(listing(diagnostics));
  REQUIRE(result);
  CHECK(spinErrors(diagnostics) == 0);
  for (const Error& diagnostic : diagnostics) CHECK(diagnostic.message.find("cycle check stopped") == std::string::npos);
}

TEST_CASE("a huge machine neither stalls the cycle check nor exhausts the stack, and its short cycles are still checked") {
  const fsmtest::Hhea hhea;
  // 20000 states in a ring: one cycle longer than the check follows; then a spinning pair,
  // which is still found.
  constexpr int STATES = 20'000;
  std::string text = R"({"initialState": "S0", "states": [)";
  for (int s = 0; s < STATES; ++s) {
    if (s > 0) text += ',';
    text += R"({"name": "S)" + std::to_string(s) + R"(", "transitions": [{"condition": {"key": "internal.operator.StartStop", "eq": 1}, "nextState": "S)" +
            std::to_string((s + 1) % STATES) + R"("}]})";
  }
  text += R"(,{"name": "P", "transitions": [{"condition": {}, "nextState": "Q"}]},
             {"name": "Q", "transitions": [{"condition": {}, "nextState": "P"}]}]})";
  std::vector<Error> diagnostics;
  const auto start = std::chrono::steady_clock::now();
  const auto result = hhea.compile(text, &diagnostics);
  const auto took = std::chrono::steady_clock::now() - start;
  CHECK_FALSE(result);
  CHECK(spinErrors(diagnostics) == 1);  // P <-> Q; the ring is not proved: the loop guard bounds it
  CHECK(count(diagnostics, Severity::Error, "/states/20000/transitions/0", "'P' -> 'Q' -> 'P'") == 1);
  CHECK(count(diagnostics, Severity::Warning, "/", "cycles of more than 64 states were not examined") == 1);
  CHECK(took < std::chrono::seconds(10));
}
