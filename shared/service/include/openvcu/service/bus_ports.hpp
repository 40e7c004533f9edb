#pragma once
// What a CAN service holds per configured bus: its link and its iceoryx streams
// (shared/ipc topics.hpp), opened in one call. vcu-can-rx and vcu-can-tx each hold one per
// bus, in the role that says which ends of the streams are theirs:
//
//   role          link   "rx"       "tx"       "send"                   "req"                         "net"
//   Receiver      yes    publishes  publishes  publishes (forwarding)   publishes (parsed requests)   publishes (claims, TP answers)
//   Transmitter   yes    -          publishes  subscribes (one-shots)   subscribes (to answer)        subscribes
//
//   auto portsResult = service::openBusPorts(runtime.instance(), bus, bus.linkOptions(), service::BusRole::Transmitter);
//   if (!portsResult) return portsResult.error();          // "bus 'vehicle': sim:vehicle: ..."
//   loop.addLink(*portsResult->link, [&] { drain(); });     // fd or sim subscriber alike

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "openvcu/can/link.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/request_stream.hpp"

namespace openvcu::service {

enum class BusRole : std::uint8_t {
  Receiver,     ///< vcu-can-rx
  Transmitter,  ///< vcu-can-tx
};

/// One bus's link and streams; the members the role does not use stay empty (table above).
/// Movable; the link and the ports do not move in memory (the loop may hold them).
/// @note restricted thread-safe: each member follows its own type's rule.
struct BusPorts {
  std::unique_ptr<can::Link> link;
  std::optional<ipc::FramePublisher> received;         ///< "rx"   (Receiver)
  std::optional<ipc::FramePublisher> sent;             ///< "tx"   (both)
  std::optional<ipc::FramePublisher> sendRequestsOut;  ///< "send" (Receiver: forwarding to this bus)
  std::optional<ipc::FrameSubscriber> sendRequestsIn;  ///< "send" (Transmitter)
  std::optional<ipc::RequestPublisher> requestsOut;    ///< "req"  (Receiver)
  std::optional<ipc::RequestSubscriber> requestsIn;    ///< "req"  (Transmitter)
  std::optional<ipc::FramePublisher> networkOut;       ///< "net"  (Receiver: J1939 network management)
  std::optional<ipc::FrameSubscriber> networkIn;       ///< "net"  (Transmitter)
};

/// Opens `bus`'s link with `options` (can::openLink) and the streams of `role` on
/// ("openvcu", "<instance>.<bus>", ...). Errors name the bus: "bus 'vehicle': ...".
/// Needs an initialised ipc::Runtime.
[[nodiscard]] Result<BusPorts> openBusPorts(const std::string& instance, const config::BusConfig& bus,
                                            const can::LinkOptions& options, BusRole role);

}  // namespace openvcu::service
