#pragma once
// vcu-can-tx as an object over the service runtime: loads the schedule and its overlay,
// opens every bus's link and the iceoryx streams ("tx" out; "send" and "req" in), starts the
// transmit thread, answers the schedule and override commands, and watches the heartbeats
// of the command writers (docs/design/can-tx.md).
//
//   auto appResult = cantx::CanTxApp::create(runtime);   // runtime: service::Service
//   if (!appResult) return service::reportStartupError(info, appResult.error());
//   return runtime.run();

#include <memory>

#include "openvcu/core/result.hpp"
#include "openvcu/service/app.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::cantx {

struct CanTxAppImpl;

/// @note restricted thread-safe: lives on the service's loop thread (it owns the transmit
///       thread, which it stops before anything that thread uses goes away).
using CanTxApp = service::App<CanTxAppImpl>;

}  // namespace openvcu::cantx

// Instantiated once, in can_tx_app.cpp (where CanTxAppImpl is defined).
extern template class openvcu::service::App<openvcu::cantx::CanTxAppImpl>;
