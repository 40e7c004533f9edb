#pragma once
// vcu-fsm as an object over the service runtime: loads and checks the FSM file, runs the
// engine on its own thread (woken by signal-table changes and its own deadlines, never
// periodically), publishes transitions, faults and events on LCM, answers the operator
// switches and the reload command (docs/fsm.md).
//
//   auto appResult = fsm::FsmApp::create(runtime);   // runtime: service::Service
//   if (!appResult) return service::reportStartupError(info, appResult.error());
//   return runtime.run();

#include <memory>

#include "openvcu/core/result.hpp"
#include "openvcu/service/app.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::fsm {

struct FsmAppImpl;

/// @note restricted thread-safe: lives on the service's loop thread (it owns the engine
///       thread, which it stops before anything that thread uses goes away).
using FsmApp = service::App<FsmAppImpl>;

}  // namespace openvcu::fsm

// Instantiated once, in fsm_app.cpp (where FsmAppImpl is defined).
extern template class openvcu::service::App<openvcu::fsm::FsmAppImpl>;
