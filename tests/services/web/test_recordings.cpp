// vcu-web's data folder (services/web/src/recordings.hpp): listings, name checks, archives,
// uploads and the cache.
#include <archive.h>
#include <archive_entry.h>
#include <doctest/doctest.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "recordings.hpp"

using namespace openvcu;
using namespace openvcu::web;
namespace fs = std::filesystem;

namespace {

constexpr std::time_t OLDER_S = 1'700'000'000;
constexpr std::time_t NEWER_S = 1'700'000'100;
constexpr std::time_t DAY_S = 24 * 60 * 60;

/// A folder under the system's temporary folder with a random name, removed afterwards.
class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "openvcu-web-data-XXXXXX").string();
    if (::mkdtemp(pattern.data()) != nullptr) m_path = pattern;
  }
  ~TempFolder() {
    std::error_code ignored;
    if (!m_path.empty()) fs::remove_all(m_path, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  [[nodiscard]] const fs::path& path() const { return m_path; }

 private:
  fs::path m_path;
};

void writeFile(const fs::path& path, const std::string& content, std::time_t modified = 0) {
  { std::ofstream(path, std::ios::binary) << content; }
  if (modified != 0) {
    const timespec times[2] = {{modified, 0}, {modified, 0}};
    REQUIRE(::utimensat(AT_FDCWD, path.c_str(), times, 0) == 0);
  }
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A prepared data folder in a temporary folder.
struct DataFixture {
  TempFolder temp;
  DataFolder sut{temp.path() / "data"};
  DataFixture() { REQUIRE(sut.prepare()); }
  [[nodiscard]] fs::path recordings() const { return sut.root() / "recordings"; }
};

/// Every regular entry of a .tar.gz read back with libarchive's reader: path -> content.
std::map<std::string, std::string> readArchive(const fs::path& path) {
  std::map<std::string, std::string> entries;
  archive* reader = archive_read_new();
  archive_read_support_filter_gzip(reader);
  archive_read_support_format_tar(reader);
  REQUIRE(archive_read_open_filename(reader, path.c_str(), 10240) == ARCHIVE_OK);
  archive_entry* entry = nullptr;
  while (archive_read_next_header(reader, &entry) == ARCHIVE_OK) {
    std::string content;
    char block[4096];
    for (la_ssize_t got; (got = archive_read_data(reader, block, sizeof block)) > 0;) {
      content.append(block, static_cast<std::size_t>(got));
    }
    entries[archive_entry_pathname(entry)] = content;
  }
  archive_read_free(reader);
  return entries;
}

}  // namespace

TEST_CASE("prepare creates the folders and a missing data folder") {
  TempFolder temp;
  DataFolder sut(temp.path() / "data");
  REQUIRE(sut.prepare());
  CHECK(fs::is_directory(sut.root() / "recordings"));
  CHECK(fs::is_directory(sut.incomingFolder()));
  CHECK(fs::is_directory(sut.cacheFolder()));
}

TEST_CASE("prepare fails when the data folder is a file") {
  TempFolder temp;
  writeFile(temp.path() / "data", "x");
  DataFolder sut(temp.path() / "data");
  CHECK_FALSE(sut.prepare());
}

TEST_CASE("recordings are listed newest first with their regular files and sizes") {
  DataFixture data;
  fs::create_directory(data.recordings() / "older");
  writeFile(data.recordings() / "older" / "vehicle.log", std::string(10, 'a'), OLDER_S);
  writeFile(data.recordings() / "older" / "events.lcmlog", std::string(5, 'b'), OLDER_S - 50);
  fs::create_directory(data.recordings() / "older" / "sub");
  fs::create_symlink("vehicle.log", data.recordings() / "older" / "link.log");
  fs::create_directory(data.recordings() / "newer");
  writeFile(data.recordings() / "newer" / "vehicle.log", std::string(3, 'c'), NEWER_S);
  fs::create_directory(data.recordings() / ".hidden");

  const auto sut = data.sut.listRecordings();
  REQUIRE(sut.size() == 2);
  CHECK(sut[0].name == "newer");
  CHECK(sut[0].bytes == 3);
  CHECK(sut[0].modifiedUnixMs == NEWER_S * 1000);
  CHECK(sut[1].name == "older");
  CHECK(sut[1].bytes == 15);
  CHECK(sut[1].modifiedUnixMs == OLDER_S * 1000);
  REQUIRE(sut[1].files.size() == 2);
  CHECK(sut[1].files[0].name == "events.lcmlog");
  CHECK(sut[1].files[0].bytes == 5);
  CHECK(sut[1].files[1].name == "vehicle.log");
}

TEST_CASE("uploads are listed newest first without the incoming folder") {
  DataFixture data;
  writeFile(data.sut.root() / "uploads" / "a.log", "12345", OLDER_S);
  writeFile(data.sut.root() / "uploads" / "b.asc", "1", NEWER_S);
  writeFile(data.sut.incomingFolder() / "partial", "xx");
  const auto sut = data.sut.listUploads();
  REQUIRE(sut.size() == 2);
  CHECK(sut[0].name == "b.asc");
  CHECK(sut[1].name == "a.log");
  CHECK(sut[1].bytes == 5);
  CHECK(sut[1].modifiedUnixMs == OLDER_S * 1000);
}

TEST_CASE("names that are not one plain path component are refused") {
  DataFixture data;
  fs::create_directory(data.recordings() / "drive1");
  fs::create_directory(data.recordings() / ".hidden");
  CHECK(data.sut.recording("drive1"));
  CHECK(validEntryName(std::string(128, 'x')));
  const std::string names[] = {"..", ".", "/etc", ".hidden", "a/b", "", "a b", std::string(200, 'x')};
  for (const std::string& name : names) {
    CAPTURE(name);
    CHECK_FALSE(validEntryName(name));
    auto sut = data.sut.recording(name);
    REQUIRE_FALSE(sut);
    CHECK(sut.error().message.find("not a valid name") != std::string::npos);
    CHECK_FALSE(data.sut.upload(name));
  }
  auto missing = data.sut.recording("absent");
  REQUIRE_FALSE(missing);
  CHECK(missing.error().message == "recording 'absent': not found");
}

TEST_CASE("a symlink leading out of the data folder is refused and not listed") {
  DataFixture data;
  TempFolder outside;
  writeFile(outside.path() / "secret.log", "secret");
  fs::create_directory_symlink(outside.path(), data.recordings() / "escape");
  fs::create_symlink(outside.path() / "secret.log", data.sut.root() / "uploads" / "secret.log");
  fs::create_directory(data.recordings() / "real");
  fs::create_directory_symlink("real", data.recordings() / "alias");

  auto sut = data.sut.recording("escape");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().message.find("leads out of recordings/") != std::string::npos);
  CHECK_FALSE(data.sut.upload("secret.log"));
  CHECK_FALSE(data.sut.archiveRecording("escape"));
  CHECK(data.sut.recording("alias"));  // a symlink that stays inside is fine
  const auto listing = data.sut.listRecordings();
  CHECK(listing.size() == 2);
  for (const auto& entry : listing) CHECK(entry.name != "escape");
  CHECK(data.sut.listUploads().empty());
}

TEST_CASE("an archive holds the regular files of the recording byte for byte") {
  DataFixture data;
  const fs::path folder = data.recordings() / "drive1";
  fs::create_directory(folder);
  std::string large;
  for (int i = 0; large.size() < 200'000; ++i) large += std::to_string(i * 7919) + " (0.0) can0 123#DEADBEEF\n";
  writeFile(folder / "can0.log", large);
  writeFile(folder / "events.lcmlog", std::string("\0\x01\x02lcm", 6));
  fs::create_symlink("/etc/hostname", folder / "outside.log");

  auto sut = data.sut.archiveRecording("drive1");
  REQUIRE(sut);
  CHECK(sut->parent_path() == data.sut.cacheFolder());
  CHECK(sut->filename().string().starts_with("drive1-"));
  CHECK(sut->filename().string().ends_with(".tar.gz"));
  const auto entries = readArchive(*sut);
  REQUIRE(entries.size() == 2);
  REQUIRE(entries.count("drive1/can0.log") == 1);
  CHECK(entries.at("drive1/can0.log") == large);
  CHECK(entries.at("drive1/events.lcmlog") == std::string("\0\x01\x02lcm", 6));

  auto second = data.sut.archiveRecording("drive1");
  REQUIRE(second);
  CHECK(*second != *sut);  // each request its own file
}

TEST_CASE("an archive that cannot be written leaves nothing in the cache") {
  DataFixture data;
  fs::create_directory(data.recordings() / "drive1");
  writeFile(data.recordings() / "drive1" / "can0.log", "x");
  fs::remove(data.sut.cacheFolder());
  writeFile(data.sut.cacheFolder(), "not a folder");
  auto sut = data.sut.archiveRecording("drive1");
  REQUIRE_FALSE(sut);
  CHECK(sut.error().message.starts_with("recording 'drive1': cannot make the archive: "));
}

TEST_CASE("acceptUpload sanitises the client's name and makes it unique") {
  DataFixture data;
  const fs::path incoming = data.sut.incomingFolder() / "body-1";
  writeFile(incoming, "first");
  auto sut = data.sut.acceptUpload(incoming, "C:\\logs\\my drive (1).log");
  REQUIRE(sut);
  CHECK(*sut == "my_drive__1_.log");
  CHECK_FALSE(fs::exists(incoming));
  CHECK(readFile(data.sut.root() / "uploads" / *sut) == "first");

  writeFile(incoming, "second");
  auto again = data.sut.acceptUpload(incoming, "my drive (1).log");
  REQUIRE(again);
  CHECK(*again == "my_drive__1_-2.log");
  CHECK(readFile(data.sut.root() / "uploads" / *again) == "second");

  writeFile(incoming, "third");
  auto hidden = data.sut.acceptUpload(incoming, "../..hidden");
  REQUIRE(hidden);
  CHECK(*hidden == "__hidden");

  writeFile(incoming, "fourth");
  auto longName = data.sut.acceptUpload(incoming, std::string(300, 'n') + ".asc");
  REQUIRE(longName);
  CHECK(validEntryName(*longName));
  CHECK(longName->ends_with(".asc"));
  CHECK(data.sut.upload(*longName));
}

TEST_CASE("acceptUpload refuses a file outside the incoming folder") {
  DataFixture data;
  writeFile(data.recordings() / "x", "x");
  CHECK_FALSE(data.sut.acceptUpload(data.recordings() / "x", "x.log"));
  CHECK(fs::exists(data.recordings() / "x"));
}

TEST_CASE("prepare removes cache files older than a day and keeps newer ones") {
  DataFixture data;
  const std::time_t now = std::time(nullptr);
  writeFile(data.sut.cacheFolder() / "old.tar.gz", "old", now - 2 * DAY_S);
  writeFile(data.sut.cacheFolder() / "new.tar.gz", "new", now - 60);
  REQUIRE(data.sut.prepare());
  CHECK_FALSE(fs::exists(data.sut.cacheFolder() / "old.tar.gz"));
  CHECK(fs::exists(data.sut.cacheFolder() / "new.tar.gz"));
}
