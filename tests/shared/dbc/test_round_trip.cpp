// Every DBC in tests/data/dbc (a new case is a new file, STYLE.md 12) and, when the team
// kit is present, every corpus DBC that parses without errors: parse -> write -> parse
// gives an equal model, and write() is a fixed point on the second pass.

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include "skip.hpp"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace fs = std::filesystem;

namespace {

const fs::path CORPUS_DIR = fs::path(OPENVCU_TEAM_KIT) / "corpus" / "dbc";

std::vector<fs::path> dbcFilesUnder(const fs::path& root) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    std::string extension = it->path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (it->is_regular_file() && extension == ".dbc") files.push_back(it->path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string readPath(const fs::path& path) {
  std::string reason;
  return text::readFile(path.string(), &reason).value_or(std::string{});
}

/// The first line where two texts differ, for the failure message.
std::string firstDifference(const std::string& a, const std::string& b) {
  std::size_t line = 1;
  std::size_t lineStart = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (a[i] != b[i]) {
      return "line " + std::to_string(line) + ": '" + a.substr(lineStart, a.find('\n', lineStart) - lineStart) +
             "' vs '" + b.substr(lineStart, b.find('\n', lineStart) - lineStart) + "'";
    }
    if (a[i] == '\n') {
      ++line;
      lineStart = i + 1;
    }
  }
  return a.size() == b.size() ? "" : "length " + std::to_string(a.size()) + " vs " + std::to_string(b.size());
}

/// The round trip of one parsed file; returns false (with CHECK failures) when it breaks.
bool roundTrips(const ParseOutput& first, const std::string& name) {
  INFO(name);
  const std::string written = write(first.database);
  const ParseOutput second = parse(written, name + " (written)");
  INFO(describe(second));
  CHECK_FALSE(second.hasErrors());
  const bool equal = second.database == first.database;
  CHECK(equal);
  const std::string rewritten = write(second.database);
  INFO(firstDifference(written, rewritten));
  CHECK(rewritten == written);
  return equal && rewritten == written && !second.hasErrors();
}

}  // namespace

TEST_CASE("every fixture DBC parses without errors, round-trips to an equal model and writes a fixed point") {
  const std::vector<fs::path> files = dbcFilesUnder(fixtureDir());
  constexpr std::size_t MINIMUM_FIXTURES = 6;
  REQUIRE(files.size() >= MINIMUM_FIXTURES);

  for (const fs::path& path : files) {
    const std::string name = path.filename().string();
    CAPTURE(name);
    const std::string content = readPath(path);
    REQUIRE(!content.empty());

    const ParseOutput sut = parse(content, name);

    INFO(describe(sut));
    CHECK_FALSE(sut.hasErrors());
    CHECK(roundTrips(sut, name));
  }
  MESSAGE("round-tripped fixture DBC files: " << files.size());
}

TEST_CASE("the round trip keeps what the fixtures are about") {
  const ParseOutput cp1252 = parse(readFixture("cp1252_units.dbc"), "cp1252_units.dbc");
  const ParseOutput again = parse(write(cp1252.database), "written.dbc");

  CHECK(cp1252.database.sourceEncoding == "cp1252");
  CHECK(again.database.sourceEncoding == "utf-8");  // write() emits UTF-8
  const Message* climate = again.database.findMessage("Climate");
  REQUIRE(climate != nullptr);
  REQUIRE(climate->findSignal("CabinTemp") != nullptr);
  CHECK(climate->findSignal("CabinTemp")->unit == "\xC2\xB0" "C");
}

TEST_CASE("every corpus DBC that parses without errors round-trips" * doctest::timeout(600)) {
  if (!fs::is_directory(CORPUS_DIR)) {
    OPENVCU_SKIP("skipped: corpus folder " << CORPUS_DIR.string()
                                      << " not found (the team kit is not beside the repository)");
  }
  const std::vector<fs::path> files = dbcFilesUnder(CORPUS_DIR);
  std::size_t clean = 0;
  std::size_t withErrors = 0;
  std::size_t broken = 0;
  for (const fs::path& path : files) {
    const std::string name = fs::relative(path, CORPUS_DIR).string();
    CAPTURE(name);
    const ParseOutput sut = parse(readPath(path), name);
    if (sut.hasErrors()) {
      ++withErrors;
      continue;
    }
    ++clean;
    if (!roundTrips(sut, name)) ++broken;
  }

  MESSAGE("corpus DBC files: " << files.size() << ", round-tripped: " << clean << ", skipped with parse errors: "
                               << withErrors << ", broken round trips: " << broken);
  CHECK(clean > 0);
  CHECK(broken == 0);
}
