#include "openvcu/trace/sample_ring.hpp"

#include <algorithm>

namespace openvcu::trace {

SampleRing::SampleRing(std::size_t capacity) : m_times(capacity), m_values(capacity) {}

void SampleRing::push(double timeSeconds, double value) noexcept {
  if (m_times.empty()) return;
  const std::size_t capacity = m_times.size();
  const std::size_t slot = (m_head + m_size) % capacity;
  m_times[slot] = timeSeconds;
  m_values[slot] = value;
  if (m_size < capacity) {
    ++m_size;
  } else {
    m_head = (m_head + 1) % capacity;
  }
}

std::size_t decimate(const SampleRing& ring, double t0, double t1, std::size_t columns,
                     std::vector<float>& out) noexcept {
  if (out.size() < columns * 3) return 0;  // the caller sizes it once per width
  if (columns == 0 || !(t1 > t0) || ring.size() == 0) return 0;
  // first sample inside the window (binary search: times are increasing)
  std::size_t low = 0;
  std::size_t high = ring.size();
  while (low < high) {
    const std::size_t mid = (low + high) / 2;
    if (ring.time(mid) < t0) {
      low = mid + 1;
    } else {
      high = mid;
    }
  }
  std::size_t filled = 0;
  long current = -1;
  for (std::size_t i = low; i < ring.size(); ++i) {
    const double t = ring.time(i);
    if (t >= t1) break;
    const double v = ring.value(i);
    const long column = std::min(static_cast<long>(columns) - 1,
                                 static_cast<long>((t - t0) / (t1 - t0) * static_cast<double>(columns)));
    if (column != current) {
      current = column;
      out[filled * 3] = static_cast<float>(column);
      out[filled * 3 + 1] = static_cast<float>(v);
      out[filled * 3 + 2] = static_cast<float>(v);
      ++filled;
    } else {
      out[(filled - 1) * 3 + 1] = std::min(out[(filled - 1) * 3 + 1], static_cast<float>(v));
      out[(filled - 1) * 3 + 2] = std::max(out[(filled - 1) * 3 + 2], static_cast<float>(v));
    }
  }
  return filled;
}

std::optional<ValueRange> valueRange(const SampleRing& ring) noexcept {
  if (ring.size() == 0) return std::nullopt;
  ValueRange range{ring.value(0), ring.value(0)};
  for (std::size_t i = 1; i < ring.size(); ++i) {
    range.low = std::min(range.low, ring.value(i));
    range.high = std::max(range.high, ring.value(i));
  }
  return range;
}

std::optional<std::size_t> sampleAtOrBefore(const SampleRing& ring, double timeSeconds) noexcept {
  if (ring.size() == 0) return std::nullopt;
  for (std::size_t i = ring.size(); i-- > 0;) {
    if (ring.time(i) <= timeSeconds) return i;
  }
  return 0;
}

}  // namespace openvcu::trace
