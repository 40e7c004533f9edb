// The systemd notify protocol as the services send it: datagrams on NOTIFY_SOCKET.

#include <doctest/doctest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "openvcu/service/notify.hpp"

namespace service = openvcu::service;
using namespace std::chrono_literals;

namespace {

/// A bound datagram socket standing in for systemd (a path in the build tree, or abstract).
class Receiver {
 public:
  explicit Receiver(std::string path) : m_path(std::move(path)) {
    m_fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    REQUIRE(m_fd >= 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    REQUIRE(m_path.size() < sizeof(address.sun_path));
    std::memcpy(address.sun_path, m_path.data(), m_path.size());
    socklen_t length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + m_path.size() + 1);
    if (m_path.front() == '@') {
      address.sun_path[0] = '\0';
      length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + m_path.size());
    } else {
      std::filesystem::remove(m_path);
    }
    REQUIRE(::bind(m_fd, reinterpret_cast<const sockaddr*>(&address), length) == 0);
  }
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;
  ~Receiver() {
    ::close(m_fd);
    if (m_path.front() != '@') std::filesystem::remove(m_path);
  }

  std::string receive() {
    pollfd pfd{m_fd, POLLIN, 0};
    if (::poll(&pfd, 1, 5000) <= 0) return {};
    char buffer[1024];
    const ssize_t got = ::recv(m_fd, buffer, sizeof(buffer), 0);
    return got > 0 ? std::string(buffer, static_cast<std::size_t>(got)) : std::string();
  }

 private:
  std::string m_path;
  int m_fd{-1};
};

std::string socketPath(const std::string& name) {
  const std::string directory = std::string(OPENVCU_BINARY_DIR) + "/tests/shared/service";
  std::filesystem::create_directories(directory);
  return directory + "/" + name + "-" + std::to_string(::getpid()) + ".sock";
}

}  // namespace

TEST_CASE("without a socket every notification is a no-op that returns false") {
  service::Notifier sut("");

  CHECK_FALSE(sut.enabled());
  CHECK_FALSE(sut.ready("ready"));
  CHECK_FALSE(sut.watchdog());
}

TEST_CASE("ready sends READY=1 with the status and this process as MAINPID in one datagram") {
  Receiver receiver(socketPath("notify-ready"));
  service::Notifier sut(socketPath("notify-ready"));

  REQUIRE(sut.ready("ready"));

  CHECK(receiver.receive() == "READY=1\nSTATUS=ready\nMAINPID=" + std::to_string(::getpid()));
}

TEST_CASE("stopping sends STOPPING=1 with a one-line status") {
  Receiver receiver(socketPath("notify-stopping"));
  service::Notifier sut(socketPath("notify-stopping"));

  REQUIRE(sut.stopping("stopping\n(SIGTERM)"));

  CHECK(receiver.receive() == "STOPPING=1\nSTATUS=stopping (SIGTERM)");
}

TEST_CASE("an '@' socket path addresses the abstract namespace") {
  const std::string abstract = "@openvcu-test-notify-" + std::to_string(::getpid());
  Receiver receiver(abstract);
  service::Notifier sut(abstract);

  REQUIRE(sut.watchdog());

  CHECK(receiver.receive() == "WATCHDOG=1");
}

TEST_CASE("the watchdog is kept at half the supervisor's WATCHDOG_USEC, only for the process it names") {
  ::setenv("WATCHDOG_USEC", "10000000", 1);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  const auto forUs = service::Notifier::fromEnvironment();
  ::setenv("WATCHDOG_PID", "1", 1);
  const auto forAnother = service::Notifier::fromEnvironment();
  ::unsetenv("WATCHDOG_USEC");
  ::unsetenv("WATCHDOG_PID");
  const auto none = service::Notifier::fromEnvironment();

  CHECK(forUs.watchdogInterval() == std::chrono::microseconds{5'000'000});
  CHECK_FALSE(forAnother.watchdogInterval().has_value());
  CHECK_FALSE(none.watchdogInterval().has_value());
}
