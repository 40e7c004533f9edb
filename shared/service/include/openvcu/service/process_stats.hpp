#pragma once
// CPU time and resident memory of a local process from /proc, for `vcu top` and the HMI's
// service health (one read per process and second; not for hot paths).
//
//   const std::int64_t ticks = service::processCpuTicks(pid);   // -1: gone or unreadable
//   percent = 100.0 * (ticks - previous) / service::clockTicksPerSecond() / seconds;

#include <cstdint>

namespace openvcu::service {

/// utime + stime of process `pid` in clock ticks (/proc/PID/stat), or -1.
[[nodiscard]] std::int64_t processCpuTicks(std::int32_t pid);
/// Its resident set in MB (10^6 bytes, /proc/PID/statm), or -1.
[[nodiscard]] double processRssMb(std::int32_t pid);
/// sysconf(_SC_CLK_TCK): the unit of processCpuTicks.
[[nodiscard]] double clockTicksPerSecond();

}  // namespace openvcu::service
