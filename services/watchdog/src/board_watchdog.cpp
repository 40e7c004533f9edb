#include "board_watchdog.hpp"

#include <fcntl.h>
#include <linux/watchdog.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace openvcu::watchdog {

Result<BoardWatchdog> BoardWatchdog::open(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) return Error{path + ": " + std::strerror(errno)};
  int timeout = 0;
  std::optional<int> timeoutS;
  if (::ioctl(fd, WDIOC_GETTIMEOUT, &timeout) == 0 && timeout > 0) timeoutS = timeout;
  return BoardWatchdog(fd, path, timeoutS);
}

BoardWatchdog::BoardWatchdog(BoardWatchdog&& other) noexcept
    : m_fd(std::exchange(other.m_fd, -1)),
      m_path(std::move(other.m_path)),
      m_timeoutS(other.m_timeoutS),
      m_feeds(other.m_feeds) {}

BoardWatchdog& BoardWatchdog::operator=(BoardWatchdog&& other) noexcept {
  if (this != &other) {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = std::exchange(other.m_fd, -1);
    m_path = std::move(other.m_path);
    m_timeoutS = other.m_timeoutS;
    m_feeds = other.m_feeds;
  }
  return *this;
}

BoardWatchdog::~BoardWatchdog() {
  if (m_fd >= 0) ::close(m_fd);
}

bool BoardWatchdog::feed() noexcept {
  if (m_fd < 0) return false;
  const char keepAlive = '1';
  if (::write(m_fd, &keepAlive, 1) != 1) return false;
  ++m_feeds;
  return true;
}

bool BoardWatchdog::disarm() noexcept {
  if (m_fd < 0) return false;
  const char magic = 'V';
  const bool written = ::write(m_fd, &magic, 1) == 1;
  ::close(std::exchange(m_fd, -1));
  return written;
}

}  // namespace openvcu::watchdog
