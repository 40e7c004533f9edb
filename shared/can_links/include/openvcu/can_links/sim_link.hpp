#pragma once
// The `sim:NAME` link: a virtual CAN bus over iceoryx for machines without SocketCAN
// (containers, CI, these build machines). Part of openvcu::can_links (it needs openvcu::ipc);
// the namespace stays openvcu::can: it is one more can::Link backend.
//
// Every process that opens sim:vehicle gets a link with one publisher and one subscriber
// on the topic ("openvcu", "sim.vehicle", "wire"). A sent frame is stamped at send
// (CLOCK_MONOTONIC in the sample, CLOCK_REALTIME in frame.timestampNs) and published;
// every other attached link receives it, in one order per sender; the sender's own
// frames are dropped by sender id, like a SocketCAN socket with loopback on and
// CAN_RAW_RECV_OWN_MSGS off. Frames sent before a peer's link exists are not delivered to
// it: like a node joining a bus late.
// The sim bus does not arbitrate: it moves frames as fast as they are sent. Bus load is
// computed by receivers from each frame's wire time at the configured bit rate
// (wire_time.hpp), so an overloaded sim bus shows up as a load above 100 %.
//
//   auto linkResult = can::openSimLink("vehicle", options);   // after ipc::Runtime::init
//
// Design: docs/design/can-links.md.

#include <memory>
#include <string>

#include "openvcu/can/link.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::can {

/// Opens sim:`busName` (1..32 of [A-Za-z0-9_-]). Needs an initialised ipc::Runtime.
/// Fails for a bad name or when iceoryx refuses the ports.
[[nodiscard]] Result<std::unique_ptr<Link>> openSimLink(const std::string& busName, const LinkOptions& options);

}  // namespace openvcu::can
