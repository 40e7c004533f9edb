#pragma once
// socketcan:IFACE: the Link backend over a Linux raw CAN / CAN FD socket (PF_CAN, CAN_RAW).
//
//   auto linkResult = can::openSocketCanLink("can0", options);
//   if (!linkResult) { std::cerr << linkResult.error().toString() << '\n'; return 1; }
//     -> "socketcan:can0: no such interface (ENODEV)"
//     -> "socketcan:can0: this kernel has no SocketCAN (EAFNOSUPPORT)"
//   can::Link& link = **linkResult;   // name() "socketcan:can0", kind() LinkKind::SocketCan
//
// What the link promises beyond link.hpp (design: docs/design/socketcan.md):
// - receive() returns data and remote frames only; error frames become bus events
//   (BusOff, ErrorPassive, ...) and are counted in stats().errorFrames.
// - Frames carry the kernel's receive stamp (SO_TIMESTAMPNS, CLOCK_REALTIME) in
//   frame.timestampNs and the same instant on CLOCK_MONOTONIC in monotonicNs.
// - Frames lost in the socket's receive buffer (SO_RXQ_OVFL) are counted in
//   stats().receiveDropped and reported as an RxOverflow event (detail = frames lost).
// - With filters, only data frames whose ID matches pass: remote (RTR) frames are dropped.
//   Up to 512 filters (CAN_RAW_FILTER_MAX) run in the kernel; more run in user space
//   (stats().filteredOut counts what they reject).
// - An interface that goes down or disappears later queues LinkDown; the link retries every
//   options.reopenInterval (a timerfd inside the wait handle, no polling) and queues LinkUp
//   when it is back. The first event of a link is LinkUp (or LinkDown when the interface
//   exists but is down at open: the link then waits for it).
// - Own frames are not received back (CAN_RAW_RECV_OWN_MSGS off); other sockets on this
//   host see them (CAN_RAW_LOOPBACK on), as with candump.

#include <memory>
#include <string>

#include "openvcu/can/link.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::can {

/// Opens the raw CAN socket on `interface` ("can0", "vcan0"; without the "socketcan:" prefix)
/// with `options` (fd, filters, errorFrames, reopenInterval; the bit rates are the
/// interface's business: `ip link set can0 type can bitrate 500000`).
/// Errors (one line, naming the interface and the OS reason): an invalid name, no SocketCAN
/// in the kernel, no such interface, not a CAN interface, CAN FD configured on a classic-only
/// interface, a refused socket option. An interface that exists but is down is not an error.
/// @note start-up only: allocates; the returned link's receive()/send() do not.
[[nodiscard]] Result<std::unique_ptr<Link>> openSocketCanLink(const std::string& interface, const LinkOptions& options);

}  // namespace openvcu::can
