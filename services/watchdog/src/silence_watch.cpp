#include "silence_watch.hpp"

#include <algorithm>

namespace openvcu::watchdog {

SilenceChange SilenceWatch::update(const std::optional<signals::BusValue>& beat, std::int64_t nowNs) noexcept {
  const bool written = beat && beat->updates > 0 && beat->quality != signals::Quality::NeverReceived;
  if (written && beat->updates != m_updates) {
    m_updates = beat->updates;
    m_stampNs = beat->timestampNs;
    m_lastBeatNs = std::clamp(beat->timestampNs, m_lastBeatNs, std::max(nowNs, m_lastBeatNs));
    if (m_silent) {
      m_silent = false;
      m_killAttemptNs.reset();
      return SilenceChange::Beating;
    }
  }
  if (!m_silent && nowNs - m_lastBeatNs > m_silentAfterNs) {
    m_silent = true;
    return SilenceChange::Silent;
  }
  return SilenceChange::None;
}

bool SilenceWatch::killDue(std::int64_t nowNs) const noexcept {
  if (!m_silent) return false;
  return !m_killAttemptNs || nowNs - *m_killAttemptNs >= m_silentAfterNs;
}

bool SilenceWatch::mayKill(std::int64_t processStartNs, std::int64_t nowNs) const noexcept {
  if (m_stampNs && *m_stampNs >= processStartNs) return true;
  return nowNs - processStartNs > START_GRACE_NS;
}

}  // namespace openvcu::watchdog
