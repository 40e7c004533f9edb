// Kernel-free helpers of the socketcan link: SocketCAN structs <-> Frame, error frames ->
// bus events, IdFilter -> can_filter, control messages, error messages.
// Facts from linux/can.h, linux/can/error.h, linux/can/raw.h and the kernel's can.rst.

#include "openvcu/can/socketcan_codec.hpp"

#include <linux/can/error.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <utility>

namespace openvcu::can {
namespace {

/// CANFD_FDF (linux/can.h, since 6.2): marks a canfd_frame as CAN FD. The kernel sets it on
/// every FD frame it passes up; older kernels ignore it on send.
constexpr std::uint8_t FD_FORMAT_FLAG = 0x04;
#ifdef CANFD_FDF
static_assert(CANFD_FDF == FD_FORMAT_FLAG);
#endif

/// The kernel's can_id for a data or remote frame, or empty when the ID is out of range.
std::optional<canid_t> kernelId(const Frame& frame, bool remote) noexcept {
  const bool extended = frame.extended();
  if (frame.id > (extended ? CAN_EFF_MASK : CAN_SFF_MASK)) return std::nullopt;
  canid_t id = frame.id;
  if (extended) id |= CAN_EFF_FLAG;
  if (remote) id |= CAN_RTR_FLAG;
  return id;
}

/// can_id -> Frame id and the ID kind flags (FLAG_ERROR, FLAG_EXTENDED).
void splitKernelId(canid_t canId, Frame& frame) noexcept {
  if ((canId & CAN_ERR_FLAG) != 0) {
    frame.flags |= FLAG_ERROR;
    frame.id = canId & CAN_ERR_MASK;
  } else if ((canId & CAN_EFF_FLAG) != 0) {
    frame.flags |= FLAG_EXTENDED;
    frame.id = canId & CAN_EFF_MASK;
  } else {
    frame.id = canId & CAN_SFF_MASK;
  }
}

constexpr std::uint8_t CONTROLLER_PASSIVE = CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE;
constexpr std::uint8_t CONTROLLER_WARNING = CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING;

struct ErrnoEntry {
  int number;
  std::string_view name;
};
// A table, not a switch: EAGAIN == EWOULDBLOCK and ENOTSUP == EOPNOTSUPP on Linux.
constexpr std::array<ErrnoEntry, 33> ERRNO_NAMES{{
    {EPERM, "EPERM"},
    {ENOENT, "ENOENT"},
    {EINTR, "EINTR"},
    {EIO, "EIO"},
    {ENXIO, "ENXIO"},
    {EBADF, "EBADF"},
    {EAGAIN, "EAGAIN"},
    {ENOMEM, "ENOMEM"},
    {EACCES, "EACCES"},
    {EFAULT, "EFAULT"},
    {EBUSY, "EBUSY"},
    {ENODEV, "ENODEV"},
    {EINVAL, "EINVAL"},
    {ENFILE, "ENFILE"},
    {EMFILE, "EMFILE"},
    {ENOSPC, "ENOSPC"},
    {EPIPE, "EPIPE"},
    {ENOTSOCK, "ENOTSOCK"},
    {EMSGSIZE, "EMSGSIZE"},
    {EPROTOTYPE, "EPROTOTYPE"},
    {ENOPROTOOPT, "ENOPROTOOPT"},
    {EPROTONOSUPPORT, "EPROTONOSUPPORT"},
    {EOPNOTSUPP, "EOPNOTSUPP"},
    {EAFNOSUPPORT, "EAFNOSUPPORT"},
    {EADDRNOTAVAIL, "EADDRNOTAVAIL"},
    {ENETDOWN, "ENETDOWN"},
    {ENETUNREACH, "ENETUNREACH"},
    {ECONNRESET, "ECONNRESET"},
    {ENOBUFS, "ENOBUFS"},
    {ENOTCONN, "ENOTCONN"},
    {ETIMEDOUT, "ETIMEDOUT"},
    {EMEDIUMTYPE, "EMEDIUMTYPE"},
    {ENOSYS, "ENOSYS"},
}};

/// What an errno means when opening a CAN socket; the C library's text otherwise.
std::string reasonFor(int errorNumber) {
  switch (errorNumber) {
    case ENODEV:
      return "no such interface";
    case EAFNOSUPPORT:
      return "this kernel has no SocketCAN";
    case EPROTONOSUPPORT:
      return "this kernel has no CAN_RAW sockets (module can-raw)";
    case EMEDIUMTYPE:
      return "not a CAN interface";
    case ENETDOWN:
      return "interface is down";
    default:
      break;
  }
  return std::strerror(errorNumber);  // start-up only: one thread formats the message
}

}  // namespace

bool toCanFrame(const Frame& frame, can_frame& out) noexcept {
  if ((frame.flags & (FLAG_FD | FLAG_ERROR)) != 0 || frame.length > CLASSIC_DATA_LENGTH) return false;
  const bool remote = (frame.flags & FLAG_RTR) != 0;
  const std::optional<canid_t> maybeId = kernelId(frame, remote);
  if (!maybeId) return false;
  out = can_frame{};
  out.can_id = *maybeId;
  out.len = frame.length;
  if (!remote) std::memcpy(out.data, frame.data.data(), frame.length);
  return true;
}

bool toCanFdFrame(const Frame& frame, canfd_frame& out) noexcept {
  if ((frame.flags & FLAG_FD) == 0 || (frame.flags & (FLAG_RTR | FLAG_ERROR)) != 0 || frame.length > MAX_DATA_LENGTH) {
    return false;
  }
  const std::optional<canid_t> maybeId = kernelId(frame, false);
  if (!maybeId) return false;
  out = canfd_frame{};
  out.can_id = *maybeId;
  out.len = roundUpFdLength(frame.length);
  out.flags = FD_FORMAT_FLAG;
  if ((frame.flags & FLAG_BRS) != 0) out.flags |= CANFD_BRS;
  if ((frame.flags & FLAG_ESI) != 0) out.flags |= CANFD_ESI;
  std::memcpy(out.data, frame.data.data(), frame.length);  // the rest stays zero: the padding
  return true;
}

Frame fromCanFrame(const can_frame& in) noexcept {
  Frame frame;
  splitKernelId(in.can_id, frame);
  frame.length = std::min<std::uint8_t>(in.len, CLASSIC_DATA_LENGTH);
  const bool remote = (in.can_id & CAN_RTR_FLAG) != 0 && (frame.flags & FLAG_ERROR) == 0;
  if (remote) {
    frame.flags |= FLAG_RTR;
  } else {
    std::memcpy(frame.data.data(), in.data, frame.length);
  }
  return frame;
}

Frame fromCanFdFrame(const canfd_frame& in) noexcept {
  Frame frame;
  splitKernelId(in.can_id, frame);
  frame.flags |= FLAG_FD;
  if ((in.flags & CANFD_BRS) != 0) frame.flags |= FLAG_BRS;
  if ((in.flags & CANFD_ESI) != 0) frame.flags |= FLAG_ESI;
  frame.length = std::min<std::uint8_t>(in.len, MAX_DATA_LENGTH);
  std::memcpy(frame.data.data(), in.data, frame.length);
  return frame;
}

std::size_t encodeSocketFrame(const Frame& frame, bool fdLink, std::span<std::uint8_t, FD_DATAGRAM_SIZE> out) noexcept {
  if (frame.fd()) {
    canfd_frame fdFrame;
    if (!fdLink || !toCanFdFrame(frame, fdFrame)) return 0;
    std::memcpy(out.data(), &fdFrame, FD_DATAGRAM_SIZE);
    return FD_DATAGRAM_SIZE;
  }
  can_frame classicFrame;
  if (!toCanFrame(frame, classicFrame)) return 0;
  std::memcpy(out.data(), &classicFrame, CLASSIC_DATAGRAM_SIZE);
  return CLASSIC_DATAGRAM_SIZE;
}

std::optional<Frame> decodeSocketFrame(std::span<const std::uint8_t> datagram) noexcept {
  if (datagram.size() == CLASSIC_DATAGRAM_SIZE) {
    can_frame classicFrame;
    std::memcpy(&classicFrame, datagram.data(), CLASSIC_DATAGRAM_SIZE);
    return fromCanFrame(classicFrame);
  }
  if (datagram.size() == FD_DATAGRAM_SIZE) {
    canfd_frame fdFrame;
    std::memcpy(&fdFrame, datagram.data(), FD_DATAGRAM_SIZE);
    return fromCanFdFrame(fdFrame);
  }
  return std::nullopt;
}

std::size_t decodeErrorFrame(const Frame& frame, std::int64_t monotonicNs,
                             std::span<BusEvent, MAX_ERROR_EVENTS> out) noexcept {
  if ((frame.flags & FLAG_ERROR) == 0) return 0;
  const std::uint32_t errorClass = frame.id;
  const auto& data = frame.data;  // error frames carry 8 bytes (CAN_ERR_DLC); missing ones read as 0
  const bool counters = (errorClass & CAN_ERR_CNT) != 0;
  std::size_t count = 0;
  const auto emit = [&](BusEventKind kind, std::uint8_t status, std::uint8_t location) noexcept {
    BusEvent& event = out[count++];
    event.kind = kind;
    event.monotonicNs = monotonicNs;
    event.detail = errorEventDetail(errorClass, status, location);
    event.txErrors = counters ? data[6] : std::uint8_t{0};
    event.rxErrors = counters ? data[7] : std::uint8_t{0};
  };

  if ((errorClass & CAN_ERR_TX_TIMEOUT) != 0) emit(BusEventKind::TxTimeout, 0, 0);
  if ((errorClass & CAN_ERR_CRTL) != 0) {
    const std::uint8_t status = data[1];
    if ((status & CAN_ERR_CRTL_RX_OVERFLOW) != 0) emit(BusEventKind::RxOverflow, status, 0);
    if ((status & CAN_ERR_CRTL_TX_OVERFLOW) != 0) emit(BusEventKind::TxTimeout, status, 0);
    // One controller state per frame, the worst one: data[1] may say "TX passive, RX warning".
    if ((status & CONTROLLER_PASSIVE) != 0) {
      emit(BusEventKind::ErrorPassive, status, 0);
    } else if ((status & CONTROLLER_WARNING) != 0) {
      emit(BusEventKind::ErrorWarning, status, 0);
    } else if ((status & CAN_ERR_CRTL_ACTIVE) != 0) {
      emit(BusEventKind::ErrorActive, status, 0);
    }
  }
  if ((errorClass & (CAN_ERR_PROT | CAN_ERR_BUSERROR)) != 0) emit(BusEventKind::ProtocolError, data[2], data[3]);
  if ((errorClass & CAN_ERR_TRX) != 0) emit(BusEventKind::TransceiverError, data[4], 0);
  if ((errorClass & CAN_ERR_ACK) != 0) emit(BusEventKind::NoAck, 0, 0);
  if ((errorClass & CAN_ERR_BUSOFF) != 0) emit(BusEventKind::BusOff, 0, 0);
  if ((errorClass & CAN_ERR_RESTARTED) != 0) emit(BusEventKind::Restarted, 0, 0);
  return count;
}

can_filter toKernelFilter(const IdFilter& filter) noexcept {
  // Both flags in the mask: the frame's EFF bit must equal the filter's and its RTR bit must
  // be clear. The id never carries CAN_INV_FILTER (bit 29), so no filter is inverted.
  constexpr canid_t KIND_BITS = CAN_EFF_FLAG | CAN_RTR_FLAG;
  if (filter.extended) {
    return can_filter{(filter.id & CAN_EFF_MASK) | CAN_EFF_FLAG, (filter.mask & CAN_EFF_MASK) | KIND_BITS};
  }
  return can_filter{filter.id & CAN_SFF_MASK, (filter.mask & CAN_SFF_MASK) | KIND_BITS};
}

std::vector<can_filter> toKernelFilters(std::span<const IdFilter> filters) {
  std::vector<can_filter> kernelFilters;
  kernelFilters.reserve(filters.size());
  for (const IdFilter& filter : filters) {
    const std::uint32_t width = filter.extended ? CAN_EFF_MASK : CAN_SFF_MASK;
    if ((filter.id & filter.mask & ~width) != 0) continue;  // passes() never accepts a frame with it
    kernelFilters.push_back(toKernelFilter(filter));
  }
  return kernelFilters;
}

bool acceptedByFilters(std::span<const IdFilter> filters, const Frame& frame) noexcept {
  if (!filters.empty() && (frame.flags & (FLAG_RTR | FLAG_ERROR)) == FLAG_RTR) return false;
  return passes(filters, frame);
}

ReceiveMetadata parseControlMessages(const msghdr& message) noexcept {
  ReceiveMetadata metadata;
  // The CMSG_* macros take non-const pointers; they only read through them.
  auto* header = const_cast<msghdr*>(&message);
  const auto* base = static_cast<const unsigned char*>(message.msg_control);
  for (cmsghdr* item = CMSG_FIRSTHDR(header); item != nullptr; item = CMSG_NXTHDR(header, item)) {
    const auto offset = static_cast<std::size_t>(reinterpret_cast<const unsigned char*>(item) - base);
    if (item->cmsg_len > message.msg_controllen - offset) break;  // claims more than the buffer holds
    if (item->cmsg_level != SOL_SOCKET) continue;
    if (item->cmsg_type == SCM_TIMESTAMPNS && item->cmsg_len >= CMSG_LEN(sizeof(timespec))) {
      timespec stamp{};
      std::memcpy(&stamp, CMSG_DATA(item), sizeof stamp);
      metadata.timestampNs = std::int64_t{stamp.tv_sec} * 1'000'000'000 + stamp.tv_nsec;
    } else if (item->cmsg_type == SO_RXQ_OVFL && item->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
      std::uint32_t dropCount{};
      std::memcpy(&dropCount, CMSG_DATA(item), sizeof dropCount);
      metadata.dropCount = dropCount;
    }
  }
  return metadata;
}

std::string_view errnoName(int errorNumber) noexcept {
  for (const ErrnoEntry& entry : ERRNO_NAMES) {
    if (entry.number == errorNumber) return entry.name;
  }
  return {};
}

bool validInterfaceName(std::string_view name) noexcept {
  constexpr std::size_t MAX_NAME_LENGTH = 15;  // IFNAMSIZ 16 with the NUL
  if (name.empty() || name.size() > MAX_NAME_LENGTH || name == "." || name == "..") return false;
  return std::none_of(name.begin(), name.end(), [](char c) {
    return c == '/' || c == ':' || c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
  });
}

std::string openErrorMessage(std::string_view interface, std::string_view what, int errorNumber) {
  std::string message = "socketcan:";
  message.append(interface).append(": ");
  if (!what.empty()) message.append(what).append(": ");
  message.append(reasonFor(errorNumber)).append(" (");
  const std::string_view name = errnoName(errorNumber);
  if (name.empty()) {
    message.append("errno ").append(std::to_string(errorNumber));
  } else {
    message.append(name);
  }
  message.append(")");
  return message;
}

}  // namespace openvcu::can
