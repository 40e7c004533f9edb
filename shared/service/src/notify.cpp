#include "openvcu/service/notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <cstring>

namespace openvcu::service {

namespace {

std::string oneLine(std::string_view text) {
  std::string line(text);
  std::replace(line.begin(), line.end(), '\n', ' ');
  return line;
}

template <typename T>
std::optional<T> parseNumber(const char* text) {
  if (text == nullptr) return std::nullopt;
  T value{};
  const char* end = text + std::strlen(text);
  const auto [ptr, ec] = std::from_chars(text, end, value);
  if (ec != std::errc{} || ptr != end) return std::nullopt;
  return value;
}

}  // namespace

Notifier Notifier::fromEnvironment() {
  const char* socketPath = std::getenv("NOTIFY_SOCKET");
  std::optional<std::chrono::microseconds> watchdog;
  // WATCHDOG_PID, when present, names the process the watchdog is meant for (sd_watchdog_enabled(3)).
  const auto maybePid = parseNumber<long>(std::getenv("WATCHDOG_PID"));
  const bool forUs = !std::getenv("WATCHDOG_PID") || (maybePid && *maybePid == static_cast<long>(::getpid()));
  if (const auto maybeUsec = parseNumber<std::uint64_t>(std::getenv("WATCHDOG_USEC"));
      maybeUsec && *maybeUsec > 0 && forUs) {
    watchdog = std::chrono::microseconds{static_cast<std::int64_t>(*maybeUsec)};
  }
  return Notifier(socketPath != nullptr ? socketPath : "", watchdog);
}

Notifier::Notifier(std::string socketPath, std::optional<std::chrono::microseconds> watchdog)
    : m_socketPath(std::move(socketPath)), m_watchdog(watchdog) {}

Notifier::Notifier(Notifier&& other) noexcept
    : m_socketPath(std::move(other.m_socketPath)), m_watchdog(other.m_watchdog), m_fd(other.m_fd) {
  other.m_socketPath.clear();
  other.m_fd = -1;
}

Notifier& Notifier::operator=(Notifier&& other) noexcept {
  if (this != &other) {
    if (m_fd >= 0) ::close(m_fd);
    m_socketPath = std::move(other.m_socketPath);
    m_watchdog = other.m_watchdog;
    m_fd = other.m_fd;
    other.m_socketPath.clear();
    other.m_fd = -1;
  }
  return *this;
}

Notifier::~Notifier() {
  if (m_fd >= 0) ::close(m_fd);
}

bool Notifier::notify(std::string_view state) noexcept {
  if (m_socketPath.empty()) return false;
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (m_socketPath.size() >= sizeof(address.sun_path)) return false;
  // '@' stands for the abstract namespace (a leading NUL byte), as in systemd.
  std::memcpy(address.sun_path, m_socketPath.data(), m_socketPath.size());
  if (m_socketPath.front() == '@') address.sun_path[0] = '\0';
  const auto addressLength = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + m_socketPath.size() +
                                                    (m_socketPath.front() == '@' ? 0 : 1));
  if (m_fd < 0) {
    m_fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (m_fd < 0) return false;
  }
  const ssize_t sent = ::sendto(m_fd, state.data(), state.size(), MSG_NOSIGNAL | MSG_DONTWAIT,
                                reinterpret_cast<const sockaddr*>(&address), addressLength);
  return sent == static_cast<ssize_t>(state.size());
}

bool Notifier::ready(std::string_view status) {
  return notify("READY=1\nSTATUS=" + oneLine(status) + "\nMAINPID=" + std::to_string(::getpid()));
}

bool Notifier::stopping(std::string_view status) {
  return notify("STOPPING=1\nSTATUS=" + oneLine(status));
}

bool Notifier::status(std::string_view status) {
  return notify("STATUS=" + oneLine(status));
}

bool Notifier::watchdog() noexcept {
  return notify("WATCHDOG=1");
}

std::optional<std::chrono::microseconds> Notifier::watchdogInterval() const noexcept {
  if (!m_watchdog) return std::nullopt;
  return *m_watchdog / 2;
}

}  // namespace openvcu::service
