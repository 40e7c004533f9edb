#pragma once
// SampleRing: (time, value) samples in a ring of fixed capacity, allocated once; the
// oldest sample goes when a new one arrives in a full ring. decimate(): per pixel column
// the lowest and highest value, so a line strip of 2 vertices per column draws any number
// of samples without losing a spike.
//
//   ring(4) after push(0,0) .. push(5,50): times 2 3 4 5
//   decimate(ring, 2, 6, 2 columns, out) -> 2; out = {0, 20, 30,  1, 40, 50}

#include <cstddef>
#include <optional>
#include <vector>

namespace openvcu::trace {

/// A ring of (time, value) samples with a fixed capacity (allocated at construction).
/// @note not thread-safe; push() and the readers are noexcept and allocation-free.
class SampleRing {
 public:
  explicit SampleRing(std::size_t capacity = 0);
  /// Appends; in a full ring the oldest sample is overwritten. Times must not decrease
  /// (decimate() searches them). A ring of capacity 0 keeps nothing.
  void push(double timeSeconds, double value) noexcept;
  void clear() noexcept {
    m_size = 0;
    m_head = 0;
  }
  [[nodiscard]] std::size_t size() const noexcept { return m_size; }
  [[nodiscard]] std::size_t capacity() const noexcept { return m_times.size(); }
  /// i-th oldest sample (i < size()).
  [[nodiscard]] double time(std::size_t i) const noexcept { return m_times[(m_head + i) % m_times.size()]; }
  [[nodiscard]] double value(std::size_t i) const noexcept { return m_values[(m_head + i) % m_values.size()]; }

 private:
  std::vector<double> m_times;
  std::vector<double> m_values;
  std::size_t m_head{};
  std::size_t m_size{};
};

/// Per pixel column the min and max of the samples in [t0, t1), for a line strip of at most
/// 2 * columns vertices. Writes (column, min, max) triples into `out`, which the caller sizes
/// to at least 3 * columns (else nothing is written); returns the columns filled. Columns
/// without samples are skipped. @note noexcept, allocation-free.
std::size_t decimate(const SampleRing& ring, double t0, double t1, std::size_t columns,
                     std::vector<float>& out) noexcept;

/// The lowest and highest value of a set of samples.
struct ValueRange {
  double low{};
  double high{};
};

/// The range of every sample in the ring; empty for an empty ring.
[[nodiscard]] std::optional<ValueRange> valueRange(const SampleRing& ring) noexcept;

/// The index of the newest sample at or before `timeSeconds`; the oldest sample when all
/// are later; empty for an empty ring.
[[nodiscard]] std::optional<std::size_t> sampleAtOrBefore(const SampleRing& ring, double timeSeconds) noexcept;

}  // namespace openvcu::trace
