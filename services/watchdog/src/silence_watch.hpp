#pragma once
// When a watched service counts as silent, and when vcu-watchdog may act on it: a class
// driven by explicit time and by the service's heartbeat slot as read, so that tests set
// the clock (docs/design/watchdog.md).
//
//   watchdog::SilenceWatch watch(1'500'000'000, startNs);           // silentAfterMs 1500
//   every 100 ms: switch (watch.update(table.readBus(slot), now)) {
//     case SilenceChange::Silent:  raise service_silent.<name>; break;
//     case SilenceChange::Beating: clear it; break;
//   }
//   if (watch.killDue(now)) { find the process; kill it; watch.killAttempted(now); }
//
// A beat is a new write of the slot (its update count moved). It counts from the time the
// service stamped on it, never later than the moment it was read and never earlier than
// the beat before it (or the watch's start: a service gets silentAfter from the watchdog's
// own start to be seen). The service is silent once the newest beat is older than
// silentAfter; it beats again with the next new write.

#include <cstdint>
#include <optional>

#include "openvcu/signals/table.hpp"

namespace openvcu::watchdog {

enum class SilenceChange : std::uint8_t {
  None,     ///< as before
  Silent,   ///< no beat for longer than silentAfter: raise the fault
  Beating,  ///< a beat arrived after a silence: clear the fault
};

/// A process that has not beaten since it started gets this long before it may be killed
/// (a start-up waits up to 5 s for iox-roudi, service::ROUDI_WAIT, and loads its DBC files).
inline constexpr std::int64_t START_GRACE_NS = 10'000'000'000;

/// @note restricted thread-safe: one thread; noexcept, allocation-free.
class SilenceWatch {
 public:
  /// `silentAfterNs` > 0; `startNs`: CLOCK_MONOTONIC when watching starts.
  SilenceWatch(std::int64_t silentAfterNs, std::int64_t startNs) noexcept
      : m_silentAfterNs(silentAfterNs), m_lastBeatNs(startNs) {}

  /// `beat`: the heartbeat slot's bus plane as read at `nowNs` (empty when the read failed:
  /// nothing changes but the time).
  SilenceChange update(const std::optional<signals::BusValue>& beat, std::int64_t nowNs) noexcept;

  [[nodiscard]] bool silent() const noexcept { return m_silent; }
  /// CLOCK_MONOTONIC of the newest beat (the watch's start before the first one).
  [[nodiscard]] std::int64_t lastBeatNs() const noexcept { return m_lastBeatNs; }
  /// How long the newest beat is ago.
  [[nodiscard]] std::int64_t silentForNs(std::int64_t nowNs) const noexcept { return nowNs - m_lastBeatNs; }
  [[nodiscard]] std::int64_t silentAfterNs() const noexcept { return m_silentAfterNs; }

  /// true while silent when no kill was attempted in this silence yet, or the last attempt
  /// is silentAfter ago (its process did not go, or the restarted one is silent too).
  [[nodiscard]] bool killDue(std::int64_t nowNs) const noexcept;
  /// Records an attempt (a kill, or a search that found no process to kill).
  void killAttempted(std::int64_t nowNs) noexcept { m_killAttemptNs = nowNs; }

  /// Whether the process that started at `processStartNs` (CLOCK_MONOTONIC) may be killed
  /// for this silence: it wrote the newest beat (stamped after its start: the silence is its
  /// own), or it is older than START_GRACE_NS without a beat of its own. A copy a supervisor
  /// just started, or a service still starting when the watchdog starts, is therefore never
  /// killed for a silence that is not its own.
  [[nodiscard]] bool mayKill(std::int64_t processStartNs, std::int64_t nowNs) const noexcept;

 private:
  std::int64_t m_silentAfterNs;
  std::int64_t m_lastBeatNs;
  std::optional<std::uint64_t> m_updates;  ///< the slot's update count at the newest beat
  std::optional<std::int64_t> m_stampNs;   ///< the newest beat's own time stamp, as written
  std::optional<std::int64_t> m_killAttemptNs;
  bool m_silent{};
};

}  // namespace openvcu::watchdog
