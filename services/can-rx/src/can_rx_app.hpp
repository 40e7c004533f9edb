#pragma once
// vcu-can-rx as an object over the service runtime: opens every configured bus's link,
// the iceoryx streams ("rx", "tx" for its own TP answers, "req", and the "send" streams of
// forwarding targets), builds the Receiver and puts links and timers into the loop.
//
//   auto appResult = canrx::CanRxApp::create(runtime);   // runtime: service::Service
//   if (!appResult) return service::reportStartupError(info, appResult.error());
//   return runtime.run();

#include <memory>

#include "openvcu/config/services.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/service/app.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::canrx {

inline constexpr signals::WriterId CAN_RX_WRITER = config::writerOf(config::ServiceId::CanRx);

struct CanRxAppImpl;

/// @note restricted thread-safe: lives on the service's loop thread.
using CanRxApp = service::App<CanRxAppImpl>;

}  // namespace openvcu::canrx

// Instantiated once, in can_rx_app.cpp (where CanRxAppImpl is defined).
extern template class openvcu::service::App<openvcu::canrx::CanRxAppImpl>;
