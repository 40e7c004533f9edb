#include "reload_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>

namespace openvcu::fsm {
namespace {

namespace fs = std::filesystem;

/// Closes a file descriptor when it goes out of scope.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) noexcept : m_fd(fd) {}
  ~FileDescriptor() {
    if (m_fd >= 0) ::close(m_fd);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  [[nodiscard]] int get() const noexcept { return m_fd; }

 private:
  int m_fd;
};

Error refusal(const std::string& path, const std::string& reason) { return Error{path + ": " + reason, Location{path, 0, 0, {}}}; }

std::string errnoText(int error) { return std::strerror(error); }

/// realpath(3) as a string, or empty.
std::optional<std::string> canonical(const std::string& path) {
  std::array<char, PATH_MAX> buffer{};
  if (::realpath(path.c_str(), buffer.data()) == nullptr) return std::nullopt;
  return std::string(buffer.data());
}

/// true when `path` is `folder` itself or below it (both absolute and normal).
bool inside(const std::string& path, const std::string& folder) {
  if (folder == "/") return path.starts_with('/');
  return path.starts_with(folder) && (path.size() == folder.size() || path[folder.size()] == '/');
}

bool insideAny(const std::string& path, const std::vector<std::string>& folders) {
  for (const std::string& folder : folders) {
    if (inside(path, folder)) return true;
  }
  return false;
}

/// "/a/b/" -> "/a/b" (lexically_normal keeps a trailing separator).
std::string withoutTrailingSlash(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  return path;
}

}  // namespace

std::vector<std::string> reloadFolders(const config::VehicleConfig& vehicle) {
  std::vector<std::string> folders;
  std::error_code error;
  const auto add = [&](const std::string& folder) {
    if (folder.empty()) return;
    const fs::path absolute = fs::absolute(folder, error);
    if (error) return;
    const std::string normal = withoutTrailingSlash(absolute.lexically_normal().string());
    if (std::find(folders.begin(), folders.end(), normal) == folders.end()) folders.push_back(normal);
  };
  if (!vehicle.fsmFile.empty()) add(fs::path(vehicle.fsmFile).parent_path().string());
  add(vehicle.directory);
  return folders;
}

Result<std::string> readReloadFile(const std::string& path, const std::vector<std::string>& allowedFolders,
                                   std::size_t maxBytes) {
  const std::string shown = path.empty() ? std::string("(empty path)") : path;
  if (path.empty() || path.front() != '/') return refusal(shown, "not an absolute path");
  if (path.find('\0') != std::string::npos) return refusal(shown, "the path contains a NUL character");

  // Folders as configured (lexical) and with their symlinks resolved (canonical).
  std::vector<std::string> lexicalFolders;
  std::vector<std::string> canonicalFolders;
  for (const std::string& folder : allowedFolders) {
    lexicalFolders.push_back(withoutTrailingSlash(fs::path(folder).lexically_normal().string()));
    if (const auto resolved = canonical(folder)) canonicalFolders.push_back(*resolved);
  }
  std::string folderList;
  for (const std::string& folder : lexicalFolders) folderList += (folderList.empty() ? "" : ", ") + folder;
  const std::string outside = "outside the folders a reload may read (" + folderList + ")";

  // 1-2: lexically inside, before anything is asked of the file system.
  const std::string lexical = withoutTrailingSlash(fs::path(path).lexically_normal().string());
  if (!insideAny(lexical, lexicalFolders) && !insideAny(lexical, canonicalFolders)) return refusal(shown, outside);

  // 3: symlinks resolved, still inside.
  const auto resolved = canonical(lexical);
  if (!resolved) {
    const int error = errno;
    // Report "missing" only when the folder it would be in resolves inside: a symlinked
    // directory pointing elsewhere must not tell what exists there.
    const auto parent = canonical(fs::path(lexical).parent_path().string());
    if (!parent || !insideAny(*parent, canonicalFolders)) return refusal(shown, outside + " after resolving symlinks");
    return refusal(shown, "cannot open: " + errnoText(error));
  }
  if (!insideAny(*resolved, canonicalFolders)) return refusal(shown, outside + " after resolving symlinks");

  // 4: a regular file, known before opening it.
  struct stat before {};
  if (::lstat(resolved->c_str(), &before) != 0) return refusal(shown, "cannot open: " + errnoText(errno));
  if (S_ISDIR(before.st_mode)) return refusal(shown, "a directory, not a regular file");
  if (!S_ISREG(before.st_mode)) return refusal(shown, "not a regular file (a FIFO, device or socket)");
  if (static_cast<std::uint64_t>(before.st_size) > maxBytes) {
    return refusal(shown, "too large: " + std::to_string(before.st_size) + " bytes (at most " +
                              std::to_string(maxBytes) + ")");
  }

  // 5: open without blocking or following, then check what was really opened.
  const FileDescriptor file(::open(resolved->c_str(), O_RDONLY | O_NONBLOCK | O_NOFOLLOW | O_NOCTTY | O_CLOEXEC));
  if (file.get() < 0) return refusal(shown, "cannot open: " + errnoText(errno));
  struct stat opened {};
  if (::fstat(file.get(), &opened) != 0) return refusal(shown, "cannot open: " + errnoText(errno));
  if (!S_ISREG(opened.st_mode)) return refusal(shown, "not a regular file (it changed while being opened)");
  const auto where = canonical("/proc/self/fd/" + std::to_string(file.get()));
  if (!where) return refusal(shown, "cannot tell where the opened file lies (/proc/self/fd): refused");
  if (!insideAny(*where, canonicalFolders)) return refusal(shown, outside + " (it changed while being opened)");

  // 6: at most maxBytes, whatever the size said (the file may grow meanwhile).
  if (static_cast<std::uint64_t>(opened.st_size) > maxBytes) {
    return refusal(shown, "too large: " + std::to_string(opened.st_size) + " bytes (at most " +
                              std::to_string(maxBytes) + ")");
  }
  std::string content;
  content.reserve(static_cast<std::size_t>(opened.st_size));
  std::array<char, 64 * 1024> chunk{};
  for (;;) {
    const std::size_t wanted = std::min(chunk.size(), maxBytes + 1 - content.size());
    const ssize_t got = ::read(file.get(), chunk.data(), wanted);
    if (got == 0) break;
    if (got < 0) {
      if (errno == EINTR) continue;
      return refusal(shown, "cannot read: " + errnoText(errno));
    }
    content.append(chunk.data(), static_cast<std::size_t>(got));
    if (content.size() > maxBytes) return refusal(shown, "too large: more than " + std::to_string(maxBytes) + " bytes");
  }
  return content;
}

Result<Machine> loadReloadMachine(const std::string& path, const std::vector<std::string>& allowedFolders,
                                  const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                                  std::vector<Error>* diagnostics) {
  auto text = readReloadFile(path, allowedFolders, RELOAD_MAX_BYTES);
  if (!text) return text.error();
  std::vector<Error> found;
  auto machineResult = parseMachine(*text, path, vehicle, catalog, &found);
  const std::size_t errors = static_cast<std::size_t>(
      std::count_if(found.begin(), found.end(), [](const Error& error) { return error.severity == Severity::Error; }));
  if (diagnostics != nullptr) diagnostics->insert(diagnostics->end(), found.begin(), found.end());
  if (machineResult) return machineResult;
  const std::size_t shown = std::max<std::size_t>(errors, 1);
  std::string reason = std::to_string(shown) + (shown == 1 ? " error" : " errors");
  if (const Location& first = machineResult.error().location; first.line > 0) {
    reason += " (the first at line " + std::to_string(first.line) + ")";
  }
  return refusal(path, reason + "; details in vcu-fsm's log or from `vcu fsm check " + path + "`");
}

}  // namespace openvcu::fsm
