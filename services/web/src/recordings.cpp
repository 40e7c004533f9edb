// vcu-web's data folder (recordings.hpp): listings, name checks that keep every request inside
// the folder, gzip'd tar archives with libarchive, and accepted uploads.
#include "recordings.hpp"

#include <archive.h>
#include <archive_entry.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <optional>
#include <system_error>

namespace openvcu::web {
namespace fs = std::filesystem;
namespace {

constexpr std::size_t MAX_ENTRY_NAME = 128;
constexpr std::size_t ARCHIVE_BLOCK = 64 * 1024;  // bytes read and handed to libarchive at a time
constexpr std::int64_t CACHE_MAX_AGE_S = 24 * 60 * 60;
/// An accepted upload's name before a "-N" suffix: leaves room for "-9999".
constexpr std::size_t MAX_UPLOAD_STEM = MAX_ENTRY_NAME - 8;
constexpr std::size_t MAX_KEPT_EXTENSION = 16;  // ".log", ".asc", ".candump": kept when a name is cut
constexpr int MAX_UPLOAD_SUFFIX = 9999;
constexpr mode_t FOLDER_MODE = 0750;
constexpr const char* NAME_FORM = "1-128 of A-Z a-z 0-9 . _ -, not starting with '.'";

bool nameCharacter(char c) noexcept {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
}

std::string errnoText(int error) {
  return std::strerror(error);
}

std::int64_t unixMs(const struct stat& info) noexcept {
  return static_cast<std::int64_t>(info.st_mtim.tv_sec) * 1000 + info.st_mtim.tv_nsec / 1'000'000;
}

/// True when `path` is `root` itself or below it (both canonical).
bool isUnder(const fs::path& path, const fs::path& root) {
  auto rootPart = root.begin();
  auto pathPart = path.begin();
  for (; rootPart != root.end(); ++rootPart, ++pathPart) {
    if (pathPart == path.end() || *pathPart != *rootPart) return false;
  }
  return true;
}

/// `container`/`name` with symlinks resolved, or the reason it cannot be used. `kind` names
/// the entry in messages ("recording").
Result<fs::path> resolveEntry(const fs::path& container, std::string_view name, std::string_view kind) {
  const std::string quoted = "'" + std::string(name) + "'";
  if (!validEntryName(name)) {
    return Error{std::string(kind) + " name " + quoted + ": not a valid name (" + NAME_FORM + ")"};
  }
  std::error_code error;
  const fs::path root = fs::canonical(container, error);
  if (error) return Error{std::string(kind) + " " + quoted + ": not found (" + error.message() + ")"};
  const fs::path resolved = fs::canonical(container / std::string(name), error);
  if (error) return Error{std::string(kind) + " " + quoted + ": not found"};
  if (resolved == root || !isUnder(resolved, root)) {
    return Error{std::string(kind) + " " + quoted + ": refused: it leads out of " + container.filename().string() +
                 "/"};
  }
  return resolved;
}

/// The regular files directly in `folder` (no symlink followed, nothing else counted), with
/// their total size and the newest modification time.
std::optional<RecordingEntry> describeFolder(const fs::path& folder, std::string name) {
  struct stat folderInfo {};
  if (::stat(folder.c_str(), &folderInfo) != 0 || !S_ISDIR(folderInfo.st_mode)) return std::nullopt;
  RecordingEntry entry{std::move(name), 0, unixMs(folderInfo), {}};
  std::int64_t newest = -1;
  std::error_code error;
  for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    struct stat info {};
    if (::lstat(it->path().c_str(), &info) != 0 || !S_ISREG(info.st_mode)) continue;
    const auto bytes = static_cast<std::uint64_t>(info.st_size);
    entry.files.push_back(RecordedFile{it->path().filename().string(), bytes});
    entry.bytes += bytes;
    newest = std::max(newest, unixMs(info));
  }
  if (newest >= 0) entry.modifiedUnixMs = newest;  // an empty folder keeps its own time
  std::sort(entry.files.begin(), entry.files.end(),
            [](const RecordedFile& a, const RecordedFile& b) { return a.name < b.name; });
  return entry;
}

void sortNewestFirst(std::vector<RecordingEntry>& entries) {
  std::sort(entries.begin(), entries.end(), [](const RecordingEntry& a, const RecordingEntry& b) {
    if (a.modifiedUnixMs != b.modifiedUnixMs) return a.modifiedUnixMs > b.modifiedUnixMs;
    return a.name < b.name;
  });
}

/// Creates `folder` (mode 0750) unless it exists; a folder or a symlink to one is fine.
Status ensureFolder(const fs::path& folder) {
  if (::mkdir(folder.c_str(), FOLDER_MODE) != 0 && errno != EEXIST) {
    return Error{"cannot create the folder: " + errnoText(errno), Location{folder.string(), 0, 0, {}}};
  }
  struct stat info {};
  if (::stat(folder.c_str(), &info) != 0)
    return Error{"cannot read: " + errnoText(errno), Location{folder.string(), 0, 0, {}}};
  if (!S_ISDIR(info.st_mode)) return Error{"not a folder", Location{folder.string(), 0, 0, {}}};
  return {};
}

/// Removes the files (anything but folders) in `folder` last modified before `before`.
void removeOlderThan(const fs::path& folder, std::time_t before) {
  std::error_code error;
  for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    struct stat info {};
    if (::lstat(it->path().c_str(), &info) != 0 || S_ISDIR(info.st_mode)) continue;
    if (info.st_mtim.tv_sec < before) ::unlink(it->path().c_str());
  }
}

/// `clientName` made into an entry name: its last path component, other characters as '_',
/// no leading '.', at most MAX_UPLOAD_STEM bytes (the extension kept). Split into stem and
/// extension so that a suffix goes between them ("drive.log" -> "drive-2.log").
std::pair<std::string, std::string> sanitiseUploadName(std::string_view clientName) {
  if (const std::size_t slash = clientName.find_last_of("/\\"); slash != std::string_view::npos) {
    clientName.remove_prefix(slash + 1);
  }
  std::string name(clientName);
  for (char& c : name) {
    if (!nameCharacter(c)) c = '_';
  }
  for (std::size_t i = 0; i < name.size() && name[i] == '.'; ++i) name[i] = '_';
  if (name.empty()) name = "upload";
  std::string extension;
  if (const std::size_t dot = name.rfind('.');
      dot != std::string::npos && dot > 0 && name.size() - dot <= MAX_KEPT_EXTENSION) {
    extension = name.substr(dot);
    name.resize(dot);
  }
  if (name.size() + extension.size() > MAX_UPLOAD_STEM) name.resize(MAX_UPLOAD_STEM - extension.size());
  return {name, extension};
}

/// Moves `from` to `to` unless `to` exists (atomically: renameat2 RENAME_NOREPLACE, or link
/// and unlink where the file system lacks it). 0 or the errno; EEXIST when taken.
int moveNoReplace(const fs::path& from, const fs::path& to) {
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return 0;
  if (errno != EINVAL && errno != ENOSYS) return errno;
  if (::link(from.c_str(), to.c_str()) != 0) return errno;
  ::unlink(from.c_str());
  return 0;
}

/// Writes one tar.gz; every failure leaves a message in `failure` and returns false.
class ArchiveWriter {
 public:
  explicit ArchiveWriter(int fd) : m_archive(::archive_write_new()) {
    if (m_archive == nullptr) {
      m_failure = "libarchive cannot start an archive";
      return;
    }
    if (::archive_write_add_filter_gzip(m_archive) < ARCHIVE_WARN ||
        ::archive_write_set_format_pax_restricted(m_archive) < ARCHIVE_WARN ||
        ::archive_write_open_fd(m_archive, fd) < ARCHIVE_WARN) {
      fail();
    }
  }
  ArchiveWriter(const ArchiveWriter&) = delete;
  ArchiveWriter& operator=(const ArchiveWriter&) = delete;
  ~ArchiveWriter() {
    if (m_archive != nullptr) ::archive_write_free(m_archive);
  }

  [[nodiscard]] bool ok() const noexcept { return m_failure.empty(); }
  [[nodiscard]] const std::string& failure() const noexcept { return m_failure; }

  /// Adds `fileName` of the open folder `folderFd` as `entryName`, streamed in blocks of
  /// `buffer`'s size. A file that is no longer a regular file is skipped; one that shrank
  /// meanwhile is padded with zeros, one that grew is cut at the size it had when opened.
  bool addFile(int folderFd, const std::string& fileName, const std::string& entryName, std::vector<char>& buffer) {
    const int fd = ::openat(folderFd, fileName.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return errno == ELOOP || errno == ENOENT || failWith(fileName + ": " + errnoText(errno));
    struct stat info {};
    if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
      ::close(fd);
      return true;
    }
    archive_entry* entry = ::archive_entry_new();
    ::archive_entry_set_pathname(entry, entryName.c_str());
    ::archive_entry_set_filetype(entry, AE_IFREG);
    ::archive_entry_set_perm(entry, 0644);
    ::archive_entry_set_size(entry, info.st_size);
    ::archive_entry_set_mtime(entry, info.st_mtim.tv_sec, info.st_mtim.tv_nsec);
    const bool headerWritten = ::archive_write_header(m_archive, entry) >= ARCHIVE_WARN;
    ::archive_entry_free(entry);
    if (!headerWritten) {
      ::close(fd);
      return fail();
    }
    auto remaining = static_cast<std::uint64_t>(info.st_size);
    while (remaining > 0) {
      const ssize_t got = ::read(fd, buffer.data(), std::min<std::uint64_t>(remaining, buffer.size()));
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) {
        const int saved = errno;
        ::close(fd);
        return failWith(fileName + ": " + errnoText(saved));
      }
      if (got == 0) break;  // shrank: finishing the entry pads it
      if (::archive_write_data(m_archive, buffer.data(), static_cast<std::size_t>(got)) < 0) {
        ::close(fd);
        return fail();
      }
      remaining -= static_cast<std::uint64_t>(got);
    }
    ::close(fd);
    return ::archive_write_finish_entry(m_archive) >= ARCHIVE_WARN || fail();
  }

  /// Flushes the compressor and the end-of-archive blocks.
  bool close() { return ::archive_write_close(m_archive) >= ARCHIVE_WARN || fail(); }

 private:
  bool fail() {
    const char* reason = ::archive_error_string(m_archive);
    return failWith(reason != nullptr ? reason : "libarchive failed");
  }
  bool failWith(std::string reason) {
    if (m_failure.empty()) m_failure = std::move(reason);
    return false;
  }

  archive* m_archive;
  std::string m_failure;
};

}  // namespace

bool validEntryName(std::string_view name) noexcept {
  if (name.empty() || name.size() > MAX_ENTRY_NAME || name.front() == '.') return false;
  return std::all_of(name.begin(), name.end(), nameCharacter);
}

DataFolder::DataFolder(fs::path root) : m_root(std::move(root)) {}

fs::path DataFolder::incomingFolder() const {
  return m_root / "uploads" / ".incoming";
}
fs::path DataFolder::cacheFolder() const {
  return m_root / "cache";
}

Status DataFolder::prepare() const {
  std::error_code error;
  if (!fs::exists(m_root, error)) {
    fs::create_directories(m_root, error);
    if (error) return Error{"cannot create the data folder: " + error.message(), Location{m_root.string(), 0, 0, {}}};
    ::chmod(m_root.c_str(), FOLDER_MODE);
  }
  for (const fs::path& folder : {m_root, m_root / "recordings", m_root / "uploads", incomingFolder(), cacheFolder()}) {
    if (Status made = ensureFolder(folder); !made) return made;
  }
  const std::time_t dayAgo = std::time(nullptr) - CACHE_MAX_AGE_S;
  removeOlderThan(cacheFolder(), dayAgo);
  removeOlderThan(incomingFolder(), dayAgo);  // bodies of uploads that never finished
  return {};
}

std::vector<RecordingEntry> DataFolder::listRecordings() const {
  std::vector<RecordingEntry> entries;
  const fs::path container = m_root / "recordings";
  std::error_code error;
  for (fs::directory_iterator it(container, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    Result<fs::path> folder = resolveEntry(container, name, "recording");
    if (!folder) continue;
    if (std::optional<RecordingEntry> entry = describeFolder(*folder, name)) entries.push_back(std::move(*entry));
  }
  sortNewestFirst(entries);
  return entries;
}

std::vector<RecordingEntry> DataFolder::listUploads() const {
  std::vector<RecordingEntry> entries;
  const fs::path container = m_root / "uploads";
  std::error_code error;
  for (fs::directory_iterator it(container, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    Result<fs::path> file = resolveEntry(container, name, "upload");
    struct stat info {};
    if (!file || ::stat(file->c_str(), &info) != 0 || !S_ISREG(info.st_mode)) continue;
    entries.push_back(RecordingEntry{name, static_cast<std::uint64_t>(info.st_size), unixMs(info), {}});
  }
  sortNewestFirst(entries);
  return entries;
}

Result<fs::path> DataFolder::recording(std::string_view name) const {
  Result<fs::path> folder = resolveEntry(m_root / "recordings", name, "recording");
  if (!folder) return folder;
  std::error_code error;
  if (!fs::is_directory(*folder, error)) return Error{"recording '" + std::string(name) + "': not a folder"};
  return folder;
}

Result<fs::path> DataFolder::upload(std::string_view name) const {
  Result<fs::path> file = resolveEntry(m_root / "uploads", name, "upload");
  if (!file) return file;
  std::error_code error;
  if (!fs::is_regular_file(*file, error)) return Error{"upload '" + std::string(name) + "': not a regular file"};
  return file;
}

Result<fs::path> DataFolder::archiveRecording(std::string_view name) const {
  Result<fs::path> folder = recording(name);
  if (!folder) return folder;
  const std::optional<RecordingEntry> contents = describeFolder(*folder, std::string(name));
  if (!contents) return Error{"recording '" + std::string(name) + "': cannot be read"};
  const std::string failurePrefix = "recording '" + std::string(name) + "': cannot make the archive: ";

  std::string target = (cacheFolder() / (std::string(name) + "-XXXXXX.tar.gz")).string();
  const int fd = ::mkstemps(target.data(), static_cast<int>(std::string_view(".tar.gz").size()));
  if (fd < 0) return Error{failurePrefix + cacheFolder().string() + ": " + errnoText(errno)};
  const int folderFd = ::open(folder->c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  std::string failure = folderFd < 0 ? errnoText(errno) : std::string();
  if (folderFd >= 0) {
    std::vector<char> buffer(ARCHIVE_BLOCK);
    ArchiveWriter writer(fd);
    for (const RecordedFile& file : contents->files) {
      if (!writer.ok() || !writer.addFile(folderFd, file.name, std::string(name) + "/" + file.name, buffer)) break;
    }
    if (writer.ok()) (void)writer.close();
    failure = writer.failure();
    ::close(folderFd);
  }
  if (::close(fd) != 0 && failure.empty()) failure = errnoText(errno);
  if (!failure.empty()) {
    ::unlink(target.c_str());
    return Error{failurePrefix + failure};
  }
  return fs::path(target);
}

Result<std::string> DataFolder::acceptUpload(const fs::path& incoming, std::string_view clientName) const {
  std::error_code error;
  const fs::path incomingRoot = fs::canonical(incomingFolder(), error);
  const fs::path parent = error ? fs::path() : fs::canonical(incoming.parent_path(), error);
  struct stat info {};
  if (error || parent != incomingRoot || ::lstat(incoming.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) {
    return Error{"upload '" + incoming.string() + "': not a file in " + incomingFolder().string()};
  }
  const auto [stem, extension] = sanitiseUploadName(clientName);
  const fs::path uploads = m_root / "uploads";
  for (int suffix = 1; suffix <= MAX_UPLOAD_SUFFIX; ++suffix) {
    const std::string name = suffix == 1 ? stem + extension : stem + "-" + std::to_string(suffix) + extension;
    const int moved = moveNoReplace(incoming, uploads / name);
    if (moved == 0) return name;
    if (moved != EEXIST) return Error{"upload '" + name + "': cannot be stored: " + errnoText(moved)};
  }
  return Error{"upload '" + stem + extension + "': too many uploads of that name"};
}

}  // namespace openvcu::web
