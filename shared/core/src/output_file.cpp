#include "openvcu/core/output_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace openvcu::output {

namespace {

Status writeAll(int fd, std::string_view text) {
  while (!text.empty()) {
    const ssize_t written = ::write(fd, text.data(), text.size());
    if (written < 0) {
      if (errno == EINTR) continue;
      return Error{std::strerror(errno)};
    }
    text.remove_prefix(static_cast<std::size_t>(written));
  }
  return {};
}

}  // namespace

Status writeFileAtomically(const std::string& path, std::string_view text, std::string_view what) {
  const std::filesystem::path target(path);
  const std::string folder = target.parent_path().empty() ? "." : target.parent_path().string();
  const std::string temporary = path + ".tmp-" + std::to_string(::getpid());
  const std::string name(what);
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Error{path + ": cannot write the " + name + ": " + std::strerror(errno)};
  Status written = writeAll(fd, text);
  if (written && ::fsync(fd) != 0) written = Error{std::strerror(errno)};
  ::close(fd);
  if (!written) {
    ::unlink(temporary.c_str());
    return Error{path + ": cannot write the " + name + ": " + written.error().message};
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const int saved = errno;
    ::unlink(temporary.c_str());
    return Error{path + ": cannot replace the " + name + ": " + std::strerror(saved)};
  }
  const int dirFd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dirFd >= 0) {
    ::fsync(dirFd);
    ::close(dirFd);
  }
  return {};
}

}  // namespace openvcu::output
