#include "openvcu/service/shutdown.hpp"

#include <signal.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace openvcu::service {

Result<ShutdownSignals> ShutdownSignals::install() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  if (const int rc = ::pthread_sigmask(SIG_BLOCK, &set, nullptr); rc != 0) {
    return Error{std::string("cannot block SIGTERM/SIGINT: ") + std::strerror(rc)};
  }
  const int fd = ::signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
  if (fd < 0) return Error{std::string("signalfd failed: ") + std::strerror(errno)};
  return ShutdownSignals(fd);
}

ShutdownSignals::ShutdownSignals(ShutdownSignals&& other) noexcept : m_fd(other.m_fd) {
  other.m_fd = -1;
}

ShutdownSignals& ShutdownSignals::operator=(ShutdownSignals&& other) noexcept {
  if (this != &other) {
    if (m_fd >= 0) ::close(m_fd);
    m_fd = other.m_fd;
    other.m_fd = -1;
  }
  return *this;
}

ShutdownSignals::~ShutdownSignals() {
  if (m_fd >= 0) ::close(m_fd);
}

std::optional<int> ShutdownSignals::take() noexcept {
  if (m_fd < 0) return std::nullopt;
  signalfd_siginfo info{};
  const ssize_t got = ::read(m_fd, &info, sizeof(info));
  if (got != static_cast<ssize_t>(sizeof(info))) return std::nullopt;
  return static_cast<int>(info.ssi_signo);
}

std::string signalName(int signalNumber) {
  switch (signalNumber) {
    case SIGTERM:
      return "SIGTERM";
    case SIGINT:
      return "SIGINT";
    case SIGKILL:
      return "SIGKILL";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal " + std::to_string(signalNumber);
  }
}

}  // namespace openvcu::service
