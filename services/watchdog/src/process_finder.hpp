#pragma once
// Finds the process of a watched service without trusting any message: it must be a
// sibling of vcu-watchdog (the same parent: the supervisord or systemd that started both)
// whose executable (/proc/<pid>/exe) is named "vcu-<name>". Nothing a process says about
// itself (heartbeat pids, its command line, its comm name) is used.
//
//   watchdog::ProcessFinder finder("/proc");
//   auto found = finder.find("vcu-fsm", ::getppid(), ::getpid());
//   // found.processes: [{pid 4711, startNs ...}], found.unreadable: processes of that
//   // parent whose executable could not be read (another user's)

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::watchdog {

struct FoundProcess {
  pid_t pid{};
  /// When it started, on CLOCK_MONOTONIC (from /proc/<pid>/stat's start time, 10 ms steps).
  std::int64_t startNs{};
  char state{};  ///< /proc/<pid>/stat's state: 'S', 'R', 'T' (stopped), ...
};

struct FindResult {
  std::vector<FoundProcess> processes;
  std::size_t unreadable{};  ///< children of the parent whose executable could not be read
};

/// The basename of an executable as /proc/<pid>/exe names it: "/usr/bin/vcu-fsm" ->
/// "vcu-fsm"; a file replaced since it started, "/build/bin/vcu-fsm (deleted)" -> "vcu-fsm".
[[nodiscard]] std::string_view executableName(std::string_view exeLink) noexcept;

/// @note allocates; a directory walk of /proc (a few hundred entries): once per kill attempt.
class ProcessFinder {
 public:
  /// `procRoot`: "/proc" (a test may point it elsewhere).
  explicit ProcessFinder(std::string procRoot = "/proc") : m_procRoot(std::move(procRoot)) {}

  /// The living processes (not zombies) with parent `parent`, other than `self`, whose
  /// executable's name is `program`.
  [[nodiscard]] FindResult find(std::string_view program, pid_t parent, pid_t self) const;

 private:
  std::string m_procRoot;
};

}  // namespace openvcu::watchdog
