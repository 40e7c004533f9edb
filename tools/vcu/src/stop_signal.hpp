#pragma once
// SIGINT/SIGTERM end a long-running command (`vcu signal watch`, `vcu dump`) cleanly:
// while a StopSignalScope lives, the signals set a flag that stopRequested() reports;
// the previous handlers come back when it ends.

#include <csignal>

namespace openvcu::cli {

class StopSignalScope {
 public:
  StopSignalScope();
  StopSignalScope(const StopSignalScope&) = delete;
  StopSignalScope& operator=(const StopSignalScope&) = delete;
  ~StopSignalScope();

 private:
  struct sigaction m_previousInt {};
  struct sigaction m_previousTerm {};
};

/// true once SIGINT or SIGTERM arrived inside the current StopSignalScope.
[[nodiscard]] bool stopRequested() noexcept;

}  // namespace openvcu::cli
