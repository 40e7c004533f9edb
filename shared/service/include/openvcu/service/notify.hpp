#pragma once
// Readiness for supervisors and tests: the systemd notify protocol (sd_notify(3)), written
// out here instead of linking libsystemd. A supervisor (systemd with Type=notify, or the
// test harness) puts the path of a Unix datagram socket in NOTIFY_SOCKET; the service sends
// newline-separated assignments to it:
//   "READY=1\nSTATUS=ready\nMAINPID=4242"   start-up finished, the service answers
//   "STOPPING=1\nSTATUS=stopping (SIGTERM)" orderly shutdown began
//   "WATCHDOG=1"                            still alive (when WATCHDOG_USEC asks for it)
//   "STATUS=bus vehicle: bus-off"           free-text status
// Without NOTIFY_SOCKET every call is a no-op that returns false. "@name" addresses an
// abstract socket. A receiver that checks the sender (systemd, the harness) reads the
// pid from the datagram's SCM_CREDENTIALS, so only the service process itself may send.

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace openvcu::service {

/// @note restricted thread-safe: one thread at a time; send calls never block (datagram,
///       MSG_DONTWAIT) and allocate only to join the message.
class Notifier {
 public:
  /// From NOTIFY_SOCKET (disabled when unset or empty) and WATCHDOG_USEC / WATCHDOG_PID.
  static Notifier fromEnvironment();
  /// Explicit socket path ("" disables); `watchdog`: the supervisor's WATCHDOG_USEC.
  explicit Notifier(std::string socketPath, std::optional<std::chrono::microseconds> watchdog = {});
  Notifier(Notifier&& other) noexcept;
  Notifier& operator=(Notifier&& other) noexcept;
  Notifier(const Notifier&) = delete;
  Notifier& operator=(const Notifier&) = delete;
  ~Notifier();

  [[nodiscard]] bool enabled() const noexcept { return !m_socketPath.empty(); }
  [[nodiscard]] const std::string& socketPath() const noexcept { return m_socketPath; }

  /// Sends `state` ("READY=1\nSTATUS=ready") as one datagram; false when disabled or the send failed.
  bool notify(std::string_view state) noexcept;
  bool ready(std::string_view status);     ///< READY=1, STATUS=status, MAINPID
  bool stopping(std::string_view status);  ///< STOPPING=1, STATUS=status
  bool status(std::string_view status);    ///< STATUS=status
  bool watchdog() noexcept;                ///< WATCHDOG=1

  /// How often to send WATCHDOG=1 (half of WATCHDOG_USEC), when the supervisor asked this
  /// process for it; empty otherwise.
  [[nodiscard]] std::optional<std::chrono::microseconds> watchdogInterval() const noexcept;

 private:
  std::string m_socketPath;
  std::optional<std::chrono::microseconds> m_watchdog;
  int m_fd{-1};
};

}  // namespace openvcu::service
