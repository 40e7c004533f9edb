// Malformed input: every problem is reported as "file:line:col: reason" at the right place,
// and no input (truncated fixtures, random mutations) crashes or hangs the parser.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {

constexpr std::size_t MAX_DIAGNOSTICS = 1000;  // the parser's documented cap (docs/design/dbc.md)
constexpr int MUTATION_RUNS = 20000;
constexpr int MAX_MUTATIONS_PER_RUN = 8;
constexpr std::uint64_t FUZZ_SEED = 1939;

/// The first error of a parse as "file:line:col: reason", or "" when there is none.
std::string firstError(const ParseOutput& output) {
  for (const Error& diagnostic : output.diagnostics) {
    if (diagnostic.severity == Severity::Error) return diagnostic.toString();
  }
  return {};
}

std::uint32_t lineCount(std::string_view text) {
  return static_cast<std::uint32_t>(std::count(text.begin(), text.end(), '\n')) + 1;
}

/// What must hold for any input: bounded diagnostics, each inside the text, and a clean
/// parse writes back to an equal model.
void checkInvariants(std::string_view text, const ParseOutput& output) {
  CHECK(output.diagnostics.size() <= MAX_DIAGNOSTICS + 1);
  const std::uint32_t lines = lineCount(text);
  for (const Error& diagnostic : output.diagnostics) {
    INFO(diagnostic.toString());
    CHECK(diagnostic.location.file == TEST_FILE);
    CHECK(diagnostic.location.line >= 1);
    CHECK(diagnostic.location.line <= lines);
    CHECK(!diagnostic.message.empty());
  }
  if (!output.hasErrors()) {
    const std::string written = write(output.database);
    const ParseOutput again = parse(written, "rewritten.dbc");
    INFO(written);
    CHECK_FALSE(again.hasErrors());
    CHECK(again.database == output.database);
  }
}

/// Compiles every message and decodes a few payload lengths: must stay in bounds (ASan),
/// visit only real signal indices and account for every compiled signal at most once.
void decodeEverything(const Database& database, std::span<const std::uint8_t> payload) {
  bool consistent = true;
  for (const Message& message : database.messages) {
    const MessageCodec codec = MessageCodec::compile(database, message);
    for (const std::size_t length : {std::size_t{0}, std::size_t{3}, std::size_t{8}, payload.size()}) {
      std::size_t visits = 0;
      const DecodeSummary summary = codec.decode(payload.first(length), [&](std::uint32_t index, const DecodedValue&) {
        consistent = consistent && index < message.signals.size();
        ++visits;
      });
      consistent = consistent && visits == summary.decoded &&
                   std::size_t{summary.decoded} + summary.missing <= codec.signals().size();
    }
  }
  CHECK(consistent);
}

std::vector<std::filesystem::path> fixtureFiles() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(fixtureDir())) {
    if (entry.is_regular_file() && entry.path().extension() == ".dbc") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

// ------------------------------------------------------------------ exact locations

namespace {

/// One malformed input and the first error the parser must report for it.
struct FirstErrorCase {
  const char* name;
  std::string_view text;
  std::string_view expected;
};

constexpr FirstErrorCase FIRST_ERROR_CASES[] = {
    {"a missing BO_ colon at the length token", "BU_: A\nBO_ 100 Msg 8 Node\n",
     "test.dbc:2:13: expected ':', found '8'"},
    {"an unknown statement at its first character (after nodes)", "BU_: A\n\nFOO bar;\n",
     "test.dbc:3:1: unknown statement 'FOO'"},
    {"an unknown statement at its first character (indented)", "BO_ 1 M: 8 N\n\n  FOO bar;\n",
     "test.dbc:3:3: unknown statement 'FOO'"},
    {"an unexpected character where a statement should start", "BU_: A\n  @\n",
     "test.dbc:2:3: unexpected character '@'"},
    {"a bad byte order at the digit", "BO_ 1 M: 8 N\n SG_ S : 0|8@2+ (1,0) [0|0] \"\" N\n",
     "test.dbc:2:14: expected byte order 0 (Motorola) or 1 (Intel), found '2'"},
    {"a missing sign at the character after the byte order", "BO_ 1 M: 8 N\n SG_ S : 0|8@1 (1,0) [0|0] \"\" N\n",
     "test.dbc:2:16: expected '+' (unsigned) or '-' (signed), found '('"},
    {"a string that is never closed at its opening quote", "VAL_TABLE_ T 1 \"open\n",
     "test.dbc:1:16: string never closed"},
    {"a message ID beyond 32 bits at the number", "BO_ 4294967296 X: 8 N\n",
     "test.dbc:1:5: message ID 4294967296 exceeds 32 bits"},
    {"SG_ outside a message at the keyword", "BU_: N\n SG_ S : 0|8@1+ (1,0) [0|0] \"\" N\n",
     "test.dbc:2:2: SG_ outside a BO_ message"},
    {"text after a BO_ header at the extra word", "BO_ 1 X: 8 N extra\n", "test.dbc:1:14: unexpected text after BO_"},
    {"a missing a semicolon that is not followed by a statement", "BA_DEF_ BO_ \"A\" INT 0 10 junk\n",
     "test.dbc:1:26: expected ';', found 'j'"},
    {"the right line after multi-line strings, block comments and CRLF",
     "CM_ \"line one\r\nline two\r\nline three\";\r\n"
     "/* a comment\r\n over two lines */\r\n"
     "BO_ 1 X 8 N\r\n",
     "test.dbc:6:9: expected ':', found '8'"},
    {"resolution errors on the line of the referring statement",
     "BO_ 1 M: 8 N\n"
     " SG_ Sel M : 0|8@1+ (1,0) [0|0] \"\" N\n"
     " SG_ Val m1 : 8|8@1+ (1,0) [0|0] \"\" N\n"
     "\n"
     "SG_MUL_VAL_ 1 Val Missing 1-1;\n",
     "test.dbc:5:1: SG_MUL_VAL_ names multiplexor 'Missing' that message 'M' does not have"},
};

}  // namespace

TEST_CASE("parser reports each malformed statement as file:line:col at the right place") {
  for (const FirstErrorCase& row : FIRST_ERROR_CASES) {
    SUBCASE(row.name) {
      const ParseOutput sut = parseText(row.text);

      CHECK(firstError(sut) == row.expected);
    }
  }
}

TEST_CASE("parser reports a warning with its location and the warning prefix") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 N\nCM_ BO_ 1 \"x\"\nBO_ 2 Q: 8 N\n");

  const auto warnings = diagnosticsWith(sut, Severity::Warning, "without ';'");
  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].toString() == "test.dbc:2:14: warning: CM_ statement without ';'");
}

TEST_CASE("parser gives a duplicated node its location") {
  const ParseOutput sut = parseText("BO_ 1 M: 8 N\nBU_: A B\n  A\n");

  const auto warnings = diagnosticsWith(sut, Severity::Warning, "listed twice");
  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].location.line == 3);
  CHECK(warnings[0].location.column == 3);
}

TEST_CASE("parser reports every malformed statement in one run and keeps the good ones") {
  const ParseOutput sut = parseText(
      "BO_ 1 A 8 N\n"
      "BO_ 2 B: 8 N\n"
      " SG_ S : 0|8@1+ (1,0) [0|0] \"\" N\n"
      "VAL_ 2 S x;\n"
      "BO_ 3 C: 8 N\n");

  CHECK(sut.errorCount() == 2);
  CHECK(sut.database.findMessage("A") == nullptr);
  CHECK(sut.database.findMessage("B") != nullptr);
  CHECK(sut.database.findMessage("C") != nullptr);
}

TEST_CASE("parser stops after the diagnostic cap on a file of malformed statements") {
  std::string garbage;
  constexpr int GARBAGE_LINES = 3000;
  for (int i = 0; i < GARBAGE_LINES; ++i) garbage += "BO_ nonsense\n";

  const ParseOutput sut = parseText(garbage);

  CHECK(sut.diagnostics.size() == MAX_DIAGNOSTICS + 1);
  CHECK(hasError(sut, "too many errors"));
}

// ------------------------------------------------------------------ robustness

TEST_CASE("parser survives every prefix of every fixture file") {
  const auto files = fixtureFiles();
  REQUIRE(!files.empty());
  std::vector<std::uint8_t> payload(64);
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<std::uint8_t>(i * 37u + 11u);
  for (const auto& path : files) {
    const std::string content = readFixture(path.filename().string());
    REQUIRE(!content.empty());
    for (std::size_t length = 0; length <= content.size(); ++length) {
      const std::string_view prefix(content.data(), length);
      CAPTURE(path.filename().string());
      CAPTURE(length);
      const ParseOutput sut = parse(prefix, TEST_FILE);
      checkInvariants(prefix, sut);
      decodeEverything(sut.database, payload);
    }
  }
}

TEST_CASE("parser survives 20000 random mutations of a fixture" * doctest::timeout(300)) {
  const std::string original = readFixture("grammar_all_statements.dbc");
  REQUIRE(!original.empty());
  std::mt19937_64 random(FUZZ_SEED);
  std::uniform_int_distribution<int> mutationCount(1, MAX_MUTATIONS_PER_RUN);
  std::uniform_int_distribution<int> kind(0, 3);
  std::uniform_int_distribution<int> anyByte(0, 255);
  // Bytes that steer the parser into other branches more often than uniform noise.
  const std::string interesting = " \t\r\n\"\\;:|@+-(),[]/*0123456789eEmMx_";
  std::uniform_int_distribution<std::size_t> pickInteresting(0, interesting.size() - 1);
  std::vector<std::uint8_t> payload(64);
  std::size_t cleanRuns = 0;
  for (int run = 0; run < MUTATION_RUNS; ++run) {
    std::string text = original;
    const int mutations = mutationCount(random);
    for (int m = 0; m < mutations && !text.empty(); ++m) {
      std::uniform_int_distribution<std::size_t> position(0, text.size() - 1);
      const std::size_t at = position(random);
      const char byte = kind(random) == 0 ? static_cast<char>(anyByte(random)) : interesting[pickInteresting(random)];
      switch (kind(random)) {
        case 0: text[at] = static_cast<char>(text[at] ^ (1 << (anyByte(random) % 8))); break;  // flip a bit
        case 1: text.insert(at, 1, byte); break;
        case 2: text.erase(at, 1); break;
        default: text[at] = byte; break;
      }
    }
    for (auto& b : payload) b = static_cast<std::uint8_t>(anyByte(random));
    CAPTURE(run);
    const ParseOutput sut = parse(text, TEST_FILE);
    checkInvariants(text, sut);
    decodeEverything(sut.database, payload);
    if (!sut.hasErrors()) ++cleanRuns;
  }
  MESSAGE("mutated inputs that still parsed without errors: " << cleanRuns << " of " << MUTATION_RUNS);
}

TEST_CASE("parser survives random bytes") {
  std::mt19937_64 random(FUZZ_SEED + 1);
  std::uniform_int_distribution<int> anyByte(0, 255);
  std::uniform_int_distribution<std::size_t> anyLength(0, 2048);
  constexpr int RANDOM_RUNS = 500;
  for (int run = 0; run < RANDOM_RUNS; ++run) {
    std::string text(anyLength(random), '\0');
    for (char& c : text) c = static_cast<char>(anyByte(random));
    CAPTURE(run);
    const ParseOutput sut = parse(text, TEST_FILE);
    CHECK(sut.diagnostics.size() <= MAX_DIAGNOSTICS + 1);
  }
}
