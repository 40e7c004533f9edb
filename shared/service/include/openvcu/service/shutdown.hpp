#pragma once
// SIGTERM and SIGINT as a file descriptor (signalfd), so an orderly stop arrives through the
// same wait as everything else: no handler runs at an arbitrary instruction, no flag is
// polled. Supervisors stop services with SIGTERM, and so does iox-roudi when it shuts down;
// install() also asks for a SIGTERM when the parent process dies (PR_SET_PDEATHSIG).
//
//   auto signalsResult = service::ShutdownSignals::install();   // first thing in main
//   loop.addFd(signalsResult->fd(), [&] { if (signalsResult->take()) loop.stop(0); });

#include <optional>
#include <string>

#include "openvcu/core/result.hpp"

namespace openvcu::service {

/// @note install() must run before the process starts any thread (iceoryx, LCM, the
///       Waiter's fd watcher): it blocks the signals in the calling thread, and only threads
///       created afterwards inherit the mask. A thread that does not block them could take
///       the signal with its default action (termination) instead. The mask stays blocked
///       after destruction (the process is ending; unblocking could deliver a pending
///       SIGTERM with its default action).
class ShutdownSignals {
 public:
  /// Blocks SIGTERM and SIGINT and opens a non-blocking signalfd for them.
  static Result<ShutdownSignals> install();

  ShutdownSignals(ShutdownSignals&& other) noexcept;
  ShutdownSignals& operator=(ShutdownSignals&& other) noexcept;
  ShutdownSignals(const ShutdownSignals&) = delete;
  ShutdownSignals& operator=(const ShutdownSignals&) = delete;
  ~ShutdownSignals();

  /// Readable when a signal is pending.
  [[nodiscard]] int fd() const noexcept { return m_fd; }

  /// The pending signal (SIGTERM or SIGINT), consumed; empty when none.
  std::optional<int> take() noexcept;

 private:
  explicit ShutdownSignals(int fd) noexcept : m_fd(fd) {}
  int m_fd{-1};
};

/// "SIGTERM", "SIGINT", else "signal N".
[[nodiscard]] std::string signalName(int signalNumber);

}  // namespace openvcu::service
