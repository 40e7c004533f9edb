// vcu-telemetry's memory of received remote commands (services/telemetry/src/replay_guard.*,
// docs/design/telemetry.md "Remote commands"): a cmdId is refused while its deadline has not
// passed, also after the memory is opened again from its file; a forgotten one cannot come back
// when the clock is set back; a cut last line and a damaged file are survived without letting
// a remembered command run again; the memory is bounded by MAX_REMEMBERED_COMMANDS and its file
// is compacted.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "replay_guard.hpp"

namespace {

using namespace openvcu;
using telemetry::ReplayGuard;
using telemetry::ReplayRefusal;
namespace fs = std::filesystem;

constexpr std::int64_t NOW_UNIX_MS = 1'764'259'200'000;
constexpr std::int64_t DEADLINE_MS = NOW_UNIX_MS + 5000;

/// A fresh folder under `base`, removed at the end of the case.
struct TempFolder {
  std::string path;
  explicit TempFolder(const fs::path& base = fs::temp_directory_path()) {
    std::string pattern = (base / "openvcu-replay-XXXXXX").string();
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path = pattern;
  }
  ~TempFolder() { fs::remove_all(path); }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  [[nodiscard]] std::string file() const { return path + "/" + std::string(telemetry::REPLAY_FILE_NAME); }
};

std::string readAll(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void writeAll(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  REQUIRE(out.good());
}

ReplayGuard openGuard(const TempFolder& folder, std::vector<Error>* warnings = nullptr) {
  auto opened = ReplayGuard::open(folder.path, warnings);
  REQUIRE_MESSAGE(opened.ok(), (opened ? std::string() : opened.error().toString()));
  return std::move(*opened);
}

}  // namespace

TEST_CASE("a cmdId admitted once is refused as replayed until its deadline, then by the floor") {
  TempFolder folder;
  ReplayGuard sut = openGuard(folder);

  const auto first = sut.admit("c-1", DEADLINE_MS, NOW_UNIX_MS);
  const auto again = sut.admit("c-1", DEADLINE_MS, DEADLINE_MS - 1);
  const auto afterDeadline = sut.admit("c-1", DEADLINE_MS, DEADLINE_MS);

  CHECK_FALSE(first);
  REQUIRE(again);
  CHECK(again->kind == ReplayRefusal::Replayed);
  CHECK(again->reason.starts_with("replayed: cmdId 'c-1' was received before"));
  REQUIRE(afterDeadline);  // forgotten at its deadline; the floor refuses it from then on
  CHECK(afterDeadline->kind == ReplayRefusal::BeforeFloor);
  CHECK(sut.floorUnixMs() == DEADLINE_MS);
  CHECK(sut.remembered() == 0);
}

TEST_CASE("a cmdId admitted before the memory was opened again is refused as replayed") {
  TempFolder folder;
  {
    ReplayGuard before = openGuard(folder);
    REQUIRE_FALSE(before.admit("c-1", DEADLINE_MS, NOW_UNIX_MS));
    REQUIRE_FALSE(before.admit("c-2", DEADLINE_MS + 1, NOW_UNIX_MS));
  }
  std::vector<Error> warnings;
  ReplayGuard sut = openGuard(folder, &warnings);

  const auto replayed = sut.admit("c-1", DEADLINE_MS, NOW_UNIX_MS + 1000);
  const auto fresh = sut.admit("c-3", DEADLINE_MS, NOW_UNIX_MS + 1000);

  CHECK(warnings.empty());
  REQUIRE(replayed);
  CHECK(replayed->kind == ReplayRefusal::Replayed);
  CHECK_FALSE(fresh);
  CHECK(sut.remembered() == 3);
  CHECK(readAll(folder.file()) == "openvcu remote commands v1 floor 0\n" + std::to_string(DEADLINE_MS) + " c-1\n" +
                                      std::to_string(DEADLINE_MS + 1) + " c-2\n" + std::to_string(DEADLINE_MS) +
                                      " c-3\n");
}

TEST_CASE("a forgotten cmdId stays refused when the clock is set back, also after a reopen") {
  TempFolder folder;
  {
    ReplayGuard before = openGuard(folder);
    REQUIRE_FALSE(before.admit("c-1", DEADLINE_MS, NOW_UNIX_MS));
    // the clock passes c-1's deadline: forgotten while another command comes, the floor rises
    REQUIRE_FALSE(before.admit("c-2", DEADLINE_MS + 9000, DEADLINE_MS + 1));
  }
  ReplayGuard sut = openGuard(folder);
  const std::int64_t setBack = NOW_UNIX_MS + 1000;  // c-1's deadline is ahead again

  // after the reopen c-1 is in the file until a rewrite: refused as replayed; once forgotten, by the floor
  const auto fromFile = sut.admit("c-1", DEADLINE_MS, setBack);
  (void)sut.admit("c-3", DEADLINE_MS + 9500, DEADLINE_MS + 2);  // the clock right again forgets c-1
  const auto fromFloor = sut.admit("c-1", DEADLINE_MS, setBack);

  REQUIRE(fromFile);
  CHECK(fromFile->kind == ReplayRefusal::Replayed);
  REQUIRE(fromFloor);
  CHECK(fromFloor->kind == ReplayRefusal::BeforeFloor);
  CHECK(fromFloor->reason.find("clock went back") != std::string::npos);
}

TEST_CASE("a last line cut by a crash is dropped with a warning and the complete lines are kept") {
  TempFolder folder;
  writeAll(folder.file(), "openvcu remote commands v1 floor 0\n" + std::to_string(DEADLINE_MS) + " c-1\n" +
                              std::to_string(DEADLINE_MS) + " c-");
  std::vector<Error> warnings;

  ReplayGuard sut = openGuard(folder, &warnings);

  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].toString() ==
        folder.file() + ":3: a last line without its end, from an interrupted write, dropped");
  CHECK(sut.floorUnixMs() == 0);
  REQUIRE(sut.admit("c-1", DEADLINE_MS, NOW_UNIX_MS));
  CHECK_FALSE(sut.admit("c-2", DEADLINE_MS, NOW_UNIX_MS));
  CHECK(readAll(folder.file()) == "openvcu remote commands v1 floor 0\n" + std::to_string(DEADLINE_MS) + " c-1\n" +
                                      std::to_string(DEADLINE_MS) + " c-2\n");
}

TEST_CASE("a damaged file keeps its good lines and refuses every deadline up to its last write plus 10 s") {
  TempFolder folder;
  writeAll(folder.file(),
           "openvcu remote commands v1 floor 0\n" + std::to_string(DEADLINE_MS) + " c-1\nnot a line of this file\n");
  const std::int64_t modifiedMs = NOW_UNIX_MS - 2000;
  const timespec times[2] = {{.tv_sec = modifiedMs / 1000, .tv_nsec = 0}, {.tv_sec = modifiedMs / 1000, .tv_nsec = 0}};
  REQUIRE(::utimensat(AT_FDCWD, folder.file().c_str(), times, 0) == 0);
  std::vector<Error> warnings;

  ReplayGuard sut = openGuard(folder, &warnings);

  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].message.starts_with("damaged: its good lines are kept"));
  CHECK(sut.floorUnixMs() == modifiedMs + telemetry::MAX_DEADLINE_AHEAD_MS);
  const auto kept = sut.admit("c-1", DEADLINE_MS + 20'000, NOW_UNIX_MS);
  const auto early = sut.admit("c-2", modifiedMs + telemetry::MAX_DEADLINE_AHEAD_MS, NOW_UNIX_MS);
  const auto late = sut.admit("c-3", modifiedMs + telemetry::MAX_DEADLINE_AHEAD_MS + 1, NOW_UNIX_MS);
  REQUIRE(kept);
  CHECK(kept->kind == ReplayRefusal::Replayed);
  REQUIRE(early);
  CHECK(early->kind == ReplayRefusal::BeforeFloor);
  CHECK_FALSE(late);
}

TEST_CASE("beyond MAX_REMEMBERED_COMMANDS within their deadlines the next cmdId is refused busy until one expires") {
  TempFolder folder(fs::exists("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path());  // 1024 syncs: tmpfs
  ReplayGuard sut = openGuard(folder);
  for (std::size_t i = 0; i < telemetry::MAX_REMEMBERED_COMMANDS; ++i) {
    REQUIRE_FALSE(sut.admit("c-" + std::to_string(i), DEADLINE_MS + static_cast<std::int64_t>(i), NOW_UNIX_MS));
  }

  const auto full = sut.admit("one-more", DEADLINE_MS + 9000, NOW_UNIX_MS);
  const auto afterOneExpired = sut.admit("one-more", DEADLINE_MS + 9000, DEADLINE_MS);

  REQUIRE(full);
  CHECK(full->kind == ReplayRefusal::Full);
  CHECK(full->reason ==
        "busy: 1024 remote commands within their deadlines are remembered; the next is forgotten in "
        "5000 ms");
  CHECK_FALSE(afterOneExpired);
  CHECK(sut.remembered() == telemetry::MAX_REMEMBERED_COMMANDS);
}

TEST_CASE("the file is rewritten once most of its lines have expired") {
  TempFolder folder(fs::exists("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path());
  ReplayGuard sut = openGuard(folder);
  constexpr int COMMANDS = 500;
  for (int i = 0; i < COMMANDS; ++i) {  // one command every 100 ms, each due 1 s later
    const std::int64_t now = NOW_UNIX_MS + i * 100;
    REQUIRE_FALSE(sut.admit("c-" + std::to_string(i), now + 1000, now));
  }
  const std::string text = readAll(folder.file());
  const auto lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));

  constexpr std::string_view HEADER = "openvcu remote commands v1 floor ";
  REQUIRE(text.starts_with(HEADER));
  const std::int64_t fileFloor = std::stoll(text.substr(HEADER.size()));

  CHECK(sut.remembered() == 10);
  CHECK(sut.floorUnixMs() == NOW_UNIX_MS + (COMMANDS - 11) * 100 + 1000);  // c-489's deadline
  CHECK(lines <= 1 + 2 * sut.remembered() + 64 + 1);
  CHECK(fileFloor > NOW_UNIX_MS);  // rewritten with the floor of its time
  CHECK(fileFloor <= sut.floorUnixMs());
}

TEST_CASE("a memory that cannot be written stops the start with the file named") {
  TempFolder folder;
  const std::string notAFolder = folder.path + "/plain-file";
  writeAll(notAFolder, "x");

  auto opened = ReplayGuard::open(notAFolder);

  REQUIRE_FALSE(opened);
  CHECK(opened.error().toString().starts_with(notAFolder + "/" + std::string(telemetry::REPLAY_FILE_NAME)));
}
