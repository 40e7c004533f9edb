// Attributes resolved at load with their defaults: GenMsgCycleTime, GenSigStartValue,
// VFrameFormat (each file's own ENUM order, or INT), ProtocolType and the long symbols.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <string>
#include <utility>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {
constexpr std::uint32_t DEFAULT_CYCLE_MS = 100;
constexpr std::uint32_t EXPLICIT_CYCLE_MS = 20;

/// Vector's ENUM order (CSS and cantools J1939 files): J1939PG is index 3.
const std::string VECTOR_ENUM = R"(BA_DEF_ BO_ "VFrameFormat" ENUM "StandardCAN","ExtendedCAN","reserved","J1939PG";)";
/// canmatrix' j1939.dbc order: J1939PG is index 4.
const std::string CANMATRIX_ENUM =
    R"(BA_DEF_ BO_ "VFrameFormat" ENUM "StandardCAN","ExtendedCAN","StandardCAN_FD","ExtendedCAN_FD","J1939PG";)";

const std::string TWO_MESSAGES =
    "BO_ 2364535585 Flagged: 8 Vcu\n"
    " SG_ S : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
    "BO_ 1809 Plain: 8 Vcu\n"
    " SG_ T : 0|8@1+ (1,0) [0|0] \"\" Vcu\n";

/// TWO_MESSAGES' messages "Flagged" and "Plain" of a parse; fails the test unless both are
/// there with their signal.
std::pair<const Message*, const Message*> flaggedAndPlain(const ParseOutput& sut) {
  const Message* flagged = sut.database.findMessage("Flagged");
  const Message* plain = sut.database.findMessage("Plain");
  REQUIRE(flagged != nullptr);
  REQUIRE(plain != nullptr);
  REQUIRE(!flagged->signals.empty());
  REQUIRE(!plain->signals.empty());
  return {flagged, plain};
}

/// The resolved frame format's DBC name ("J1939PG"), or "no such message".
std::string formatOf(const ParseOutput& output, std::string_view name) {
  const Message* message = output.database.findMessage(name);
  return message ? std::string(toString(message->frameFormat)) : "no such message";
}
}  // namespace

TEST_CASE("parser resolves GenMsgCycleTime from the explicit value, else the default") {
  const ParseOutput sut = parseText(TWO_MESSAGES + "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n" +
                                    "BA_DEF_DEF_ \"GenMsgCycleTime\" " + std::to_string(DEFAULT_CYCLE_MS) + ";\n" +
                                    "BA_ \"GenMsgCycleTime\" BO_ 2364535585 " + std::to_string(EXPLICIT_CYCLE_MS) +
                                    ";\n");

  CHECK(sut.diagnostics.empty());
  const Message* flagged = sut.database.findMessage("Flagged");
  const Message* plain = sut.database.findMessage("Plain");
  REQUIRE(flagged != nullptr);
  REQUIRE(plain != nullptr);
  CHECK(flagged->cycleTimeMs == EXPLICIT_CYCLE_MS);
  CHECK(plain->cycleTimeMs == DEFAULT_CYCLE_MS);
}

TEST_CASE("parser leaves the cycle time empty when GenMsgCycleTime is 0") {
  const ParseOutput sut = parseText(TWO_MESSAGES + "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n" +
                                    "BA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n");

  const Message* plain = sut.database.findMessage("Plain");
  REQUIRE(plain != nullptr);
  CHECK_FALSE(plain->cycleTimeMs.has_value());
}

TEST_CASE("parser resolves GenSigStartValue from the explicit value, else the default") {
  constexpr double DEFAULT_START = 7;
  constexpr double EXPLICIT_START = 42;
  const ParseOutput sut = parseText(TWO_MESSAGES + "BA_DEF_ SG_ \"GenSigStartValue\" INT 0 255;\n" +
                                    "BA_DEF_DEF_ \"GenSigStartValue\" 7;\n" +
                                    "BA_ \"GenSigStartValue\" SG_ 2364535585 S 42;\n");

  CHECK(sut.diagnostics.empty());
  const auto [flagged, plain] = flaggedAndPlain(sut);
  CHECK(sut.database.startValueRaw(flagged->signals[0]) == EXPLICIT_START);
  CHECK(sut.database.startValueRaw(plain->signals[0]) == DEFAULT_START);
}

TEST_CASE("parser has no start value when GenSigStartValue is not defined") {
  const ParseOutput sut = parseText(TWO_MESSAGES);

  REQUIRE(!sut.database.messages.empty());
  REQUIRE(!sut.database.messages[0].signals.empty());
  CHECK_FALSE(sut.database.startValueRaw(sut.database.messages[0].signals[0]).has_value());
}

TEST_CASE("parser resolves VFrameFormat index 3 as J1939PG in a file with Vector's ENUM order") {
  const ParseOutput sut = parseText(TWO_MESSAGES + VECTOR_ENUM + "\nBA_ \"VFrameFormat\" BO_ 2364535585 3;\n");

  CHECK(sut.diagnostics.empty());
  CHECK(formatOf(sut, "Flagged") == "J1939PG");
  REQUIRE(sut.database.findMessage("Flagged") != nullptr);
  CHECK(sut.database.findMessage("Flagged")->isJ1939());
}

TEST_CASE("parser resolves VFrameFormat index 4 as J1939PG and 3 as ExtendedCAN_FD in canmatrix' ENUM order") {
  const ParseOutput sut = parseText(TWO_MESSAGES + CANMATRIX_ENUM +
                                    "\nBA_ \"VFrameFormat\" BO_ 2364535585 4;\nBA_ \"VFrameFormat\" BO_ 1809 3;\n");

  CHECK(sut.diagnostics.empty());
  CHECK(formatOf(sut, "Flagged") == "J1939PG");
  CHECK(formatOf(sut, "Plain") == "ExtendedCAN_FD");
}

TEST_CASE("parser applies a VFrameFormat default given as the ENUM text") {
  const ParseOutput sut = parseText(TWO_MESSAGES + VECTOR_ENUM + "\nBA_DEF_DEF_ \"VFrameFormat\" \"J1939PG\";\n" +
                                    "BA_ \"VFrameFormat\" BO_ 1809 0;\n");

  CHECK(sut.diagnostics.empty());
  CHECK(formatOf(sut, "Flagged") == "J1939PG");
  CHECK(formatOf(sut, "Plain") == "StandardCAN");
}

TEST_CASE("parser resolves VFrameFormat declared INT with Vector's numbers 0, 1, 3, 14 and 15") {
  struct Case {
    int value;
    FrameFormat expected;
  };
  const Case cases[] = {{0, FrameFormat::StandardCan},
                        {1, FrameFormat::ExtendedCan},
                        {3, FrameFormat::J1939},
                        {14, FrameFormat::StandardCanFd},
                        {15, FrameFormat::ExtendedCanFd}};
  for (const Case& c : cases) {
    CAPTURE(c.value);
    const ParseOutput sut = parseText(TWO_MESSAGES + "BA_DEF_ BO_ \"VFrameFormat\" INT 0 15;\n" +
                                      "BA_ \"VFrameFormat\" BO_ 1809 " + std::to_string(c.value) + ";\n");

    CHECK(sut.diagnostics.empty());
    CHECK(formatOf(sut, "Plain") == std::string(toString(c.expected)));
  }
}

TEST_CASE("parser derives the frame format from ID and length without VFrameFormat") {
  const ParseOutput sut = parseText(
      "BO_ 1 Classic: 8 Vcu\n"
      "BO_ 2 Fd: 64 Vcu\n"
      "BO_ 2147483651 ExtClassic: 8 Vcu\n"
      "BO_ 2147483652 ExtFd: 12 Vcu\n");

  CHECK(formatOf(sut, "Classic") == "StandardCAN");
  CHECK(formatOf(sut, "Fd") == "StandardCAN_FD");
  CHECK(formatOf(sut, "ExtClassic") == "ExtendedCAN");
  CHECK(formatOf(sut, "ExtFd") == "ExtendedCAN_FD");
}

TEST_CASE("parser treats extended messages of a ProtocolType J1939 network as J1939") {
  const ParseOutput sut = parseText(TWO_MESSAGES + "BA_DEF_ \"ProtocolType\" STRING;\nBA_ \"ProtocolType\" \"J1939\";\n");

  CHECK(formatOf(sut, "Flagged") == "J1939PG");
  CHECK(formatOf(sut, "Plain") == "StandardCAN");
}

TEST_CASE("parser sets displayName from SystemSignalLongSymbol and SystemMessageLongSymbol") {
  const ParseOutput sut = parseText(TWO_MESSAGES +
                                    "BA_DEF_ SG_ \"SystemSignalLongSymbol\" STRING;\n"
                                    "BA_DEF_ BO_ \"SystemMessageLongSymbol\" STRING;\n"
                                    "BA_DEF_DEF_ \"SystemSignalLongSymbol\" \"\";\n"
                                    "BA_ \"SystemSignalLongSymbol\" SG_ 2364535585 S \"Engine's Speed (long name)\";\n"
                                    "BA_ \"SystemMessageLongSymbol\" BO_ 1809 \"Plain_Message_With_A_Very_Long_Name_Beyond_32\";\n");

  CHECK(sut.diagnostics.empty());
  const auto [flagged, plain] = flaggedAndPlain(sut);
  CHECK(flagged->signals[0].displayName == "Engine's Speed (long name)");
  CHECK(flagged->signals[0].name == "S");
  CHECK(plain->signals[0].displayName == "T");
  CHECK(plain->displayName == "Plain_Message_With_A_Very_Long_Name_Beyond_32");
  CHECK(flagged->displayName == "Flagged");
}

TEST_CASE("parser resolves the J1939 fixture with its own defaults") {
  const ParseOutput sut = parse(readFixture("j1939_hhea_vcu.dbc"), "j1939_hhea_vcu.dbc");

  INFO(describe(sut));
  CHECK(sut.diagnostics.empty());
  const Message* s1 = sut.database.findMessage("S1_ES_PGN61427");
  const Message* propA = sut.database.findMessage("PropA_C3_PGN61184");
  const Message* heartbeat = sut.database.findMessage("VcuHeartbeat");
  REQUIRE(s1 != nullptr);
  REQUIRE(propA != nullptr);
  REQUIRE(heartbeat != nullptr);
  CHECK(s1->isJ1939());
  CHECK(s1->cycleTimeMs == 20u);
  CHECK(propA->isJ1939());
  CHECK(propA->extended);
  CHECK(std::string(toString(heartbeat->frameFormat)) == "StandardCAN");
  CHECK_FALSE(heartbeat->cycleTimeMs.has_value());
}

TEST_CASE("parser resolves VFrameFormat through each fixture file's own ENUM order") {
  const ParseOutput vectorOrder = parse(readFixture("vframeformat_enum_vector_order.dbc"), "vector_order.dbc");
  const ParseOutput canmatrixOrder = parse(readFixture("vframeformat_enum_canmatrix_order.dbc"), "canmatrix_order.dbc");

  CHECK(vectorOrder.diagnostics.empty());
  CHECK(canmatrixOrder.diagnostics.empty());
  CHECK(formatOf(vectorOrder, "Tagged") == "J1939PG");
  CHECK(formatOf(vectorOrder, "Untagged") == "ExtendedCAN");
  CHECK(formatOf(canmatrixOrder, "Tagged") == "J1939PG");
  CHECK(formatOf(canmatrixOrder, "FdNotJ1939") == "ExtendedCAN_FD");
}

TEST_CASE("parser resolves the VFrameFormat INT fixture with Vector's numbers") {
  const ParseOutput sut = parse(readFixture("vframeformat_int.dbc"), "vframeformat_int.dbc");

  CHECK(sut.diagnostics.empty());
  CHECK(formatOf(sut, "Classic") == "StandardCAN");
  CHECK(formatOf(sut, "Extended") == "ExtendedCAN");
  CHECK(formatOf(sut, "J1939") == "J1939PG");
  CHECK(formatOf(sut, "ClassicFd") == "StandardCAN_FD");
  CHECK(formatOf(sut, "ExtendedFd") == "ExtendedCAN_FD");
}
