#pragma once
// The board's watchdog device (/dev/watchdog, Linux watchdog API): once opened the timer
// runs, each write restarts it, and the board resets when it runs out. vcu-watchdog feeds
// it only while every watched service beats; a hung kernel, a dead feeder or a stopped
// feed lets it run out. An orderly stop writes the magic character 'V' before closing,
// which stops the timer (unless the kernel's nowayout is set).
//
//   auto boardResult = watchdog::BoardWatchdog::open("/dev/watchdog");
//   if (!boardResult) return boardResult.error();       // "/dev/watchdog: Permission denied"
//   once a second, while all services beat: boardResult->feed();
//   orderly stop: boardResult->disarm();                 // 'V', close
//
// A feed writes one byte '1' (never 'V': a 'V' in a feed would arm the magic close).

#include <cstdint>
#include <optional>
#include <string>

#include "openvcu/core/result.hpp"

namespace openvcu::watchdog {

/// @note restricted thread-safe: one thread; feed() and disarm() are noexcept and make one
///       write(2) each.
class BoardWatchdog {
 public:
  /// Opens `path` for writing (the timer starts for a real device). Errors name the path.
  static Result<BoardWatchdog> open(const std::string& path);

  BoardWatchdog(BoardWatchdog&& other) noexcept;
  BoardWatchdog& operator=(BoardWatchdog&& other) noexcept;
  BoardWatchdog(const BoardWatchdog&) = delete;
  BoardWatchdog& operator=(const BoardWatchdog&) = delete;
  /// Closes without the magic character: a real device keeps running and resets the board
  /// unless someone opens and feeds it again (what a crash of the feeder must do).
  ~BoardWatchdog();

  /// Restarts the device's timer. false when the write failed (errno kept).
  bool feed() noexcept;
  /// Writes 'V' and closes: the timer stops (magic close). Idempotent.
  bool disarm() noexcept;

  [[nodiscard]] const std::string& path() const noexcept { return m_path; }
  /// The device's timeout (WDIOC_GETTIMEOUT), empty for a device or file that does not say.
  [[nodiscard]] std::optional<int> timeoutSeconds() const noexcept { return m_timeoutS; }
  [[nodiscard]] std::uint64_t feeds() const noexcept { return m_feeds; }

 private:
  BoardWatchdog(int fd, std::string path, std::optional<int> timeoutS) noexcept
      : m_fd(fd), m_path(std::move(path)), m_timeoutS(timeoutS) {}
  int m_fd{-1};
  std::string m_path;
  std::optional<int> m_timeoutS;
  std::uint64_t m_feeds{};
};

}  // namespace openvcu::watchdog
