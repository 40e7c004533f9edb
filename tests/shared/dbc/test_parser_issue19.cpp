// Issue 19: DBC input that used to be silently lost or accepted. One test per class, every
// input made here: unterminated strings and comments, line-end conventions, overlapping
// signals, duplicate message names, the multiplexor limit, attributes redefined with
// another type, and files that are not regular files.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "../core/pending_signal.hpp"
#include "../core/temp_folder.hpp"
#include "openvcu/dbc/codec.hpp"

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {

/// A message with a cycle time and value descriptions given after a CM_ on line 5.
std::string fileWithComment(std::string_view commentLine) {
  return std::string("BU_: Vcu\n"
                     "BO_ 100 Status: 8 Vcu\n"
                     " SG_ Mode : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
                     "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n") +
         std::string(commentLine) +
         "\n"
         "BA_ \"GenMsgCycleTime\" BO_ 100 20;\n"
         "VAL_ 100 Mode 0 \"Off\" 1 \"On\";\n";
}

std::vector<std::string> errorsOf(const ParseOutput& output) {
  std::vector<std::string> errors;
  for (const Error& diagnostic : output.diagnostics) {
    if (diagnostic.severity == Severity::Error) errors.push_back(diagnostic.toString());
  }
  return errors;
}

/// Overlap warnings only.
std::vector<std::string> overlapsOf(const ParseOutput& output) {
  std::vector<std::string> found;
  for (const Error& diagnostic : diagnosticsWith(output, Severity::Warning, "overlap")) {
    found.push_back(diagnostic.toString());
  }
  return found;
}

}  // namespace

// ------------------------------------------------------------------ scanner

TEST_CASE("a CM_ string left open is an error at its opening quote and the statements after it still apply (#19)") {
  const ParseOutput sut = parseText(fileWithComment("CM_ BO_ 100 \"cut here"));

  INFO(describe(sut));
  CHECK(errorsOf(sut) == std::vector<std::string>{"test.dbc:5:13: string not closed before line 6, which starts a BA_ statement"});
  const Message* status = sut.database.findMessage("Status");
  REQUIRE(status != nullptr);
  CHECK(status->cycleTimeMs == 20);
  CHECK(status->signals[0].valueDescriptions.size() == 2);
}

TEST_CASE("a multi-line CM_ string whose lines are not statements is still one comment") {
  const ParseOutput sut = parseText(fileWithComment("CM_ BO_ 100 \"first line\n  BO_gus is not a keyword\nlast\";"));

  INFO(describe(sut));
  CHECK(errorsOf(sut).empty());
  REQUIRE(sut.database.findMessage("Status") != nullptr);
  CHECK(sut.database.findMessage("Status")->comment == "first line\n  BO_gus is not a keyword\nlast");
}

TEST_CASE("a string still open at the end of the file is an error at its opening line (#19)") {
  const ParseOutput sut = parseText("BU_: Vcu\nBO_ 100 Status: 8 Vcu\nCM_ BO_ 100 \"cut at the end");

  CHECK(errorsOf(sut) == std::vector<std::string>{"test.dbc:3:13: string never closed"});
}

TEST_CASE("a stray /* is an error on its own line and the messages after it are still read (#19)") {
  const ParseOutput sut = parseText("BU_: Vcu\n"
                                    "BO_ 100 First: 8 Vcu\n"
                                    " SG_ A : 0|8@1+ (1,0) [0|0] \"\" Vcu /* stray\n"
                                    "BO_ 200 Second: 8 Vcu\n"
                                    " SG_ B : 0|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(errorsOf(sut) == std::vector<std::string>{"test.dbc:3:36: comment '/*' never closed"});
  CHECK(sut.database.findMessage("Second") != nullptr);
}

TEST_CASE("CR-only, CRLF and LF files read alike, with the same line numbers (#19)") {
  const std::string lf = "BU_: Vcu\n"
                         "BO_ 100 Status: 8 Vcu\n"
                         " SG_ Mode : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
                         "CM_ SG_ 100 Mode \"two\nlines\";\n"
                         "BO_ 200 Broken: x Vcu\n";
  std::string cr = lf;
  std::string crlf;
  for (char& c : cr) c = c == '\n' ? '\r' : c;
  for (const char c : lf) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);

  for (const std::string& text : {lf, cr, crlf}) {
    const ParseOutput sut = parseText(text);
    INFO(describe(sut));
    REQUIRE(sut.database.messages.size() == 1);
    CHECK(sut.database.messages[0].signals.size() == 1);
    CHECK(sut.database.messages[0].signals[0].comment == "two\nlines");
    CHECK(errorsOf(sut) == std::vector<std::string>{"test.dbc:6:17: expected message length, found 'x'"});
  }
}

// ------------------------------------------------------------------ checks

TEST_CASE("overlapping signals are a warning at the later one unless multiplexing keeps them apart (#19)") {
  const ParseOutput sut = parseText("BU_: Vcu\n"
                                    "BO_ 100 Plain: 8 Vcu\n"
                                    " SG_ Word : 0|16@1+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ High : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ Motorola : 23|8@0+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ Beside : 24|8@1+ (1,0) [0|0] \"\" Vcu\n"
                                    "BO_ 200 Muxed: 8 Vcu\n"
                                    " SG_ Selector M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ PageOne m1 : 8|16@1+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ PageTwo m2 : 8|16@1+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ AlsoOne m1 : 16|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(overlapsOf(sut) ==
        std::vector<std::string>{
            "test.dbc:4:2: warning: signals 'Word' and 'High' of message 'Plain' overlap (bit 8) and can be present "
            "together; encoding one changes the other",
            "test.dbc:11:2: warning: signals 'PageOne' and 'AlsoOne' of message 'Muxed' overlap (bit 16) and can be "
            "present together; encoding one changes the other"});
  CHECK_FALSE(sut.hasErrors());
}

TEST_CASE("a Motorola and an Intel signal on the same bits overlap") {
  const ParseOutput sut = parseText("BO_ 100 Mixed: 8 Vcu\n"
                                    " SG_ Big : 7|12@0+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ Little : 8|4@1+ (1,0) [0|0] \"\" Vcu\n");

  // Big: bits 7..0 of byte 0, then 7..4 of byte 1 (LSB0 12..15); Little: 8..11.
  CHECK(overlapsOf(sut).empty());
  const ParseOutput touching = parseText("BO_ 100 Mixed: 8 Vcu\n"
                                         " SG_ Big : 7|12@0+ (1,0) [0|0] \"\" Vcu\n"
                                         " SG_ Little : 12|4@1+ (1,0) [0|0] \"\" Vcu\n");
  CHECK(overlapsOf(touching).size() == 1);
}

TEST_CASE("two messages of one name are an error naming both (#19)") {
  const ParseOutput sut = parseText("BU_: Vcu\n"
                                    "BO_ 100 Status: 8 Vcu\n"
                                    " SG_ A : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
                                    "BO_ 200 Status: 8 Vcu\n"
                                    " SG_ B : 0|8@1+ (1,0) [0|0] \"\" Vcu\n");

  CHECK(errorsOf(sut) ==
        std::vector<std::string>{"test.dbc:4:1: message name 'Status' is used twice (ID 0xC8 here, ID 0x64 at line 2)"});
}

TEST_CASE("more multiplexors in one message than the codec can decode is a warning (#19)") {
  // Extended multiplexing: a root selector and 33 nested selectors each choosing one signal.
  constexpr int NESTED = static_cast<int>(MessageCodec::MAX_MUX_SLOTS);  // + the root = 33
  std::string text = "BO_ 2566844926 Deep: 64 Vcu\n SG_ Root M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n";
  std::string muxValues;
  for (int i = 0; i < NESTED; ++i) {
    const std::string selector = "Sel" + std::to_string(i);
    const std::string value = "Val" + std::to_string(i);
    text += " SG_ " + selector + " m" + std::to_string(i) + "M : " + std::to_string(8 + i * 8) + "|4@1+ (1,0) [0|0] \"\" Vcu\n";
    text += " SG_ " + value + " m1 : " + std::to_string(12 + i * 8) + "|4@1+ (1,0) [0|0] \"\" Vcu\n";
    muxValues += "SG_MUL_VAL_ 2566844926 " + selector + " Root " + std::to_string(i) + "-" + std::to_string(i) + ";\n";
    muxValues += "SG_MUL_VAL_ 2566844926 " + value + " " + selector + " 1-1;\n";
  }
  const ParseOutput sut = parseText(text + muxValues);

  INFO(describe(sut));
  CHECK(hasWarning(sut, "message 'Deep' has 33 multiplexors; only the signals of 32 of them can be decoded"));
  CHECK(overlapsOf(sut).empty());
  const ParseOutput withinLimit = parseText("BO_ 1 Small: 8 Vcu\n SG_ Root M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
                                            " SG_ A m1 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");
  CHECK_FALSE(hasWarning(withinLimit, "multiplexors"));
}

TEST_CASE("an extended multiplexed signal with 40 value ranges decodes at each of them") {
  std::string ranges;
  for (int value = 0; value < 80; value += 2) ranges += std::string(ranges.empty() ? "" : ", ") + std::to_string(value) + "-" + std::to_string(value);
  const ParseOutput sut = parseText("BO_ 100 Paged: 8 Vcu\n SG_ Page M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
                                    " SG_ Even m0 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n"
                                    "SG_MUL_VAL_ 100 Even Page " + ranges + ";\n");
  INFO(describe(sut));
  REQUIRE_FALSE(sut.hasErrors());
  const MessageCodec codec = MessageCodec::compile(sut.database, sut.database.messages[0]);

  for (std::uint8_t page = 0; page < 80; ++page) {
    const std::uint8_t payload[8] = {page, 0x5A, 0, 0, 0, 0, 0, 0};
    const std::vector<Visited> visited = decodeAll(codec, payload);
    CHECK(visited.size() == (page % 2 == 0 ? 2u : 1u));
  }
}

TEST_CASE("an attribute defined again with another type is an error, the same definition twice is not (#19)") {
  const ParseOutput sut = parseText("BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 65535;\n"
                                    "BA_DEF_ BO_ \"GenMsgCycleTime\" FLOAT 0 65535;\n"
                                    "BA_DEF_ SG_ \"GenSigStartValue\" INT 0 100;\n"
                                    "BA_DEF_ SG_ \"GenSigStartValue\" INT 0 100;\n"
                                    "BA_DEF_ \"BusType\" ENUM \"CAN\",\"CAN FD\";\n"
                                    "BA_DEF_ \"BusType\" ENUM \"CAN FD\",\"CAN\";\n");

  CHECK(errorsOf(sut) == std::vector<std::string>{
                             "test.dbc:2: attribute 'GenMsgCycleTime' (BO_) defined again with another type (first at line 1)",
                             "test.dbc:6: attribute 'BusType' (network) defined again with another ENUM list (first at line 5)"});
}

// ------------------------------------------------------------------ files

TEST_CASE("loadFile refuses a directory and /dev/zero at once, naming what they are (#19)") {
  const openvcu::test::TempFolder folder;
  const auto started = std::chrono::steady_clock::now();

  const Result<Database> directory = loadFile(folder.path(""));
  const Result<Database> zero = loadFile("/dev/zero");

  REQUIRE_FALSE(directory.ok());
  CHECK(directory.error().toString() == folder.path("") + ": not a regular file (directory)");
  REQUIRE_FALSE(zero.ok());
  CHECK(zero.error().toString() == "/dev/zero: not a regular file (character device)");
  CHECK(std::chrono::steady_clock::now() - started < std::chrono::seconds(1));
}

TEST_CASE("a pending SIGTERM ends the parse of a long file with an error, so a loading service stops (#19)") {
  constexpr int MESSAGES = 20000;  // several stop checks' worth of statements
  std::string text = "BU_: Vcu\n";
  for (int i = 1; i <= MESSAGES; ++i) text += "BO_ " + std::to_string(i) + " M" + std::to_string(i) + ": 8 Vcu\n";
  const openvcu::test::PendingSigterm pending;

  const ParseOutput sut = parseText(text);

  CHECK(hasError(sut, "reading stopped: SIGTERM or SIGINT is pending"));
  CHECK(sut.database.messages.size() < static_cast<std::size_t>(MESSAGES));
}

TEST_CASE("a diagnostic quoting a name with a NUL or newline from the file stays one line (#19)") {
  const ParseOutput sut = parseText(std::string("BA_ \"Bad\nName\0X\" 1;\n", 20));

  REQUIRE_FALSE(sut.diagnostics.empty());
  for (const Error& diagnostic : sut.diagnostics) {
    CHECK(diagnostic.message.find('\n') == std::string::npos);
    CHECK(diagnostic.message.find('\0') == std::string::npos);
  }
  CHECK(hasWarning(sut, "undefined attribute 'Bad\\nName\\0X'"));
}
