#pragma once
// How long a frame occupies the bus, and how busy a bus is (ISO 11898-1:2015).
//
//   frameBits(standard 0x555, DLC 8, A5 A5 .. A5) -> 111  (108 frame bits, 0 stuff bits,
//                                                          3 intermission bits)
//   wireTimeNs(that frame, 500000, 2000000)      -> 222000  (111 bits x 2 us)
//
// The count is exact for classic frames: the CRC-15 of the real bit stream (SOF,
// arbitration, control, data) is computed and the stuff bits counted over SOF..CRC
// sequence, then CRC delimiter, ACK slot + delimiter, EOF (7) and intermission (3) are
// added. Classic frames go through a CRC-15 byte table and a stuffing table, a byte at a
// time (about 6x faster than bit by bit, docs/benchmarks.md); the bit-by-bit builder of
// wire_bits_reference.hpp is the reference they are tested against.
// CAN FD frames are exact under the ISO (not the non-ISO Bosch) rules: dynamic stuffing
// over SOF..data, the fixed-stuffed stuff count + CRC-17/21 field (whose values do not
// change its length); the two bits in which the bit rate switches (BRS, CRC delimiter)
// are counted whole at the nominal rate. Design: docs/design/replay-and-bus-load.md.

#include <array>
#include <chrono>
#include <cstdint>

#include "openvcu/can/frame.hpp"

namespace openvcu::can {

/// The bits of one frame on the wire, intermission included.
struct WireBits {
  std::uint32_t nominalBits{};  ///< bits sent at the nominal (arbitration) bit rate
  std::uint32_t dataBits{};     ///< bits sent at the data bit rate (CAN FD with BRS only, else 0)
  std::uint32_t stuffBits{};    ///< stuff bits included above (dynamic and CAN FD fixed ones)
  bool operator==(const WireBits&) const = default;
};

/// Error flag (6) + error delimiter (8) + intermission (3): what a FLAG_ERROR "frame" counts
/// as. The least an error costs the bus (superposed flags can add up to 6 bits).
inline constexpr std::uint32_t ERROR_FRAME_BITS = 17;

/// Bits of `frame` on the wire, by bit rate phase. Classic frames longer than 8 bytes
/// count as 8; a CAN FD length that is not a valid DLC length is rounded up (zero padding);
/// FLAG_RTR on a CAN FD frame is ignored (FD has no remote frames).
/// @note thread-safe, noexcept, allocation-free.
[[nodiscard]] WireBits wireBits(const Frame& frame) noexcept;

/// All bits of `frame` on the wire (nominalBits + dataBits of wireBits()).
/// Classic standard data frame: 47 + 8 x length + stuff bits; extended: 67 + 8 x length + stuff.
/// @note thread-safe, noexcept, allocation-free.
[[nodiscard]] std::uint32_t frameBits(const Frame& frame) noexcept;

/// The CRC-15 a classic frame carries (polynomial 0x4599, initial value 0, over the
/// unstuffed SOF..data bits). 0 for CAN FD and error frames.
/// @note thread-safe, noexcept, allocation-free.
[[nodiscard]] std::uint16_t classicCrc15(const Frame& frame) noexcept;

/// Time `frame` occupies the bus in ns, rounded to the nearest ns: nominal bits at
/// `bitrate`, data-phase bits (CAN FD with BRS) at `dataBitrate` (0: `bitrate`).
/// 0 when `bitrate` is 0.
/// @note thread-safe, noexcept, allocation-free.
[[nodiscard]] std::int64_t wireTimeNs(const Frame& frame, std::uint32_t bitrate, std::uint32_t dataBitrate) noexcept;

/// Bus load over a sliding window from the frames seen on a bus: the sum of their wire
/// times divided by the time covered. The window is a ring of BUCKET_COUNT fixed
/// buckets (default 10 x 100 ms), so add() allocates nothing and costs O(BUCKET_COUNT).
///
///   BusLoadMeter meter(500000, 2000000);
///   meter.add(frame, receivedFrame.monotonicNs);    // for every frame received
///   meter.loadPercent(nowNs);                        // 37.5
///
/// The load is reported as measured, not clamped: a real bus cannot exceed 100 %, but the
/// sim bus does not arbitrate (it moves frames as fast as they are sent), so an overloaded
/// sim bus reads above 100 % – that is the point of measuring it. During the first window
/// the time before the first frame counts as idle. A frame stamped older than the window
/// (or older than what a bucket now holds) is ignored.
/// @note restricted thread-safe: one thread at a time. add() and the queries are
///       noexcept and allocation-free.
class BusLoadMeter {
 public:
  static constexpr std::size_t BUCKET_COUNT = 10;

  /// `window` is clamped to at least BUCKET_COUNT ns.
  BusLoadMeter(std::uint32_t bitrate, std::uint32_t dataBitrate,
               std::chrono::nanoseconds window = std::chrono::seconds(1)) noexcept;

  /// Counts `frame` at `monotonicNs` (when it was on the bus, CLOCK_MONOTONIC).
  void add(const Frame& frame, std::int64_t monotonicNs) noexcept;

  /// Wire time of the frames of the last window ending at `nowNs`, in % of the time that
  /// window covers (the current, partly elapsed bucket and the BUCKET_COUNT - 1 before it).
  [[nodiscard]] double loadPercent(std::int64_t nowNs) const noexcept;
  /// The highest loadPercent() seen at any add() since construction or reset().
  [[nodiscard]] double peakPercent() const noexcept;
  /// Frames per second over the same window as loadPercent().
  [[nodiscard]] double framesPerSecond(std::int64_t nowNs) const noexcept;
  /// Frames counted since construction or reset().
  [[nodiscard]] std::uint64_t totalFrames() const noexcept { return m_totalFrames; }
  /// Forgets everything (buckets, peak, total).
  void reset() noexcept;

 private:
  struct Bucket {
    std::int64_t index{-1};  ///< monotonicNs / bucket width of the time it holds; -1: empty
    std::int64_t busyNs{};   ///< sum of wire times
    std::uint32_t frames{};
  };
  struct Window {
    std::int64_t busyNs{};
    std::uint64_t frames{};
    std::int64_t spanNs{};
  };
  [[nodiscard]] Window window(std::int64_t nowNs) const noexcept;

  std::uint32_t m_bitrate;
  std::uint32_t m_dataBitrate;
  std::int64_t m_bucketNs;
  std::array<Bucket, BUCKET_COUNT> m_buckets{};
  double m_peakPercent{};
  std::uint64_t m_totalFrames{};
};

}  // namespace openvcu::can
