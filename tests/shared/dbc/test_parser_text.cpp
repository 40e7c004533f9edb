// DBC text level: comments, line endings, encodings, missing final newline.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <string>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {
const Signal* firstSignal(const ParseOutput& output) {
  if (output.database.messages.empty() || output.database.messages[0].signals.empty()) return nullptr;
  return &output.database.messages[0].signals[0];
}
}  // namespace

// ------------------------------------------------------------------ comments

TEST_CASE("parser skips // line comments between and after statements") {
  const ParseOutput sut = parseText(
      "// leading comment\n"
      "BU_: Vcu // trailing comment\n"
      "BO_ 1 M: 8 Vcu // after a message\n"
      " SG_ S : 0|8@1+ (1,0) [0|0] \"\" Vcu // after a signal\n"
      "// between\n"
      "CM_ BO_ 1 \"text\"; // after a comment statement\n");

  INFO(describe(sut));
  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.nodes.size() == 1);
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].signals.size() == 1);
  CHECK(sut.database.messages[0].comment == "text");
}

TEST_CASE("parser skips /* */ block comments across lines") {
  const ParseOutput sut = parseText(
      "/* a block\n"
      "   over lines BO_ 9 Hidden: 8 Vcu */\n"
      "BO_ 1 M: 8 /* inline */ Vcu\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].transmitter == "Vcu");
  CHECK(sut.database.findMessage("Hidden") == nullptr);
}

TEST_CASE("parser keeps comment markers inside strings") {
  const ParseOutput sut = parseText(
      "BO_ 1 M: 8 Vcu\n"
      " SG_ S : 0|8@1+ (1,0) [0|0] \"u//nit\" Vcu\n"
      "CM_ BO_ 1 \"see http://example.org /* not a comment */\";\n");

  CHECK(sut.diagnostics.empty());
  const Signal* signal = firstSignal(sut);
  REQUIRE(signal != nullptr);
  CHECK(signal->unit == "u//nit");
  CHECK(sut.database.messages[0].comment == "see http://example.org /* not a comment */");
}

TEST_CASE("parser reports an unterminated block comment at its line and reads on after it (#19)") {
  const ParseOutput sut = parseText("BU_: Vcu\n/* never closed\nBO_ 1 M: 8 Vcu\n");

  const std::vector<Error> errors = diagnosticsWith(sut, Severity::Error, "never closed");
  REQUIRE(errors.size() == 1);
  CHECK(errors[0].toString() == "test.dbc:2:1: comment '/*' never closed");
  CHECK(sut.database.messages.size() == 1);
}

// ------------------------------------------------------------------ line endings

TEST_CASE("parser reads CRLF line endings and drops the CR from multi-line strings") {
  const ParseOutput sut = parseText(
      "BU_: Vcu\r\n"
      "BO_ 1 M: 8 Vcu\r\n"
      " SG_ S : 0|8@1+ (1,0) [0|0] \"\" Vcu\r\n"
      " SG_ T : 8|8@1+ (1,0) [0|0] \"\" Vcu\r\n"
      "\r\n"
      "CM_ BO_ 1 \"one\r\ntwo\";\r\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.messages.size() == 1);
  CHECK(sut.database.messages[0].signals.size() == 2);
  CHECK(sut.database.messages[0].comment == "one\ntwo");
}

TEST_CASE("parser reads the CRLF fixture without a final newline") {
  const ParseOutput sut = parse(readFixture("crlf_no_final_newline.dbc"), "crlf_no_final_newline.dbc");

  INFO(describe(sut));
  CHECK(sut.diagnostics.empty());
  const Message* dash = sut.database.findMessage("Dash");
  REQUIRE(dash != nullptr);
  CHECK(dash->signals.size() == 2);
  CHECK(dash->comment == "Two lines\nin a CRLF file");
  const Signal* lamp = dash->findSignal("Lamp");
  REQUIRE(lamp != nullptr);
  CHECK(lamp->valueDescriptions.size() == 2);
}

TEST_CASE("parser reads a last statement without a final newline") {
  const ParseOutput withSignal = parseText("BO_ 1 M: 8 Vcu\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" Vcu");
  const ParseOutput withValues = parseText("BO_ 1 M: 8 Vcu\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" Vcu\nVAL_ 1 S 0 \"a\";");

  CHECK(withSignal.diagnostics.empty());
  const Signal* signal = firstSignal(withSignal);
  REQUIRE(signal != nullptr);
  CHECK(signal->receivers == std::vector<std::string>{"Vcu"});
  CHECK(withValues.diagnostics.empty());
  const Signal* described = firstSignal(withValues);
  REQUIRE(described != nullptr);
  CHECK(described->valueDescriptions.size() == 1);
}

TEST_CASE("parser accepts a VAL_ without a semicolon at the very end of the file with a warning") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" Vcu\nVAL_ 1 S 0 \"a\"");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "without ';'"));
  const Signal* signal = firstSignal(sut);
  REQUIRE(signal != nullptr);
  CHECK(signal->valueDescriptions.size() == 1);
}

// ------------------------------------------------------------------ encodings

TEST_CASE("parser reports plain ASCII text as ascii") {
  const ParseOutput sut = parseText("BU_: Vcu\n");

  CHECK(sut.database.sourceEncoding == "ascii");
}

TEST_CASE("parser keeps UTF-8 text as it is") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ T : 0|8@1+ (1,0) [0|0] \"\xC2\xB0" "C\" Vcu\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.sourceEncoding == "utf-8");
  const Signal* signal = firstSignal(sut);
  REQUIRE(signal != nullptr);
  CHECK(signal->unit == "\xC2\xB0" "C");
}

TEST_CASE("parser converts CP1252 text to UTF-8 and says so") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 Vcu\n SG_ T : 0|8@1+ (1,0) [0|0] \"\xB0" "C\" Vcu\nCM_ BO_ 1 \"\x80 \x96 f\xFCr\";\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.sourceEncoding == "cp1252");
  const Signal* signal = firstSignal(sut);
  REQUIRE(signal != nullptr);
  CHECK(signal->unit == "\xC2\xB0" "C");                                        // degree sign
  CHECK(sut.database.messages[0].comment == "\xE2\x82\xAC \xE2\x80\x93 f\xC3\xBCr");  // euro, en dash, u-umlaut
}

TEST_CASE("parser reads the CP1252 fixture as UTF-8") {
  const ParseOutput sut = parse(readFixture("cp1252_units.dbc"), "cp1252_units.dbc");

  INFO(describe(sut));
  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.sourceEncoding == "cp1252");
  const Message* climate = sut.database.findMessage("Climate");
  REQUIRE(climate != nullptr);
  const Signal* cost = climate->findSignal("Cost");
  REQUIRE(cost != nullptr);
  CHECK(cost->unit == "\xE2\x82\xAC/kWh");
}

TEST_CASE("parser reads the UTF-8 fixture unchanged") {
  const ParseOutput sut = parse(readFixture("utf8_units.dbc"), "utf8_units.dbc");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.sourceEncoding == "utf-8");
  const Message* motor = sut.database.findMessage("Motor");
  REQUIRE(motor != nullptr);
  const Signal* angle = motor->findSignal("Angle");
  REQUIRE(angle != nullptr);
  CHECK(angle->unit == "\xC2\xB0");
}

TEST_CASE("parser skips a UTF-8 byte order mark") {
  const ParseOutput sut = parseText("\xEF\xBB\xBF" "VERSION \"bom\"\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.version == "bom");
}

// ------------------------------------------------------------------ fixtures

TEST_CASE("parser reads the full grammar fixture without diagnostics") {
  const ParseOutput sut = parse(readFixture("grammar_all_statements.dbc"), "grammar_all_statements.dbc");

  INFO(describe(sut));
  CHECK(sut.diagnostics.empty());
  const Database& db = sut.database;
  CHECK(db.version == "openvcu grammar fixture 1.0");
  CHECK(db.newSymbols.size() == 28);
  CHECK(db.nodes.size() == 5);
  CHECK(db.valueTables.size() == 2);
  CHECK(db.messages.size() == 4);
  CHECK(db.environmentVariables.size() == 2);
  CHECK(db.signalGroups.size() == 1);
  CHECK(db.attributeDefinitions.size() == 8);
  CHECK(db.relationAttributes.size() == 2);
  const Message* battery = db.findMessage("BatteryStatus");
  REQUIRE(battery != nullptr);
  CHECK(battery->isJ1939());
  const Message* status = db.findMessage("VcuStatus");
  REQUIRE(status != nullptr);
  CHECK(status->cycleTimeMs == 10u);
  CHECK(status->transmitters() == std::vector<std::string>{"Vcu", "Charger"});
}

TEST_CASE("parser reads the issue #2 odd-case fixture with warnings only") {
  const ParseOutput sut = parse(readFixture("issue_2_odd_cases.dbc"), "issue_2_odd_cases.dbc");

  INFO(describe(sut));
  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "bit 29 or 30"));
  CHECK(hasWarning(sut, "clamped"));
  CHECK(hasWarning(sut, "72 bits"));
  CHECK(hasWarning(sut, "CM_ statement without ';'"));
  CHECK(hasWarning(sut, "VAL_ statement without ';'"));
  CHECK(hasWarning(sut, "unknown type 'BOOL'"));
  const Database& db = sut.database;
  const Message* first = db.findMessage("First");
  REQUIRE(first != nullptr);
  CHECK(first->signals.size() == 3);
  CHECK(first->comment == "A comment /* with */ comment markers // inside");
  const Signal* spaced = first->findSignal("Spaced");
  REQUIRE(spaced != nullptr);
  CHECK(spaced->receivers == std::vector<std::string>{"Sensor_1", "64_NODE"});
  CHECK(spaced->valueDescriptions.size() == 3);
  const Message* noFlag = db.findMessage("NoFlagExtended");
  REQUIRE(noFlag != nullptr);
  CHECK(noFlag->extended);
  CHECK_FALSE(noFlag->cycleTimeMs.has_value());
  CHECK(first->cycleTimeMs == 100u);
}
