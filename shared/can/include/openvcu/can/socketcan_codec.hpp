#pragma once
// The parts of the socketcan link that need no kernel, exposed for tests (and for tools that
// speak SocketCAN's wire structs): frame conversion, error-frame decoding, filter
// conversion, control-message parsing, error messages, and the seam where the link meets
// the OS. Services include socketcan_link.hpp only; this header brings in <linux/can.h>.
//
//   Frame{id 0x18FEF100, FLAG_EXTENDED, length 2, 11 22}
//     -> can_frame{can_id 0x98FEF100 (CAN_EFF_FLAG | id), len 2, data 11 22}      (16 bytes)
//   Frame{id 0x123, FLAG_FD | FLAG_BRS, length 9}
//     -> canfd_frame{can_id 0x123, len 12 (zero padded), flags 0x05 (CANFD_FDF | CANFD_BRS)}  (72 bytes)
//   error frame can_id 0x20000044 (CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_BUSOFF), data[1] 0x20
//     -> BusEvent ErrorPassive, BusEvent BusOff
//   IdFilter{id 0x123, mask 0x7FF, extended false}
//     -> can_filter{can_id 0x123, can_mask 0xC00007FF (CAN_EFF_FLAG | CAN_RTR_FLAG | mask)}
//
// The rules behind each conversion are in docs/design/socketcan.md.

#include <linux/can.h>
#include <sys/socket.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/can/link.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::can {

// ---------------------------------------------------------------------------------------
// Frames. A raw CAN socket reads and writes one struct per datagram: can_frame (16 bytes)
// for classic frames, canfd_frame (72 bytes) for CAN FD frames (only with CAN_RAW_FD_FRAMES).

inline constexpr std::size_t CLASSIC_DATAGRAM_SIZE = sizeof(can_frame);  ///< CAN_MTU
inline constexpr std::size_t FD_DATAGRAM_SIZE = sizeof(canfd_frame);     ///< CANFD_MTU
static_assert(CLASSIC_DATAGRAM_SIZE == 16 && FD_DATAGRAM_SIZE == 72, "SocketCAN ABI (linux/can.h)");

/// Classic data or remote frame -> can_frame (RTR: len = requested length, no data).
/// false when it cannot be one: FLAG_FD or FLAG_ERROR set, length > 8, or an ID wider than
/// 11 bits (standard) / 29 bits (extended). BRS/ESI mean nothing on a classic frame and are ignored.
/// @note thread-safe, real-time safe.
[[nodiscard]] bool toCanFrame(const Frame& frame, can_frame& out) noexcept;

/// FLAG_FD frame -> canfd_frame: flags CANFD_FDF, plus CANFD_BRS / CANFD_ESI from FLAG_BRS /
/// FLAG_ESI; a length between the CAN FD sizes is rounded up and zero padded (9 -> 12), as
/// the controller would send it. false without FLAG_FD, with FLAG_RTR or FLAG_ERROR, length > 64
/// or an ID out of range. @note thread-safe, real-time safe.
[[nodiscard]] bool toCanFdFrame(const Frame& frame, canfd_frame& out) noexcept;

/// can_frame -> Frame (timestampNs 0): CAN_ERR_FLAG -> FLAG_ERROR with id = error class,
/// CAN_EFF_FLAG -> FLAG_EXTENDED, CAN_RTR_FLAG -> FLAG_RTR (length kept, data zero); a length
/// above 8 is cut to 8; len8_dlc is not kept. @note thread-safe, real-time safe.
[[nodiscard]] Frame fromCanFrame(const can_frame& in) noexcept;

/// canfd_frame -> Frame with FLAG_FD, FLAG_BRS / FLAG_ESI from CANFD_BRS / CANFD_ESI; length
/// cut to 64. CAN FD has no remote frames: CAN_RTR_FLAG is ignored. @note thread-safe, real-time safe.
[[nodiscard]] Frame fromCanFdFrame(const canfd_frame& in) noexcept;

/// Encodes `frame` as the datagram to write on a socket with (`fdLink`) or without CAN FD
/// enabled and returns its size: CLASSIC_DATAGRAM_SIZE for classic frames (on both kinds of
/// link), FD_DATAGRAM_SIZE for FD frames, 0 when the frame cannot go on this link
/// (SendStatus::Invalid). @note thread-safe, real-time safe.
[[nodiscard]] std::size_t encodeSocketFrame(const Frame& frame, bool fdLink,
                                            std::span<std::uint8_t, FD_DATAGRAM_SIZE> out) noexcept;

/// A datagram as read from a raw CAN socket -> Frame; empty unless it is exactly 16 or 72
/// bytes long. @note thread-safe, real-time safe.
[[nodiscard]] std::optional<Frame> decodeSocketFrame(std::span<const std::uint8_t> datagram) noexcept;

// ---------------------------------------------------------------------------------------
// Error frames (linux/can/error.h). Frame::id holds the error class bits.

/// Most events one error frame yields: TX timeout, RX overflow, TX overflow, one controller
/// state (passive > warning > active), protocol, transceiver, no ACK, bus-off, restarted.
inline constexpr std::size_t MAX_ERROR_EVENTS = 9;

/// BusEvent::detail of an event decoded from an error frame:
/// bits 0..15 the error class (can_id & 0xFFFF), bits 16..23 the class's status byte
/// (data[1] controller, data[2] protocol error type, data[4] transceiver), bits 24..31
/// data[3] (protocol error location).
constexpr std::uint32_t errorEventDetail(std::uint32_t errorClass, std::uint8_t status,
                                         std::uint8_t location) noexcept {
  return (errorClass & 0xFFFFu) | (std::uint32_t{status} << 16) | (std::uint32_t{location} << 24);
}

/// Turns one error frame (FLAG_ERROR) into bus events, written to `out` in the order of
/// MAX_ERROR_EVENTS; returns how many. Every event gets `monotonicNs` and, when the class has
/// CAN_ERR_CNT, txErrors = data[6] and rxErrors = data[7]. CAN_ERR_LOSTARB yields no event
/// (losing arbitration is normal bus operation); CAN_ERR_BUSERROR without CAN_ERR_PROT yields
/// ProtocolError; a controller TX overflow yields TxTimeout (a frame was not sent).
/// Returns 0 for a frame without FLAG_ERROR. @note thread-safe, real-time safe.
std::size_t decodeErrorFrame(const Frame& frame, std::int64_t monotonicNs,
                             std::span<BusEvent, MAX_ERROR_EVENTS> out) noexcept;

// ---------------------------------------------------------------------------------------
// Filters.

/// IdFilter -> can_filter. CAN_EFF_FLAG is in id and mask, so 11-bit filters only match
/// standard frames and 29-bit filters only extended ones; CAN_RTR_FLAG is in the mask (clear
/// in the id), so filters only match data frames. ID bits beyond 11/29 are dropped.
[[nodiscard]] can_filter toKernelFilter(const IdFilter& filter) noexcept;

/// The kernel list for `filters`. A filter that can never match (id & mask has bits beyond
/// 11/29, which passes() never accepts) is left out, so the result may be empty although
/// `filters` is not: installing an empty list then receives no frames, as intended.
/// @note start-up only (allocates).
[[nodiscard]] std::vector<can_filter> toKernelFilters(std::span<const IdFilter> filters);

/// true when the kernel takes `count` filters (CAN_RAW_FILTER_MAX, 512 in linux/can/raw.h);
/// beyond that the link receives everything and applies acceptedByFilters() itself.
constexpr bool fitsKernelFilters(std::size_t count) noexcept {
  return count <= CAN_RAW_FILTER_MAX;
}

/// What the kernel filters from toKernelFilters() accept, in user space: can::passes()
/// and, when there are filters, no remote frames. Error frames always pass.
/// @note thread-safe, real-time safe.
[[nodiscard]] bool acceptedByFilters(std::span<const IdFilter> filters, const Frame& frame) noexcept;

// ---------------------------------------------------------------------------------------
// Receive metadata (control messages of one recvmsg/recvmmsg datagram).

struct ReceiveMetadata {
  std::optional<std::int64_t> timestampNs;  ///< SCM_TIMESTAMPNS, CLOCK_REALTIME ns
  std::optional<std::uint32_t> dropCount;   ///< SO_RXQ_OVFL: frames this socket dropped so far (cumulative)
};

/// Reads the SCM_TIMESTAMPNS and SO_RXQ_OVFL control messages of `message`; others, short
/// ones and ones reaching past msg_controllen are ignored. @note thread-safe, real-time safe.
[[nodiscard]] ReceiveMetadata parseControlMessages(const msghdr& message) noexcept;

/// A CLOCK_REALTIME stamp moved to CLOCK_MONOTONIC with two clock readings taken together,
/// never later than `monotonicNowNs` (a stamp cannot be in the future).
constexpr std::int64_t realtimeToMonotonic(std::int64_t realtimeStampNs, std::int64_t realtimeNowNs,
                                           std::int64_t monotonicNowNs) noexcept {
  const std::int64_t ageNs = realtimeNowNs - realtimeStampNs;
  return ageNs > 0 ? monotonicNowNs - ageNs : monotonicNowNs;
}

// ---------------------------------------------------------------------------------------
// Errors.

/// "ENODEV", "EAFNOSUPPORT", ...; empty for numbers it does not know.
[[nodiscard]] std::string_view errnoName(int errorNumber) noexcept;

/// A Linux network interface name: 1..15 characters, not "." or "..", no '/', ':' or blanks.
[[nodiscard]] bool validInterfaceName(std::string_view name) noexcept;

/// "socketcan:<interface>: [<what>: ]<reason> (<ERRNO>)", e.g.
///   ("can0", "", ENODEV) -> "socketcan:can0: no such interface (ENODEV)"
///   ("can0", "cannot bind", EINVAL) -> "socketcan:can0: cannot bind: Invalid argument (EINVAL)"
[[nodiscard]] std::string openErrorMessage(std::string_view interface, std::string_view what, int errorNumber);

// ---------------------------------------------------------------------------------------
// The OS edge. The link opens its socket through a SocketOpener: at open and on every
// reopen attempt. openSocketCanLink() uses openRawCanSocket(); tests pass a socketpair.

/// What the socket must be set up with; prepared once at open, valid for the life of the link.
struct SocketSetup {
  const char* interfaceName{""};  ///< NUL terminated
  bool fd{};                      ///< CAN_RAW_FD_FRAMES
  bool errorFrames{};             ///< CAN_RAW_ERR_FILTER = CAN_ERR_MASK
  bool kernelFilters{};           ///< set CAN_RAW_FILTER to `filters` (empty: no frames)
  std::span<const can_filter> filters;
};

/// One attempt to open the socket.
struct SocketAttempt {
  int fd{-1};            ///< the bound, non-blocking socket, now owned by the caller; -1 on failure
  int errorNumber{};     ///< errno when fd < 0; ENETDOWN: the interface exists but is down
  const char* what{""};  ///< the step that failed ("cannot bind"); "" when the errno says it all
};

/// Must not throw or allocate: it runs inside receive() when the link reopens.
using SocketOpener = std::function<SocketAttempt(const SocketSetup&)>;

/// socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW); checks the interface
/// exists, is a CAN interface (ARPHRD_CAN) and, for FD, has the CAN FD MTU; sets the
/// options; binds; and fails with ENETDOWN (closing the socket) when the interface is not up.
/// @note allocation-free, never blocks.
[[nodiscard]] SocketAttempt openRawCanSocket(const SocketSetup& setup) noexcept;

/// openSocketCanLink() with the OS edge replaced.
[[nodiscard]] Result<std::unique_ptr<Link>> openSocketCanLinkWith(const std::string& interface,
                                                                  const LinkOptions& options, SocketOpener opener);

}  // namespace openvcu::can
