#include "openvcu/core/input_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace openvcu::input {
namespace {

std::string errnoText(int error) { return error != 0 ? std::strerror(error) : "unknown error"; }

/// "64 MiB", "64 GiB", else the byte count.
std::string limitText(std::uint64_t bytes) {
  if (bytes % (std::uint64_t{1} << 30) == 0) return std::to_string(bytes >> 30) + " GiB";
  if (bytes % (std::uint64_t{1} << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes) + " bytes";
}

std::string tooLarge(std::string_view size, FileKind kind) {
  return "too large: " + std::string(size) + " bytes (a " + std::string(kind.name) + " may have at most " +
         limitText(kind.maxBytes) + ")";
}

Error fileError(const std::string& path, std::string message) {
  return Error{std::move(message), Location{path, 0, 0, {}}};
}

}  // namespace

std::string_view fileTypeName(unsigned int mode) noexcept {
  switch (mode & S_IFMT) {
    case S_IFREG: return "regular file";
    case S_IFDIR: return "directory";
    case S_IFCHR: return "character device";
    case S_IFBLK: return "block device";
    case S_IFIFO: return "FIFO";
    case S_IFSOCK: return "socket";
    case S_IFLNK: return "symbolic link";
    default: return "unknown file type";
  }
}

bool stopSignalPending() noexcept {
  sigset_t pending;
  sigemptyset(&pending);
  if (::sigpending(&pending) != 0) return false;
  return sigismember(&pending, SIGTERM) == 1 || sigismember(&pending, SIGINT) == 1;
}

Result<InputFile> InputFile::open(const std::string& path, FileKind kind) {
  if (path.empty()) return fileError(path, "no file name given");
  if (path.find('\0') != std::string::npos) return fileError(path, "the file name contains a NUL character");
  // O_NONBLOCK: opening a FIFO without a writer would otherwise wait for one.
  int fd = -1;
  do {
    fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  } while (fd < 0 && errno == EINTR);
  if (fd < 0) return fileError(path, "cannot open: " + errnoText(errno));
  struct stat status {};
  if (::fstat(fd, &status) != 0) {
    const int error = errno;
    ::close(fd);
    return fileError(path, "cannot open: " + errnoText(error));
  }
  if (!S_ISREG(status.st_mode)) {
    ::close(fd);
    return fileError(path, "not a regular file (" + std::string(fileTypeName(status.st_mode)) + ")");
  }
  const auto size = static_cast<std::uint64_t>(status.st_size);
  if (size > kind.maxBytes) {
    ::close(fd);
    return fileError(path, tooLarge(std::to_string(size), kind));
  }
  // Regular files never block; clear the flag so reads behave as usual.
  if (const int flags = ::fcntl(fd, F_GETFL); flags >= 0) (void)::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  return InputFile(fd, path, kind, size);
}

InputFile::InputFile(int fd, std::string path, FileKind kind, std::uint64_t size) noexcept
    : m_fd(fd), m_path(std::move(path)), m_kind(kind), m_size(size) {}

InputFile::InputFile(InputFile&& other) noexcept
    : m_fd(std::exchange(other.m_fd, -1)),
      m_path(std::move(other.m_path)),
      m_kind(other.m_kind),
      m_size(other.m_size),
      m_read(other.m_read) {}

InputFile& InputFile::operator=(InputFile&& other) noexcept {
  if (this != &other) {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = std::exchange(other.m_fd, -1);
    m_path = std::move(other.m_path);
    m_kind = other.m_kind;
    m_size = other.m_size;
    m_read = other.m_read;
  }
  return *this;
}

InputFile::~InputFile() {
  if (m_fd >= 0) ::close(m_fd);
}

InputFile::ReadOutcome InputFile::read(std::span<char> into) noexcept {
  if (stopSignalPending()) return {ReadStatus::StopPending, 0, 0};
  if (m_read > m_kind.maxBytes) return {ReadStatus::TooLarge, 0, 0};
  // One byte beyond the limit is enough to tell that the file grew past it.
  const std::uint64_t allowed = m_kind.maxBytes + 1 - m_read;
  const std::size_t wanted = allowed < into.size() ? static_cast<std::size_t>(allowed) : into.size();
  if (wanted == 0) return {ReadStatus::Data, 0, 0};
  for (;;) {
    const ssize_t got = ::read(m_fd, into.data(), wanted);
    if (got < 0 && errno == EINTR) {
      if (stopSignalPending()) return {ReadStatus::StopPending, 0, 0};
      continue;
    }
    if (got < 0) return {ReadStatus::Failed, 0, errno};
    if (got == 0) return {ReadStatus::End, 0, 0};
    m_read += static_cast<std::uint64_t>(got);
    if (m_read > m_kind.maxBytes) return {ReadStatus::TooLarge, 0, 0};
    return {ReadStatus::Data, static_cast<std::size_t>(got), 0};
  }
}

Error InputFile::describe(const ReadOutcome& outcome) const {
  switch (outcome.status) {
    case ReadStatus::StopPending: {
      sigset_t pending;
      sigemptyset(&pending);
      const bool term = ::sigpending(&pending) == 0 && sigismember(&pending, SIGTERM) == 1;
      return fileError(m_path, std::string("reading stopped: ") + (term ? "SIGTERM" : "SIGINT") + " is pending");
    }
    case ReadStatus::TooLarge:
      return fileError(m_path, tooLarge("more than " + std::to_string(m_kind.maxBytes), m_kind));
    case ReadStatus::Failed:
      return fileError(m_path, "cannot read: " + errnoText(outcome.error));
    case ReadStatus::Data:
    case ReadStatus::End:
      break;
  }
  return fileError(m_path, "read without a problem");
}

Result<std::string> readWholeFile(const std::string& path, FileKind kind) {
  Result<InputFile> openResult = InputFile::open(path, kind);
  if (!openResult) return openResult.error();
  InputFile& file = *openResult;
  std::string content;
  // The size at open, plus one chunk for a file that grows meanwhile (bounded by the limit).
  constexpr std::size_t CHUNK = 1 << 20;  // between two checks for a pending stop signal
  content.reserve(static_cast<std::size_t>(file.size()) + CHUNK);
  std::size_t used = 0;
  for (;;) {
    if (content.size() - used < CHUNK) content.resize(used + CHUNK);
    const InputFile::ReadOutcome outcome = file.read(std::span<char>(content.data() + used, content.size() - used));
    if (outcome.status == InputFile::ReadStatus::End) break;
    if (outcome.status != InputFile::ReadStatus::Data) return file.describe(outcome);
    used += outcome.count;
  }
  content.resize(used);
  return content;
}

}  // namespace openvcu::input
