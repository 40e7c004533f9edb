#include "openvcu/config/transmit_limits.hpp"

#include <algorithm>
#include <cmath>

#include "openvcu/can/wire_time.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/vehicle.hpp"

namespace openvcu::config {

std::optional<std::string> checkCycleMs(double cycleMs) {
  if (std::isfinite(cycleMs) && cycleMs == std::trunc(cycleMs) && cycleMs >= MIN_CYCLE_MS && cycleMs <= MAX_CYCLE_MS) {
    return std::nullopt;
  }
  return "the cycle must be a whole number of ms from " + std::to_string(MIN_CYCLE_MS) + " to " +
         std::to_string(MAX_CYCLE_MS) + ", not " + formatNumber(cycleMs);
}

double cyclicBusLoad(std::span<const CyclicFrame> frames, const BusConfig& bus) noexcept {
  double load = 0;
  for (const CyclicFrame& cyclic : frames) {
    if (cyclic.cycleNs <= 0) continue;
    can::Frame frame;  // data all zero
    frame.id = cyclic.canId;
    frame.flags = cyclic.extended ? can::FLAG_EXTENDED : 0;
    if (cyclic.length > can::CLASSIC_DATA_LENGTH) frame.flags = static_cast<std::uint8_t>(frame.flags | can::FLAG_FD | can::FLAG_BRS);
    frame.length = std::min<std::uint8_t>(cyclic.length, static_cast<std::uint8_t>(can::MAX_DATA_LENGTH));
    load += static_cast<double>(can::wireTimeNs(frame, bus.bitrate, bus.dataBitrate)) /
            static_cast<double>(cyclic.cycleNs);
  }
  return load;
}

}  // namespace openvcu::config
