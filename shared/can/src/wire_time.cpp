// Wire bits, wire time and bus load of CAN frames (ISO 11898-1:2015).
//
//   wireBits(standard 0x555, DLC 8, A5 x 8) -> {111, 0, 0}; wireTimeNs(it, 500000, 0) -> 222000
//
// wireBits dispatches: classic frames to the table-driven count (wire_bits_table.cpp),
// CAN FD frames to the bit-by-bit builder (wire_bits_reference.cpp), error frames to
// ERROR_FRAME_BITS.
#include "openvcu/can/wire_time.hpp"

#include <algorithm>
#include <cmath>

#include "openvcu/can/wire_bits_reference.hpp"
#include "wire_bits_internal.hpp"

namespace openvcu::can {

WireBits wireBits(const Frame& frame) noexcept {
  if ((frame.flags & FLAG_ERROR) != 0) return WireBits{ERROR_FRAME_BITS, 0, 0};
  // Why a table for classic frames only: they are most of the traffic, and the bit-by-bit
  // builder costs about 0.4 us a frame (docs/benchmarks.md, "Trace analysis").
  if (frame.fd()) return detail::referenceWireBits(frame);
  std::uint16_t crc = 0;
  return detail::classicWireBits(frame, crc);
}

std::uint32_t frameBits(const Frame& frame) noexcept {
  const WireBits bits = wireBits(frame);
  return bits.nominalBits + bits.dataBits;
}

std::uint16_t classicCrc15(const Frame& frame) noexcept {
  if ((frame.flags & FLAG_ERROR) != 0 || frame.fd()) return 0;
  std::uint16_t crc = 0;
  (void)detail::classicWireBits(frame, crc);
  return crc;
}

std::int64_t wireTimeNs(const Frame& frame, std::uint32_t bitrate, std::uint32_t dataBitrate) noexcept {
  if (bitrate == 0) return 0;
  const WireBits bits = wireBits(frame);
  const double dataRate = dataBitrate != 0 ? dataBitrate : bitrate;
  constexpr double NS_PER_S = 1e9;
  const double ns = static_cast<double>(bits.nominalBits) * NS_PER_S / bitrate +
                    static_cast<double>(bits.dataBits) * NS_PER_S / dataRate;
  return std::llround(ns);
}

BusLoadMeter::BusLoadMeter(std::uint32_t bitrate, std::uint32_t dataBitrate, std::chrono::nanoseconds window) noexcept
    : m_bitrate(bitrate),
      m_dataBitrate(dataBitrate),
      m_bucketNs(std::max<std::int64_t>(window.count() / static_cast<std::int64_t>(BUCKET_COUNT), 1)) {}

void BusLoadMeter::add(const Frame& frame, std::int64_t monotonicNs) noexcept {
  if (monotonicNs < 0) return;
  const std::int64_t index = monotonicNs / m_bucketNs;
  Bucket& bucket = m_buckets[static_cast<std::size_t>(index % static_cast<std::int64_t>(BUCKET_COUNT))];
  if (bucket.index > index) return;  // older than what the ring holds
  if (bucket.index < index) bucket = Bucket{index, 0, 0};
  bucket.busyNs += wireTimeNs(frame, m_bitrate, m_dataBitrate);
  ++bucket.frames;
  ++m_totalFrames;
  m_peakPercent = std::max(m_peakPercent, loadPercent(monotonicNs));
}

BusLoadMeter::Window BusLoadMeter::window(std::int64_t nowNs) const noexcept {
  Window result;
  if (nowNs < 0) return result;
  const std::int64_t newest = nowNs / m_bucketNs;
  const std::int64_t oldest = newest - static_cast<std::int64_t>(BUCKET_COUNT) + 1;
  for (const Bucket& bucket : m_buckets) {
    if (bucket.index >= oldest && bucket.index <= newest) {
      result.busyNs += bucket.busyNs;
      result.frames += bucket.frames;
    }
  }
  // The current bucket counts for the part of it that has elapsed (at least 1 ns).
  result.spanNs = (static_cast<std::int64_t>(BUCKET_COUNT) - 1) * m_bucketNs + (nowNs - newest * m_bucketNs);
  result.spanNs = std::max<std::int64_t>(result.spanNs, 1);
  return result;
}

double BusLoadMeter::loadPercent(std::int64_t nowNs) const noexcept {
  const Window sum = window(nowNs);
  constexpr double PERCENT = 100.0;
  return PERCENT * static_cast<double>(sum.busyNs) / static_cast<double>(sum.spanNs);
}

double BusLoadMeter::peakPercent() const noexcept {
  return m_peakPercent;
}

double BusLoadMeter::framesPerSecond(std::int64_t nowNs) const noexcept {
  const Window sum = window(nowNs);
  constexpr double NS_PER_S = 1e9;
  return static_cast<double>(sum.frames) * NS_PER_S / static_cast<double>(sum.spanNs);
}

void BusLoadMeter::reset() noexcept {
  m_buckets.fill(Bucket{});
  m_peakPercent = 0.0;
  m_totalFrames = 0;
}

}  // namespace openvcu::can
