// DBC grammar, part 3: the statements after the messages (CM_, BA_*, VAL_*, SIG_VALTYPE_,
// BO_TX_BU_, SIG_GROUP_, EV_, ENVVAR_DATA_).

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <string>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {
/// One node, one message, its signals side by side, one environment variable: what the
/// statements refer to.
const std::string BASE =
    "BU_: Vcu Dash\n"
    "BO_ 100 Status: 16 Vcu\n"
    " SG_ Gear : 0|8@1- (1,0) [-1|1] \"\" Dash\n"
    " SG_ Ratio : 8|32@1+ (1,0) [0|0] \"\" Dash\n"
    " SG_ Energy : 64|64@1+ (1,0) [0|0] \"\" Dash\n"
    "EV_ Counter: 0 [0|100] \"\" 5 7 DUMMY_NODE_VECTOR0 Vcu;\n";

const Signal* gearOf(const ParseOutput& output) {
  const Message* message = output.database.findMessage("Status");
  return message ? message->findSignal("Gear") : nullptr;
}
}  // namespace

// ------------------------------------------------------------------ CM_

TEST_CASE("parser attaches CM_ to the network, a node, a message, a signal and an environment variable") {
  const ParseOutput sut = parseText(BASE +
                                    "CM_ \"network\";\n"
                                    "CM_ BU_ Vcu \"node\";\n"
                                    "CM_ BO_ 100 \"message\";\n"
                                    "CM_ SG_ 100 Gear \"signal\";\n"
                                    "CM_ EV_ Counter \"variable\";\n");

  CHECK(sut.diagnostics.empty());
  CHECK(sut.database.comment == "network");
  REQUIRE(sut.database.findNode("Vcu") != nullptr);
  CHECK(sut.database.findNode("Vcu")->comment == "node");
  REQUIRE(sut.database.findMessage("Status") != nullptr);
  CHECK(sut.database.findMessage("Status")->comment == "message");
  REQUIRE(gearOf(sut) != nullptr);
  CHECK(gearOf(sut)->comment == "signal");
  REQUIRE(sut.database.environmentVariables.size() == 1);
  CHECK(sut.database.environmentVariables[0].comment == "variable");
}

TEST_CASE("parser reads a multi-line CM_ and keeps the line break") {
  const ParseOutput sut = parseText(BASE + "CM_ BO_ 100 \"first line\nsecond line\";\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.findMessage("Status") != nullptr);
  CHECK(sut.database.findMessage("Status")->comment == "first line\nsecond line");
}

TEST_CASE("parser unescapes quotes and backslashes in CM_ text") {
  const ParseOutput sut = parseText(BASE + R"(CM_ SG_ 100 Gear "the \"gear\" lever, C:\\path";)" + "\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(gearOf(sut) != nullptr);
  CHECK(gearOf(sut)->comment == R"(the "gear" lever, C:\path)");
}

TEST_CASE("parser accepts CM_ without a semicolon before the next statement with a warning") {
  const ParseOutput sut = parseText(BASE + "CM_ BO_ 100 \"no terminator\"\nBO_ 200 Next: 8 Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "CM_ statement without ';'"));
  REQUIRE(sut.database.findMessage("Status") != nullptr);
  CHECK(sut.database.findMessage("Status")->comment == "no terminator");
  CHECK(sut.database.findMessage("Next") != nullptr);
}

TEST_CASE("parser warns and ignores a CM_ for an undefined message") {
  const ParseOutput sut = parseText(BASE + "CM_ BO_ 999 \"nobody\";\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "undefined message ID 999"));
}

TEST_CASE("parser turns a malformed CM_ into a warning and keeps the file") {
  const ParseOutput sut = parseText(BASE + "CM_ BO_ 100 missing quotes;\nBO_ 200 Next: 8 Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "comment ignored"));
  CHECK(sut.database.findMessage("Next") != nullptr);
}

// ------------------------------------------------------------------ BA_DEF_, BA_DEF_DEF_, BA_

TEST_CASE("parser reads BA_DEF_ of every type with its limits and ENUM list") {
  const ParseOutput sut = parseText(
      "BA_DEF_ BO_ \"IntAttr\" INT -5 10;\n"
      "BA_DEF_ BU_ \"HexAttr\" HEX 0 255;\n"
      "BA_DEF_ SG_ \"FloatAttr\" FLOAT -0.5 1.5E3;\n"
      "BA_DEF_ \"StringAttr\" STRING ;\n"
      "BA_DEF_ EV_ \"EnumAttr\" ENUM \"Zero\",\"One\" , \"Two\";\n");

  CHECK(sut.diagnostics.empty());
  const Database& db = sut.database;
  const AttributeDefinition* intAttr = db.findAttributeDefinition("IntAttr", ObjectType::Message);
  const AttributeDefinition* hexAttr = db.findAttributeDefinition("HexAttr", ObjectType::Node);
  const AttributeDefinition* floatAttr = db.findAttributeDefinition("FloatAttr", ObjectType::Signal);
  const AttributeDefinition* stringAttr = db.findAttributeDefinition("StringAttr", ObjectType::Network);
  const AttributeDefinition* enumAttr = db.findAttributeDefinition("EnumAttr", ObjectType::EnvironmentVariable);
  REQUIRE(intAttr != nullptr);
  REQUIRE(hexAttr != nullptr);
  REQUIRE(floatAttr != nullptr);
  REQUIRE(stringAttr != nullptr);
  REQUIRE(enumAttr != nullptr);
  CHECK(intAttr->type == AttributeType::Int);
  CHECK(intAttr->minimum == -5.0);
  CHECK(intAttr->maximum == 10.0);
  CHECK(hexAttr->type == AttributeType::Hex);
  CHECK(hexAttr->maximum == 255.0);
  CHECK(floatAttr->type == AttributeType::Float);
  CHECK(floatAttr->maximum == 1500.0);
  CHECK(stringAttr->type == AttributeType::String);
  CHECK(enumAttr->type == AttributeType::Enum);
  CHECK(enumAttr->enumValues == std::vector<std::string>{"Zero", "One", "Two"});
  CHECK(db.findAttributeDefinition("IntAttr", ObjectType::Signal) == nullptr);
}

TEST_CASE("parser reads an unknown attribute type as STRING with a warning") {
  const ParseOutput sut = parseText("BA_DEF_ SG_ \"Flag\" BOOL 0 1;\nBU_: Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "unknown type 'BOOL'"));
  const AttributeDefinition* flag = sut.database.findAttributeDefinition("Flag", ObjectType::Signal);
  REQUIRE(flag != nullptr);
  CHECK(flag->type == AttributeType::String);
  CHECK(sut.database.nodes.size() == 1);
}

TEST_CASE("parser stores BA_DEF_DEF_ as the definition's default") {
  const ParseOutput sut = parseText("BA_DEF_ BO_ \"Cycle\" INT 0 1000;\nBA_DEF_DEF_ \"Cycle\" 100;\n" + BASE);

  CHECK(sut.diagnostics.empty());
  const AttributeDefinition* cycle = sut.database.findAttributeDefinition("Cycle", ObjectType::Message);
  REQUIRE(cycle != nullptr);
  REQUIRE(cycle->defaultValue.has_value());
  CHECK(*cycle->defaultValue == AttributeValue::fromNumber(100));
  const Message* status = sut.database.findMessage("Status");
  REQUIRE(status != nullptr);
  CHECK(status->attributes.empty());
  CHECK(sut.database.attribute(status->attributes, "Cycle", ObjectType::Message) == AttributeValue::fromNumber(100));
}

TEST_CASE("parser warns about BA_DEF_DEF_ for an undefined attribute") {
  const ParseOutput sut = parseText("BA_DEF_DEF_ \"Nothing\" 1;\n");

  CHECK(hasWarning(sut, "undefined attribute 'Nothing'"));
}

TEST_CASE("parser attaches BA_ values to the network, a node, a message, a signal and an environment variable") {
  const ParseOutput sut = parseText(BASE +
                                    "BA_DEF_ \"Bus\" STRING;\n"
                                    "BA_DEF_ BU_ \"Address\" HEX 0 255;\n"
                                    "BA_DEF_ BO_ \"Cycle\" INT 0 1000;\n"
                                    "BA_DEF_ SG_ \"Start\" FLOAT -10 10;\n"
                                    "BA_DEF_ EV_ \"Level\" ENUM \"Low\",\"High\";\n"
                                    "BA_ \"Bus\" \"Vehicle\";\n"
                                    "BA_ \"Address\" BU_ Vcu 0x21;\n"
                                    "BA_ \"Cycle\" BO_ 100 20;\n"
                                    "BA_ \"Start\" SG_ 100 Gear -1.5;\n"
                                    "BA_ \"Level\" EV_ Counter 1;\n");

  INFO(describe(sut));
  CHECK(sut.diagnostics.empty());
  const Database& db = sut.database;
  CHECK(db.networkAttributes.at("Bus") == AttributeValue::fromString("Vehicle"));
  REQUIRE(db.findNode("Vcu") != nullptr);
  CHECK(db.findNode("Vcu")->attributes.at("Address") == AttributeValue::fromNumber(0x21));
  REQUIRE(db.findMessage("Status") != nullptr);
  CHECK(db.findMessage("Status")->attributes.at("Cycle") == AttributeValue::fromNumber(20));
  REQUIRE(gearOf(sut) != nullptr);
  CHECK(gearOf(sut)->attributes.at("Start") == AttributeValue::fromNumber(-1.5));
  REQUIRE(db.environmentVariables.size() == 1);
  const EnvironmentVariable& counter = db.environmentVariables[0];
  CHECK(counter.attributes.at("Level") == AttributeValue::fromNumber(1));
  CHECK(db.attributeText(counter.attributes, "Level", ObjectType::EnvironmentVariable) == "High");
}

TEST_CASE("parser keeps a BA_ value for an undefined attribute with a warning") {
  const ParseOutput sut = parseText(BASE + "BA_ \"Unknown\" BO_ 100 7;\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "undefined attribute 'Unknown'"));
  REQUIRE(sut.database.findMessage("Status") != nullptr);
  CHECK(sut.database.findMessage("Status")->attributes.count("Unknown") == 1);
}

TEST_CASE("parser warns when a BA_ value has the wrong kind or an ENUM index out of its list") {
  const ParseOutput sut = parseText(BASE +
                                    "BA_DEF_ BO_ \"Cycle\" INT 0 1000;\n"
                                    "BA_DEF_ BO_ \"Kind\" ENUM \"A\",\"B\";\n"
                                    "BA_ \"Cycle\" BO_ 100 \"fast\";\n"
                                    "BA_ \"Kind\" BO_ 100 5;\n");

  CHECK(hasWarning(sut, "expects a number"));
  CHECK(hasWarning(sut, "not an index of its ENUM list"));
}

TEST_CASE("parser reads BA_DEF_REL_, BA_DEF_DEF_REL_ and BA_REL_ for signal, message and variable relations") {
  const ParseOutput sut = parseText(BASE +
                                    "BA_DEF_REL_ BU_SG_REL_ \"SigTimeout\" INT 0 65535;\n"
                                    "BA_DEF_REL_ BU_BO_REL_ \"MsgTimeout\" INT 0 65535;\n"
                                    "BA_DEF_REL_ BU_EV_REL_ \"EvAccess\" STRING ;\n"
                                    "BA_DEF_DEF_REL_ \"SigTimeout\" 50;\n"
                                    "BA_REL_ \"SigTimeout\" BU_SG_REL_ Dash SG_ 100 Gear 100;\n"
                                    "BA_REL_ \"MsgTimeout\" BU_BO_REL_ Dash 100 250;\n"
                                    "BA_REL_ \"EvAccess\" BU_EV_REL_ Vcu Counter \"rw\";\n");

  CHECK(sut.diagnostics.empty());
  const Database& db = sut.database;
  const AttributeDefinition* sigTimeout = db.findAttributeDefinition("SigTimeout", ObjectType::NodeSignalRelation);
  REQUIRE(sigTimeout != nullptr);
  REQUIRE(sigTimeout->defaultValue.has_value());
  CHECK(*sigTimeout->defaultValue == AttributeValue::fromNumber(50));
  CHECK(db.findAttributeDefinition("MsgTimeout", ObjectType::NodeMessageRelation) != nullptr);
  CHECK(db.findAttributeDefinition("EvAccess", ObjectType::NodeEnvRelation) != nullptr);
  REQUIRE(db.relationAttributes.size() == 3);
  const RelationAttribute& signalRelation = db.relationAttributes[0];
  CHECK(std::string(toString(signalRelation.relation)) == "BU_SG_REL_");
  CHECK(signalRelation.node == "Dash");
  CHECK(signalRelation.messageId == 100);
  CHECK(signalRelation.target == "Gear");
  CHECK(signalRelation.value == AttributeValue::fromNumber(100));
  CHECK(std::string(toString(db.relationAttributes[1].relation)) == "BU_BO_REL_");
  CHECK(db.relationAttributes[1].value == AttributeValue::fromNumber(250));
  CHECK(db.relationAttributes[2].target == "Counter");
  CHECK(db.relationAttributes[2].value == AttributeValue::fromString("rw"));
}

TEST_CASE("parser rejects BA_DEF_REL_ with a plain object type") {
  const ParseOutput sut = parseText("BA_DEF_REL_ BO_ \"X\" INT 0 1;\n");

  CHECK(hasError(sut, "expected BU_SG_REL_, BU_BO_REL_ or BU_EV_REL_"));
}

// ------------------------------------------------------------------ VAL_, VAL_TABLE_

TEST_CASE("parser reads VAL_ with negative keys for a signal") {
  const ParseOutput sut = parseText(BASE + "VAL_ 100 Gear -1 \"Reverse\" 0 \"Neutral\" 1 \"Drive\" ;\n");

  CHECK(sut.diagnostics.empty());
  const Signal* gear = gearOf(sut);
  REQUIRE(gear != nullptr);
  REQUIRE(gear->valueDescriptions.size() == 3);
  CHECK(gear->valueDescriptions[0] == ValueDescription{-1, "Reverse"});
  REQUIRE(gear->describe(-1) != nullptr);
  CHECK(*gear->describe(-1) == "Reverse");
  CHECK(gear->describe(2) == nullptr);
}

TEST_CASE("parser reads VAL_ for an environment variable") {
  const ParseOutput sut = parseText(BASE + "VAL_ Counter 0 \"Empty\" 100 \"Full\";\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.environmentVariables.size() == 1);
  CHECK(sut.database.environmentVariables[0].valueDescriptions.size() == 2);
}

TEST_CASE("parser accepts VAL_ without a semicolon before the next statement with a warning") {
  const ParseOutput sut = parseText(BASE + "VAL_ 100 Gear 0 \"Neutral\" 1 \"Drive\"\nVAL_TABLE_ T 1 \"x\";\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "VAL_ statement without ';'"));
  REQUIRE(gearOf(sut) != nullptr);
  CHECK(gearOf(sut)->valueDescriptions.size() == 2);
  CHECK(sut.database.valueTables.size() == 1);
}

TEST_CASE("parser rejects a VAL_ key that is not an integer") {
  const ParseOutput sut = parseText(BASE + "VAL_ 100 Gear 0.5 \"half\";\n");

  CHECK(hasError(sut, "must be an integer"));
}

TEST_CASE("parser reads VAL_TABLE_ entries in file order") {
  const ParseOutput sut = parseText("VAL_TABLE_ Direction -1 \"Reverse\" 0 \"Neutral\" 1 \"Drive\" ;\nVAL_TABLE_ Empty ;\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.valueTables.size() == 2);
  CHECK(sut.database.valueTables[0].name == "Direction");
  CHECK(sut.database.valueTables[0].values ==
        std::vector<ValueDescription>{{-1, "Reverse"}, {0, "Neutral"}, {1, "Drive"}});
  CHECK(sut.database.valueTables[1].values.empty());
}

// ------------------------------------------------------------------ SIG_VALTYPE_, BO_TX_BU_, SIG_GROUP_

TEST_CASE("parser reads SIG_VALTYPE_ 1 as float32 and 2 as float64") {
  const ParseOutput sut = parseText(BASE + "SIG_VALTYPE_ 100 Ratio : 1;\nSIG_VALTYPE_ 100 Energy : 2;\n");

  CHECK(sut.diagnostics.empty());
  const Message* status = sut.database.findMessage("Status");
  REQUIRE(status != nullptr);
  REQUIRE(status->findSignal("Ratio") != nullptr);
  REQUIRE(status->findSignal("Energy") != nullptr);
  CHECK(status->findSignal("Ratio")->valueType == ValueType::Float32);
  CHECK(status->findSignal("Energy")->valueType == ValueType::Float64);
  CHECK(status->findSignal("Ratio")->decodable());
  CHECK(status->findSignal("Energy")->decodable());
}

TEST_CASE("parser warns when SIG_VALTYPE_ does not match the signal size") {
  const ParseOutput sut = parseText(BASE + "SIG_VALTYPE_ 100 Gear : 1;\n");

  CHECK(hasWarning(sut, "needs 32"));
  REQUIRE(gearOf(sut) != nullptr);
  CHECK_FALSE(gearOf(sut)->decodable());
}

TEST_CASE("parser rejects SIG_VALTYPE_ other than 0, 1 or 2") {
  const ParseOutput sut = parseText(BASE + "SIG_VALTYPE_ 100 Gear : 3;\n");

  CHECK(hasError(sut, "SIG_VALTYPE_ must be 0"));
}

TEST_CASE("parser adds BO_TX_BU_ nodes after the BO_ transmitter") {
  const ParseOutput sut = parseText(BASE + "BO_TX_BU_ 100 : Dash,Vcu , Logger;\n");

  CHECK(sut.diagnostics.empty());
  const Message* status = sut.database.findMessage("Status");
  REQUIRE(status != nullptr);
  CHECK(status->extraTransmitters == std::vector<std::string>{"Dash", "Vcu", "Logger"});
  CHECK(status->transmitters() == std::vector<std::string>{"Vcu", "Dash", "Logger"});
}

TEST_CASE("parser reads SIG_GROUP_ with its signals") {
  const ParseOutput sut = parseText(BASE + "SIG_GROUP_ 100 Drive 1 : Gear Ratio;\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.signalGroups.size() == 1);
  const SignalGroup& group = sut.database.signalGroups[0];
  CHECK(group.messageId == 100);
  CHECK(group.name == "Drive");
  CHECK(group.repetitions == 1);
  CHECK(group.signals == std::vector<std::string>{"Gear", "Ratio"});
}

// ------------------------------------------------------------------ EV_, ENVVAR_DATA_

TEST_CASE("parser reads EV_ with every field and ENVVAR_DATA_") {
  const ParseOutput sut = parseText(
      "BU_: Vcu Dash\n"
      "EV_ Label: 2 [0|10.5] \"m\" 1.5 7 DUMMY_NODE_VECTOR8000 Vcu,Dash;\n"
      "ENVVAR_DATA_ Label: 16;\n");

  CHECK(sut.diagnostics.empty());
  REQUIRE(sut.database.environmentVariables.size() == 1);
  const EnvironmentVariable& label = sut.database.environmentVariables[0];
  CHECK(label.name == "Label");
  CHECK(label.type == 2);
  CHECK(label.minimum == 0.0);
  CHECK(label.maximum == 10.5);
  CHECK(label.unit == "m");
  CHECK(label.initialValue == 1.5);
  CHECK(label.id == 7);
  CHECK(label.accessType == "DUMMY_NODE_VECTOR8000");
  CHECK(label.accessNodes == std::vector<std::string>{"Vcu", "Dash"});
  REQUIRE(label.dataSize.has_value());
  CHECK(*label.dataSize == 16);
}

TEST_CASE("parser accepts EV_ without a semicolon before the next statement with a warning") {
  const ParseOutput sut = parseText(
      "BU_: Vcu\n"
      "EV_ Label: 0 [0|1] \"\" 0 7 DUMMY_NODE_VECTOR0 Vcu\n"
      "BO_ 1 M: 8 Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "EV_ statement without ';'"));
  REQUIRE(sut.database.environmentVariables.size() == 1);
  CHECK(sut.database.environmentVariables[0].accessNodes == std::vector<std::string>{"Vcu"});
  CHECK(sut.database.messages.size() == 1);
}

TEST_CASE("parser warns about ENVVAR_DATA_ for an undefined variable") {
  const ParseOutput sut = parseText("ENVVAR_DATA_ Nothing: 4;\n");

  CHECK(hasWarning(sut, "undefined environment variable 'Nothing'"));
}

TEST_CASE("parser skips statements openvcu does not use with a warning") {
  const ParseOutput sut = parseText("BU_: Vcu\nSGTYPE_ T : 8@1+ (1,0) [0|0] \"\" 0 ;\nCAT_DEF_ 1 C 0 ;\nBO_ 1 M: 8 Vcu\n");

  CHECK_FALSE(sut.hasErrors());
  CHECK(hasWarning(sut, "SGTYPE_ statement is not used"));
  CHECK(hasWarning(sut, "CAT_DEF_ statement is not used"));
  CHECK(sut.database.messages.size() == 1);
}
