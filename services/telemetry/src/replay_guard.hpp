#pragma once
// vcu-telemetry's memory of the remote commands it has received (docs/design/telemetry.md,
// "Remote commands"): each cmdId with its deadline, kept until the deadline has passed, in a
// file of the queue folder, so a command runs at most once, across restarts too. A command's
// deadline is at most MAX_DEADLINE_AHEAD_MS ahead when it arrives, so the memory is bounded by
// time (and by MAX_REMEMBERED_COMMANDS), never by forgetting a command that could still run.
//
//   auto guard = ReplayGuard::open("/var/lib/openvcu/telemetry", &warnings);
//   guard->admit("c-17", 1764259205000, 1764259200000);  // empty: new, written and synced
//   guard->admit("c-17", 1764259205000, 1764259201000);  // -> {Replayed, "replayed: cmdId 'c-17' ..."}
//
// The file, remote-commands.seen (text, one line each, written with fdatasync before admit()
// returns, rewritten through a temporary file and rename when half of it is expired):
//   openvcu remote commands v1 floor 1764259190000
//   1764259205000 c-17
// The floor is the latest deadline forgotten: every command with a deadline at or before it is
// refused, so an expired entry cannot run again even when the clock is set back. A last line
// cut by a crash is dropped (its command was not sent: sending waits for the sync). Any other
// damage keeps the good lines and raises the floor to the file's modification time plus
// MAX_DEADLINE_AHEAD_MS (every command the lost lines named had a deadline before that).
//
// @note not thread-safe: one owner (vcu-telemetry's loop thread). One process per folder (the
//       disk queue's lock on the folder guarantees it).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::telemetry {

/// A deadlineUnixMs further ahead than this is refused (so no cmdId is remembered longer).
inline constexpr std::int64_t MAX_DEADLINE_AHEAD_MS = 10'000;
/// How many cmdIds within their deadlines are remembered at most; one more is refused "busy".
inline constexpr std::size_t MAX_REMEMBERED_COMMANDS = 1024;
/// The memory's file in the queue folder.
inline constexpr std::string_view REPLAY_FILE_NAME = "remote-commands.seen";

enum class ReplayRefusal : std::uint8_t {
  Replayed,     ///< the cmdId was received before and its deadline has not passed
  BeforeFloor,  ///< the deadline is not after the latest deadline forgotten
  Full,         ///< MAX_REMEMBERED_COMMANDS are remembered within their deadlines
  Io,           ///< the cmdId could not be written and synced: refused, so it cannot run twice
};

struct ReplayVerdict {
  ReplayRefusal kind{};
  std::string reason;  ///< for the answer: "replayed: cmdId 'c-17' was received before ..."
};

class ReplayGuard {
 public:
  /// Reads (or creates) folder/remote-commands.seen and rewrites it cleanly. Errors: the file
  /// cannot be read or written. Damage is a warning (see above), never an error.
  static Result<ReplayGuard> open(const std::string& folder, std::vector<Error>* warnings = nullptr);

  ReplayGuard(ReplayGuard&& other) noexcept;
  ReplayGuard& operator=(ReplayGuard&& other) noexcept;
  ReplayGuard(const ReplayGuard&) = delete;
  ReplayGuard& operator=(const ReplayGuard&) = delete;
  ~ReplayGuard();

  /// Forgets the cmdIds whose deadline is at or before nowUnixMs (raising the floor), then
  /// remembers cmdId until deadlineUnixMs, written and synced before it returns. Empty: the
  /// command is new. Otherwise why it must not run. The caller has checked that the deadline
  /// is after now and at most MAX_DEADLINE_AHEAD_MS ahead.
  std::optional<ReplayVerdict> admit(const std::string& cmdId, std::int64_t deadlineUnixMs, std::int64_t nowUnixMs);

  [[nodiscard]] std::size_t remembered() const noexcept { return m_deadlines.size(); }
  /// Every deadline at or before this is refused (0: none forgotten yet).
  [[nodiscard]] std::int64_t floorUnixMs() const noexcept { return m_floorUnixMs; }
  [[nodiscard]] const std::string& path() const noexcept { return m_path; }

 private:
  ReplayGuard() = default;
  void forgetExpired(std::int64_t nowUnixMs);
  /// The whole memory to a temporary file, synced, renamed over the file; the folder synced.
  Status rewrite();
  Status appendLine(const std::string& line);
  void closeFile() noexcept;

  std::string m_folder;
  std::string m_path;
  int m_fd{-1};  ///< the file, open for appending
  std::int64_t m_floorUnixMs{0};
  std::map<std::string, std::int64_t, std::less<>> m_deadlines;  ///< cmdId -> deadlineUnixMs
  std::size_t m_fileLines{0};                                    ///< entries in the file (live or not)
};

}  // namespace openvcu::telemetry
