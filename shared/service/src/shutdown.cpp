#include "openvcu/service/shutdown.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace openvcu::service {

Result<ShutdownSignals> ShutdownSignals::install() {
  // The parent before anything else: compared once the death signal is armed (below).
  const pid_t parent = ::getppid();
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  if (const int rc = ::pthread_sigmask(SIG_BLOCK, &set, nullptr); rc != 0) {
    return Error{std::string("cannot block SIGTERM/SIGINT: ") + std::strerror(rc)};
  }
  const int fd = ::signalfd(-1, &set, SFD_NONBLOCK | SFD_CLOEXEC);
  if (fd < 0) return Error{std::string("signalfd failed: ") + std::strerror(errno)};
  // A service ends with its supervisor (issue 19): when the parent (supervisord, the test
  // harness, a shell) dies, even by SIGKILL, the kernel sends this process SIGTERM, which
  // now arrives through the signalfd like any orderly stop. Armed after the mask, so the
  // signal is never taken with its default action. A parent that died before prctl() took
  // effect sends nothing: the process has been re-parented, getppid() differs from the
  // parent read above, and the SIGTERM is queued here by hand. (A service whose parent is
  // PID 1, e.g. under systemd, gets no signal from this: PID 1 does not die.)
  if (::prctl(PR_SET_PDEATHSIG, SIGTERM) != 0) {
    const int error = errno;
    ::close(fd);
    return Error{std::string("prctl(PR_SET_PDEATHSIG) failed: ") + std::strerror(error)};
  }
  if (::getppid() != parent) ::kill(::getpid(), SIGTERM);
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
