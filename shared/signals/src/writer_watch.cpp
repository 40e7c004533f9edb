#include "openvcu/signals/writer_watch.hpp"

#include <algorithm>

namespace openvcu::signals {

WriterChange WriterWatch::update(const std::optional<BusValue>& beat, std::uint64_t damageCount,
                                 std::int64_t nowNs) noexcept {
  if (beat && beat->updates > 0 && beat->quality != Quality::NeverReceived) {
    m_sinceNs = std::max(m_sinceNs, beat->timestampNs);
  }
  if (damageCount != m_damage) {
    m_damage = damageCount;
    // The heartbeat was wiped: its full timeout to come again. A writer lost before stays
    // lost until it really beats again.
    if (!m_lost) m_sinceNs = std::max(m_sinceNs, nowNs);
  }
  const bool lost = nowNs - m_sinceNs > m_timeoutNs;
  if (lost == m_lost) return WriterChange::None;
  m_lost = lost;
  return lost ? WriterChange::Lost : WriterChange::Back;
}

}  // namespace openvcu::signals
