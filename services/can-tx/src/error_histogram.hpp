#pragma once
// |error| histogram of vcu-can-tx's period and SHM->SDM delta errors (heartbeat statistics
// tx.<Msg>.period_err_* and delta_err_*): log-linear buckets, so that p50 and p99 are
// percentiles however large the errors are, not the maximum.
//
//   cantx::ErrorHistogram histogram;
//   histogram.record(sendNs - previousNs - cycleNs);   // the sign does not matter
//   const auto summary = histogram.summary();          // {count, p50Us, p99Us, maxUs}
//
// Resolution: 1 us buckets from 0 to 2,048 us (LINEAR_US); above that, 32 buckets per
// doubling (2,048-4,096 us in 64 us steps, 4,096-8,192 us in 128 us steps, ...) up to
// 2^24 us = 16.8 s (RANGE_US): a percentile there is within 1/64 (1.6 %) of the true one
// (it reads as the middle of its bucket, never above the exact maximum). A percentile that
// falls at or beyond RANGE_US reads as RANGE_US: "at least 16.8 s". The maximum is exact.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace openvcu::cantx {

/// @note record() from one thread, summary() from any (relaxed atomics: a reader sees each
///       counter whole). record() is noexcept, allocation-free, constant time.
class ErrorHistogram {
 public:
  static constexpr std::int64_t LINEAR_US = 2048;       ///< 1 us buckets below this
  static constexpr std::size_t SUB_BUCKETS = 32;        ///< per doubling above LINEAR_US
  static constexpr std::int64_t RANGE_US = 1 << 24;     ///< 16,777,216 us: the top of the range
  static constexpr std::size_t OCTAVES = 13;            ///< 2^11 .. 2^24 us
  static constexpr std::size_t BUCKETS = LINEAR_US + OCTAVES * SUB_BUCKETS + 1;  ///< + the overflow bucket

  void record(std::int64_t errorNs) noexcept;
  struct Summary {
    std::uint64_t count{};
    std::int64_t p50Us{};
    std::int64_t p99Us{};
    std::int64_t maxUs{};
  };
  [[nodiscard]] Summary summary() const noexcept;

  /// The bucket of an error of `micros` (>= 0) us; BUCKETS - 1 is the overflow bucket.
  [[nodiscard]] static std::size_t bucketOf(std::int64_t micros) noexcept;
  /// The value a percentile in `bucket` reads as (us): its lower bound in the 1 us buckets,
  /// its middle above them, RANGE_US for the overflow bucket.
  [[nodiscard]] static std::int64_t valueOf(std::size_t bucket) noexcept;

 private:
  std::array<std::atomic<std::uint32_t>, BUCKETS> m_buckets{};
  std::atomic<std::uint64_t> m_count{};
  std::atomic<std::int64_t> m_maxNs{};
};

}  // namespace openvcu::cantx
