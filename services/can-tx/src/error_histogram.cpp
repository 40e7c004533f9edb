#include "error_histogram.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace openvcu::cantx {
namespace {

constexpr int FIRST_OCTAVE = static_cast<int>(std::bit_width(static_cast<std::uint64_t>(ErrorHistogram::LINEAR_US))) - 1;  // 11
constexpr int SUB_BITS = static_cast<int>(std::bit_width(ErrorHistogram::SUB_BUCKETS)) - 1;                               // 5
static_assert(ErrorHistogram::LINEAR_US == std::int64_t{1} << FIRST_OCTAVE);
static_assert(ErrorHistogram::RANGE_US ==
              std::int64_t{1} << (FIRST_OCTAVE + static_cast<int>(ErrorHistogram::OCTAVES)));

}  // namespace

std::size_t ErrorHistogram::bucketOf(std::int64_t micros) noexcept {
  if (micros < LINEAR_US) return static_cast<std::size_t>(std::max<std::int64_t>(micros, 0));
  if (micros >= RANGE_US) return BUCKETS - 1;
  const int octave = static_cast<int>(std::bit_width(static_cast<std::uint64_t>(micros))) - 1;  // 11..23
  const auto sub = static_cast<std::size_t>((micros >> (octave - SUB_BITS)) & (SUB_BUCKETS - 1));
  return static_cast<std::size_t>(LINEAR_US) + static_cast<std::size_t>(octave - FIRST_OCTAVE) * SUB_BUCKETS + sub;
}

std::int64_t ErrorHistogram::valueOf(std::size_t bucket) noexcept {
  if (bucket < static_cast<std::size_t>(LINEAR_US)) return static_cast<std::int64_t>(bucket);
  if (bucket >= BUCKETS - 1) return RANGE_US;
  const std::size_t index = bucket - static_cast<std::size_t>(LINEAR_US);
  const int octave = FIRST_OCTAVE + static_cast<int>(index / SUB_BUCKETS);
  const std::int64_t width = std::int64_t{1} << (octave - SUB_BITS);
  const std::int64_t lower = (std::int64_t{1} << octave) + static_cast<std::int64_t>(index % SUB_BUCKETS) * width;
  return lower + width / 2;
}

void ErrorHistogram::record(std::int64_t errorNs) noexcept {
  const std::int64_t error = errorNs < 0 ? -errorNs : errorNs;
  const std::size_t bucket = bucketOf(error / 1000);
  m_buckets[bucket].store(m_buckets[bucket].load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  m_count.store(m_count.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  if (error > m_maxNs.load(std::memory_order_relaxed)) m_maxNs.store(error, std::memory_order_relaxed);
}

ErrorHistogram::Summary ErrorHistogram::summary() const noexcept {
  Summary summary;
  std::array<std::uint32_t, BUCKETS> copy{};
  std::uint64_t total = 0;
  for (std::size_t b = 0; b < BUCKETS; ++b) {
    copy[b] = m_buckets[b].load(std::memory_order_relaxed);
    total += copy[b];
  }
  summary.count = total;
  summary.maxUs = m_maxNs.load(std::memory_order_relaxed) / 1000;
  if (total == 0) return summary;
  // nearest rank; the bucket's value, but never above the exact maximum
  auto percentile = [&](double fraction) {
    const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(fraction * static_cast<double>(total))));
    std::uint64_t seen = 0;
    for (std::size_t b = 0; b < BUCKETS; ++b) {
      seen += copy[b];
      if (seen >= rank) return b == BUCKETS - 1 ? RANGE_US : std::min(valueOf(b), summary.maxUs);
    }
    return summary.maxUs;  // a record() between the copy and the count: the top
  };
  summary.p50Us = percentile(0.50);
  summary.p99Us = percentile(0.99);
  return summary;
}

}  // namespace openvcu::cantx
