#include <ctime>
#include <random>

#include "openvcu/ipc/events.hpp"

namespace openvcu::ipc {

std::int64_t randomRequestId() {
  std::random_device seed;
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  std::mt19937_64 generator((static_cast<std::uint64_t>(seed()) << 32) ^ seed() ^
                            static_cast<std::uint64_t>(now.tv_sec * 1'000'000'000 + now.tv_nsec));
  return static_cast<std::int64_t>(generator() >> 20) | 1;
}

}  // namespace openvcu::ipc
