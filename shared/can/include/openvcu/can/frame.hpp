#pragma once
// The raw CAN / CAN FD frame every openvcu component passes around: plain data,
// fixed size, no pointers, so it can live in shared memory and in iceoryx samples.

#include <array>
#include <cstdint>
#include <span>
#include <type_traits>

namespace openvcu::can {

inline constexpr std::size_t MAX_DATA_LENGTH = 64;  ///< CAN FD payload limit
inline constexpr std::size_t CLASSIC_DATA_LENGTH = 8;
inline constexpr std::uint32_t STANDARD_ID_MASK = 0x7FFu;
inline constexpr std::uint32_t EXTENDED_ID_MASK = 0x1FFFFFFFu;

/// Frame flags (bit set in Frame::flags).
enum FrameFlag : std::uint8_t {
  FLAG_EXTENDED = 1u << 0,  ///< 29-bit identifier
  FLAG_FD = 1u << 1,        ///< CAN FD frame
  FLAG_BRS = 1u << 2,       ///< CAN FD bit-rate switch
  FLAG_ESI = 1u << 3,       ///< CAN FD error state indicator
  FLAG_RTR = 1u << 4,       ///< remote transmission request (classic CAN only)
  FLAG_ERROR = 1u << 5,     ///< error frame (id carries the SocketCAN error class)
};

/// One frame. `id` never carries flag bits; extended-ness is FLAG_EXTENDED.
struct Frame {
  std::int64_t timestampNs{};  ///< CLOCK_REALTIME (logs, kernel stamps) or monotonic, per producer
  std::uint32_t id{};
  std::uint8_t flags{};
  std::uint8_t length{};       ///< payload bytes, 0..64
  std::array<std::uint8_t, MAX_DATA_LENGTH> data{};

  [[nodiscard]] bool extended() const noexcept { return (flags & FLAG_EXTENDED) != 0; }
  [[nodiscard]] bool fd() const noexcept { return (flags & FLAG_FD) != 0; }
  [[nodiscard]] std::span<const std::uint8_t> payload() const noexcept {
    return {data.data(), length};
  }
};
static_assert(std::is_trivially_copyable_v<Frame>);
static_assert(std::is_standard_layout_v<Frame>);
static_assert(sizeof(Frame) == 80);

/// CAN FD DLC -> length (0..15 -> 0..64).
constexpr std::uint8_t dlcToLength(std::uint8_t dlc) noexcept {
  constexpr std::uint8_t TABLE[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  return TABLE[dlc & 0x0F];
}
/// Smallest CAN FD length that holds `length` bytes (e.g. 9 -> 12); 64 above 48.
constexpr std::uint8_t roundUpFdLength(std::size_t length) noexcept {
  for (std::uint8_t dlc = 0; dlc < 16; ++dlc) {
    if (dlcToLength(dlc) >= length) return dlcToLength(dlc);
  }
  return 64;
}

}  // namespace openvcu::can
