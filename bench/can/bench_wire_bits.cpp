// bench_wire_bits: CPU time of can::frameBits on random classic frames, one core.
//
//   bench_wire_bits [FRAMES] [PASSES]      (default 1000000 frames, 5 passes)
//   -> "can::frameBits: best 52.3 ns/frame, median 55.0 ns/frame (1000000 frames x 5 passes,
//       bits sum 121234567)"
//
// The frames are drawn once from a fixed seed (std::mt19937, seed 1939): half 11-bit, half
// 29-bit identifiers, DLC 0..8 uniform, random payload bytes, no RTR/FD/error frames. Each
// pass counts every frame; the time is thread CPU time (CLOCK_THREAD_CPUTIME_ID). The bits
// sum is printed so the calls cannot be optimised away, and is the same for any build that
// counts correctly. Results and the command: docs/benchmarks.md, section "Trace analysis".

#include <time.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "openvcu/can/wire_time.hpp"

namespace {

std::int64_t threadCpuNs() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  constexpr std::int64_t NS_PER_S = 1'000'000'000;
  return static_cast<std::int64_t>(now.tv_sec) * NS_PER_S + now.tv_nsec;
}

}  // namespace

int main(int argc, char** argv) {
  namespace can = openvcu::can;
  const long frameCount = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 1'000'000;
  const long passes = argc > 2 ? std::strtol(argv[2], nullptr, 10) : 5;
  if (frameCount <= 0 || passes <= 0) {
    std::fprintf(stderr, "usage: bench_wire_bits [FRAMES > 0] [PASSES > 0]\n");
    return 2;
  }
  std::mt19937 random(1939);
  std::vector<can::Frame> frames(static_cast<std::size_t>(frameCount));
  for (can::Frame& frame : frames) {
    frame.flags = (random() % 2) != 0 ? can::FLAG_EXTENDED : 0;
    frame.id = static_cast<std::uint32_t>(random()) & (frame.extended() ? can::EXTENDED_ID_MASK : can::STANDARD_ID_MASK);
    frame.length = static_cast<std::uint8_t>(random() % (can::CLASSIC_DATA_LENGTH + 1));
    for (std::size_t b = 0; b < frame.length; ++b) frame.data[b] = static_cast<std::uint8_t>(random());
  }
  std::vector<double> nsPerFrame;
  std::uint64_t bitsSum = 0;
  for (long pass = 0; pass < passes; ++pass) {
    std::uint64_t sum = 0;
    const std::int64_t start = threadCpuNs();
    for (const can::Frame& frame : frames) sum += can::frameBits(frame);
    const std::int64_t elapsed = threadCpuNs() - start;
    nsPerFrame.push_back(static_cast<double>(elapsed) / static_cast<double>(frameCount));
    bitsSum = sum;
  }
  std::sort(nsPerFrame.begin(), nsPerFrame.end());
  std::printf("can::frameBits: best %.1f ns/frame, median %.1f ns/frame (%ld frames x %ld passes, bits sum %llu)\n",
              nsPerFrame.front(), nsPerFrame[nsPerFrame.size() / 2], frameCount, passes,
              static_cast<unsigned long long>(bitsSum));
  std::printf("RESULT frame_bits_best_ns=%.1f frame_bits_median_ns=%.1f frames=%ld passes=%ld bits_sum=%llu\n",
              nsPerFrame.front(), nsPerFrame[nsPerFrame.size() / 2], frameCount, passes,
              static_cast<unsigned long long>(bitsSum));
  return 0;
}
