// DBC grammar, part 2: multiplexing (M, mN, mNM, bare m, SG_MUL_VAL_).

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <string>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {
const Signal* signalOf(const ParseOutput& output, std::string_view name) {
  if (output.database.messages.empty()) return nullptr;
  return output.database.messages[0].findSignal(name);
}

/// The signal `name` of the first message; fails the test when there is none.
const Signal* requiredSignal(const ParseOutput& output, std::string_view name) {
  const Signal* signal = signalOf(output, name);
  REQUIRE(signal != nullptr);
  return signal;
}

/// Message "M" (ID 1, 8 bytes) whose first signal is the multiplexor "Selector" (bits 0..7),
/// followed by `rest` (more SG_ lines and statements).
ParseOutput withSelector(const std::string& rest) {
  return parseText("BO_ 1 M: 8 Vcu\n SG_ Selector M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n" + rest);
}
}  // namespace

TEST_CASE("parser reads M as multiplexor and mN as multiplexed by it") {
  const ParseOutput sut = withSelector(
      " SG_ Page0 m0 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Page17 m17 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(sut.diagnostics.empty());
  const Signal* selector = requiredSignal(sut, "Selector");
  const Signal* page17 = requiredSignal(sut, "Page17");
  CHECK(selector->muxRole == MuxRole::Multiplexor);
  CHECK(page17->muxRole == MuxRole::Multiplexed);
  CHECK(page17->muxValue == 17);
  CHECK(page17->muxSwitch == "Selector");
  CHECK(page17->muxRanges.empty());
  CHECK_FALSE(page17->extendedMux);
}

TEST_CASE("parser reads mNM as a multiplexed multiplexor") {
  const ParseOutput sut = withSelector(
      " SG_ Sub m2M : 8|4@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Leaf m3 : 16|8@1+ (1,0) [0|0] \"\" Vcu\n"
      "SG_MUL_VAL_ 1 Sub Selector 2-2;\n"
      "SG_MUL_VAL_ 1 Leaf Sub 3-3;\n");

  CHECK(sut.diagnostics.empty());
  const Signal* sub = requiredSignal(sut, "Sub");
  const Signal* leaf = requiredSignal(sut, "Leaf");
  CHECK(sub->muxRole == MuxRole::MultiplexedMultiplexor);
  CHECK(sub->muxValue == 2);
  CHECK(sub->muxSwitch == "Selector");
  CHECK(leaf->muxSwitch == "Sub");
  CHECK(leaf->extendedMux);
}

TEST_CASE("parser reads a bare m indicator as a multiplexor") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ Code m : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Page1 m1 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(sut.diagnostics.empty());
  const Signal* code = requiredSignal(sut, "Code");
  const Signal* page1 = requiredSignal(sut, "Page1");
  CHECK(code->muxRole == MuxRole::Multiplexor);
  CHECK(page1->muxSwitch == "Code");
}

TEST_CASE("parser rejects a malformed multiplexer indicator") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ Bad mX : 0|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(hasError(sut, "bad multiplexer indicator 'mX'"));
}

TEST_CASE("parser warns about a multiplexed signal in a message without a multiplexor") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ Orphan m1 : 0|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "has no multiplexor"));
}

TEST_CASE("parser reads SG_MUL_VAL_ with one range") {
  const ParseOutput sut = withSelector(
      " SG_ Value m5 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
      "SG_MUL_VAL_ 1 Value Selector 5-9;\n");

  CHECK(sut.diagnostics.empty());
  const Signal* value = requiredSignal(sut, "Value");
  CHECK(value->extendedMux);
  CHECK(value->muxSwitch == "Selector");
  CHECK(value->muxRanges == std::vector<MuxRange>{{5, 9}});
}

TEST_CASE("parser reads SG_MUL_VAL_ with several ranges") {
  const ParseOutput sut = withSelector(
      " SG_ Value m8 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
      "SG_MUL_VAL_ 1 Value Selector 8-8, 16-16,24-31 ;\n");

  CHECK(sut.diagnostics.empty());
  const Signal* value = requiredSignal(sut, "Value");
  CHECK(value->muxRanges == std::vector<MuxRange>{{8, 8}, {16, 16}, {24, 31}});
}

TEST_CASE("parser assigns two independent multiplexors through SG_MUL_VAL_") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ MuxA M : 0|4@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ MuxB M : 4|4@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ ValueA m1 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ ValueB m2 : 16|8@1+ (1,0) [0|0] \"\" Vcu\n"
      "SG_MUL_VAL_ 1 ValueA MuxA 1-1;\n"
      "SG_MUL_VAL_ 1 ValueB MuxB 2-2;\n");

  CHECK(sut.diagnostics.empty());
  const Signal* valueA = requiredSignal(sut, "ValueA");
  const Signal* valueB = requiredSignal(sut, "ValueB");
  CHECK(valueA->muxSwitch == "MuxA");
  CHECK(valueB->muxSwitch == "MuxB");
}

TEST_CASE("parser uses the first multiplexor with a warning when several exist and SG_MUL_VAL_ is missing") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ MuxA M : 0|4@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ MuxB M : 4|4@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Value m1 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "several multiplexors"));
  const Signal* value = requiredSignal(sut, "Value");
  CHECK(value->muxSwitch == "MuxA");
}

TEST_CASE("parser ignores SG_MUL_VAL_ for a signal that is not multiplexed, with a warning") {
  const ParseOutput sut = withSelector(
      " SG_ Plain : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
      "SG_MUL_VAL_ 1 Plain Selector 1-1;\n");

  CHECK(hasWarning(sut, "not multiplexed"));
  const Signal* plain = requiredSignal(sut, "Plain");
  CHECK_FALSE(plain->extendedMux);
  CHECK(plain->muxSwitch.empty());
}

TEST_CASE("parser reports a bad SG_MUL_VAL_ for a multiplexed signal") {
  struct Row {
    const char* name;
    const char* mulVal;
    const char* error;
  };
  const Row rows[] = {
      {"naming a multiplexor the message does not have", "SG_MUL_VAL_ 1 Value Nobody 1-1;\n", "does not have"},
      {"a range whose upper bound is below its lower bound", "SG_MUL_VAL_ 1 Value Selector 9-3;\n",
       "upper bound below lower bound"},
  };
  for (const Row& row : rows) {
    SUBCASE(row.name) {
      const ParseOutput sut = withSelector(std::string(" SG_ Value m1 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n") + row.mulVal);

      CHECK(hasError(sut, row.error));
    }
  }
}

TEST_CASE("parser reports a multiplexor chain that loops") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ A m1M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ B m1M : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
      "SG_MUL_VAL_ 1 A B 1-1;\n"
      "SG_MUL_VAL_ 1 B A 1-1;\n");

  CHECK(hasError(sut, "loops"));
}

TEST_CASE("parser reads the multiplexing fixture without diagnostics") {
  const ParseOutput sut = parse(readFixture("multiplexing.dbc"), "multiplexing.dbc");

  INFO(describe(sut));
  CHECK(sut.diagnostics.empty());
  const Message* twoMux = sut.database.findMessage("TwoMultiplexors");
  REQUIRE(twoMux != nullptr);
  const Signal* valueB = twoMux->findSignal("ValueB");
  REQUIRE(valueB != nullptr);
  CHECK(valueB->muxRanges == std::vector<MuxRange>{{2, 3}, {5, 5}, {8, 15}});
}
