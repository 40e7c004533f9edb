// DBC grammar, part 1: the header statements (VERSION, NS_, BS_, BU_), BO_ and SG_.
// One test per grammar item; inline text keeps each case readable on its own.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <limits>
#include <string>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {
constexpr std::uint32_t EXTENDED_FLAG = 0x80000000u;
constexpr std::uint32_t J1939_EEC1_ID = 0x0CF00400u;  // 29-bit ID used in the cases below
}  // namespace

// ------------------------------------------------------------------ header statements

TEST_CASE("parser reads the VERSION string") {
  const ParseOutput sut = parseText("VERSION \"3.1 beta\"\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.version == "3.1 beta");
}

TEST_CASE("parser accepts a VERSION keyword without a string") {
  const ParseOutput sut = parseText("VERSION\nBU_: A\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(sut.database.version.empty());
  REQUIRE(sut.database.nodes.size() == 1);
}

TEST_CASE("parser keeps NS_ entries as new symbols and reads the statements after them") {
  const ParseOutput sut = parseText(
      "NS_ :\n"
      "\tNS_DESC_\n"
      "\tCM_\n"
      "\tBA_DEF_ BA_\n"
      "\tBU_SG_REL_\n"
      "\n"
      "BS_:\n"
      "BU_: Vcu\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.newSymbols == std::vector<std::string>{"NS_DESC_", "CM_", "BA_DEF_", "BA_", "BU_SG_REL_"});
  REQUIRE(sut.database.nodes.size() == 1);
  CHECK(sut.database.nodes[0].name == "Vcu");
}

TEST_CASE("parser accepts an empty NS_ list") {
  const ParseOutput sut = parseText("NS_ :\n\nBS_:\n\nBU_: Vcu\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.newSymbols.empty());
  CHECK(sut.database.nodes.size() == 1);
}

TEST_CASE("parser accepts an empty NS_ list directly followed by BS_") {
  const ParseOutput sut = parseText("NS_ :\nBS_:\nBU_: Vcu\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.newSymbols.empty());
  CHECK(sut.database.nodes.size() == 1);
}

TEST_CASE("parser skips the BS_ bit timing with and without values") {
  const ParseOutput sut = parseText("BS_: 500 : 12,34\nBS_:\nBU_: Vcu\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.nodes.size() == 1);
}

TEST_CASE("parser reads the BU_ node list on one line") {
  const ParseOutput sut = parseText("BU_: Vcu Battery  Charger\t64_NODE\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.nodes.size() == 4);
  CHECK(sut.database.nodes[0].name == "Vcu");
  CHECK(sut.database.nodes[3].name == "64_NODE");
  CHECK(sut.database.findNode("Charger") != nullptr);
}

TEST_CASE("parser reads a BU_ node list spread over several lines up to the next statement") {
  const ParseOutput sut = parseText(
      "BU_: Vcu Battery\n"
      "  Charger\n"
      "\tInverter\n"
      "\n"
      "BO_ 1 M: 1 Vcu\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.nodes.size() == 4);
  CHECK(sut.database.nodes[3].name == "Inverter");
  CHECK(sut.database.messages.size() == 1);
}

TEST_CASE("parser ends the BU_ list at a line starting in column 1") {
  const ParseOutput sut = parseText("BU_: Vcu\n\tBattery\nB0_ 100 Typo: 8 Vcu\n");

  CHECK(sut.database.nodes.size() == 2);
  CHECK(hasError(sut, "unknown statement 'B0_'"));
}

TEST_CASE("parser warns about a node listed twice") {
  const ParseOutput sut = parseText("BU_: Vcu Vcu\n");

  CHECK(hasWarning(sut, "listed twice"));
}

// ------------------------------------------------------------------ BO_

TEST_CASE("parser reads a standard BO_ message") {
  const ParseOutput sut = parseText("BO_ 1809 Heartbeat: 8 Vcu\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  const Message& message = sut.database.messages[0];
  CHECK(message.name == "Heartbeat");
  CHECK(message.id == 1809);
  CHECK(message.declaredId == 1809);
  CHECK_FALSE(message.extended);
  CHECK_FALSE(message.pseudo);
  CHECK(message.length == 8);
  CHECK(message.transmitter == "Vcu");
  CHECK(sut.database.findMessage(1809, false) == &message);
  CHECK(sut.database.findMessage(1809, true) == nullptr);
}

TEST_CASE("parser reads bit 31 of a BO_ ID as the extended flag") {
  const std::uint32_t declared = J1939_EEC1_ID | EXTENDED_FLAG;
  const ParseOutput sut = parseText("BO_ " + std::to_string(declared) + " EEC1: 8 Engine\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  const Message& message = sut.database.messages[0];
  CHECK(message.id == J1939_EEC1_ID);
  CHECK(message.declaredId == declared);
  CHECK(message.extended);
  CHECK(sut.database.findMessage(J1939_EEC1_ID, true) == &message);
}

TEST_CASE("parser reads a 29-bit ID written without the extended flag as extended") {
  const ParseOutput sut = parseText("BO_ " + std::to_string(J1939_EEC1_ID) + " EEC1: 8 Engine\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].extended);
  CHECK(sut.database.messages[0].id == J1939_EEC1_ID);
  CHECK(sut.database.findMessage(J1939_EEC1_ID, true) != nullptr);
}

TEST_CASE("parser resolves references to a flagless 29-bit ID written either way") {
  const std::uint32_t flagged = J1939_EEC1_ID | EXTENDED_FLAG;
  const ParseOutput sut = parseText("BO_ " + std::to_string(J1939_EEC1_ID) + " EEC1: 8 Engine\n" +
                                    " SG_ Speed : 24|16@1+ (0.125,0) [0|8031.875] \"rpm\" Vcu\n" +
                                    "CM_ BO_ " + std::to_string(flagged) + " \"by flagged ID\";\n" +
                                    "CM_ SG_ " + std::to_string(J1939_EEC1_ID) + " Speed \"by plain ID\";\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].comment == "by flagged ID");
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].comment == "by plain ID");
}

TEST_CASE("parser marks an ID with bit 29 or 30 set as a pseudo message and warns") {
  const ParseOutput sut = parseText("BO_ 4294967295 Odd: 8 Vcu\n SG_ S : 0|8@1+ (1,0) [0|255] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "bit 29 or 30"));
  REQUIRE(sut.database.messages.size() == 1);
  const Message& message = sut.database.messages[0];
  CHECK(message.pseudo);
  CHECK(message.declaredId == 0xFFFFFFFFu);
  CHECK(sut.database.findMessage(message.id, message.extended) == nullptr);
  CHECK(sut.database.findMessage("Odd") == &message);
}

TEST_CASE("parser keeps VECTOR__INDEPENDENT_SIG_MSG as a pseudo message without a warning") {
  const ParseOutput sut = parseText(
      "BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: 0 Vector__XXX\n"
      " SG_ Orphan : 0|8@1+ (1,0) [0|255] \"\" Vector__XXX\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  const Message& message = sut.database.messages[0];
  CHECK(message.pseudo);
  CHECK(message.length == 0);
  CHECK(message.signals.size() == 1);
  CHECK(sut.database.findMessage(0, false) == nullptr);
  CHECK(sut.database.findMessage(0, true) == nullptr);
  CHECK(sut.database.findMessage(INDEPENDENT_SIGNALS) == &message);
}

TEST_CASE("parser accepts a space before the BO_ colon") {
  const ParseOutput sut = parseText("BO_ 1 X : 8 N\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].name == "X");
  CHECK(sut.database.messages[0].transmitter == "N");
}

TEST_CASE("parser accepts a BO_ without a transmitter") {
  const ParseOutput sut = parseText("BO_ 1 X: 8\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].transmitter.empty());
  CHECK(sut.database.messages[0].transmitters().empty());
}

TEST_CASE("parser warns when two messages share an ID") {
  const ParseOutput sut = parseText("BO_ 5 A: 8 N\nBO_ 5 B: 8 N\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "repeats ID"));
  REQUIRE(sut.database.messages.size() == 2);
  CHECK(sut.database.findMessage(5, false) == &sut.database.messages[0]);
}

// ------------------------------------------------------------------ SG_

TEST_CASE("parser reads an Intel unsigned signal with every field") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ Speed : 24|16@1+ (0.125,-10) [-10|8021.875] \"rpm\" Dash,Logger\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  const Signal& signal = sut.database.messages[0].signals[0];
  CHECK(signal.name == "Speed");
  CHECK(signal.startBit == 24);
  CHECK(signal.size == 16);
  CHECK(signal.byteOrder == ByteOrder::LittleEndian);
  CHECK_FALSE(signal.isSigned);
  CHECK(signal.valueType == ValueType::Integer);
  CHECK(signal.factor == 0.125);
  CHECK(signal.offset == -10.0);
  CHECK(signal.minimum == -10.0);
  CHECK(signal.maximum == 8021.875);
  CHECK(signal.unit == "rpm");
  CHECK(signal.receivers == std::vector<std::string>{"Dash", "Logger"});
  CHECK(signal.muxRole == MuxRole::None);
  CHECK(signal.displayName == "Speed");
  CHECK(signal.decodable());
}

TEST_CASE("parser reads a Motorola signed signal") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ Torque : 7|12@0- (0.5,0) [-1024|1023.5] \"Nm\" Vcu\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  const Signal& signal = sut.database.messages[0].signals[0];
  CHECK(signal.byteOrder == ByteOrder::BigEndian);
  CHECK(signal.isSigned);
  CHECK(signal.startBit == 7);
  CHECK(signal.size == 12);
}

TEST_CASE("parser reads signals of 1 to 64 bits as decodable") {
  std::string text = "BO_ 2147484672 Wide: 64 Vcu\n";
  constexpr std::uint32_t MAX_DECODABLE_BITS = 64;
  for (std::uint32_t size = 1; size <= MAX_DECODABLE_BITS; ++size) {
    text += " SG_ S" + std::to_string(size) + " : 0|" + std::to_string(size) + "@1+ (1,0) [0|0] \"\" Vcu\n";
  }

  const ParseOutput sut = parseText(text);

  // All start at bit 0 on purpose: the only diagnostics are the overlap warnings (#19).
  CHECK_FALSE(sut.hasErrors());
  CHECK(sut.warningCount() == diagnosticsWith(sut, Severity::Warning, "overlap").size());
  REQUIRE(sut.database.messages.size() == 1);
  const Message& message = sut.database.messages[0];
  REQUIRE(message.signals.size() == MAX_DECODABLE_BITS);
  for (std::uint32_t size = 1; size <= MAX_DECODABLE_BITS; ++size) {
    CAPTURE(size);
    CHECK(message.signals[size - 1].size == size);
    CHECK(message.signals[size - 1].decodable());
  }
}

TEST_CASE("parser loads a signal longer than 64 bits with a warning and marks it not decodable") {
  const ParseOutput sut = parseText("BO_ 2147484672 Tp: 200 Vcu\n SG_ Text : 0|1600@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "not decodable"));
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].size == 1600);
  CHECK_FALSE(sut.database.messages[0].signals[0].decodable());
}

TEST_CASE("parser reports a signal of size 0 as an error") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ Empty : 0|0@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(hasError(sut, "size 0"));
}

TEST_CASE("parser warns about a signal outside its message length") {
  const ParseOutput sut = parseText("BO_ 1 M: 2 Vcu\n SG_ Late : 56|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "lies outside the 2-byte message"));
}

TEST_CASE("parser reads comma-separated receivers with blanks around the commas") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" A , B,C  D\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].receivers == std::vector<std::string>{"A", "B", "C", "D"});
}

TEST_CASE("parser accepts tabs and runs of spaces between every SG_ field") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n\t\tSG_\tS  :  0|8@1+\t(1,0)   [0|255]  \"\"\tVcu  \n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].maximum == 255.0);
}

TEST_CASE("parser reads names that start with a digit") {
  const ParseOutput sut = parseText("BO_ 1 5_SEC_MSG: 8 Vcu\n SG_ 64_BIT_LE : 0|64@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].name == "5_SEC_MSG");
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].name == "64_BIT_LE");
}

TEST_CASE("parser reads exponents and negative factors exactly") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ Fine : 0|16@1+ (3.0517578125E-005,0) [0|2] \"\" Vcu\n"
      " SG_ Reversed : 16|16@1+ (-0.5,1E+002) [-32667.5|100] \"\" Vcu\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 2);
  CHECK(sut.database.messages[0].signals[0].factor == 3.0517578125e-5);
  CHECK(sut.database.messages[0].signals[1].factor == -0.5);
  CHECK(sut.database.messages[0].signals[1].offset == 100.0);
}

TEST_CASE("parser clamps a number beyond the double range and warns") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ Huge : 0|8@1+ (1,0) [-2.7E+4161|2.745744098767810851571364370E+4161] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(diagnosticsWith(sut, Severity::Warning, "clamped").size() == 2);
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].maximum == std::numeric_limits<double>::max());
  CHECK(sut.database.messages[0].signals[0].minimum == -std::numeric_limits<double>::max());
}

TEST_CASE("parser reads an exponent below the double range as zero with a warning") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ Tiny : 0|8@1+ (1E-400,0) [0|1] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "clamped"));
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].factor == 0.0);
}

TEST_CASE("parser keeps a message whose SG_ line is broken and reads the next signal") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ Broken : 0|8@2+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Good : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(sut.errorCount() == 1);
  REQUIRE(sut.database.messages.size() == 1);
  REQUIRE(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].signals[0].name == "Good");
}

TEST_CASE("parser warns about a signal name used twice in one message") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" Vcu\n SG_ S : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "defined twice"));
}
