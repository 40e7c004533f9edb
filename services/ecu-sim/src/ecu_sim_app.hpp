#pragma once
// vcu-ecu-sim as an object over the service runtime: opens the configuration's buses as the
// other nodes (sim bus or SocketCAN), runs the node models (simulation.json's "model": the
// HHEA models of vehicle_model.hpp, or the generic model of generic_model.hpp) on one thread
// with absolute deadlines (the model tick and each message's cycle), answers `vcu sim fault`
// (CommandKind::SimFault) and reports in its heartbeat and LCM fault events.
//
//   auto appResult = ecusim::EcuSimApp::create(runtime);
//   if (!appResult) return service::reportStartupError(info, appResult.error());
//   return runtime.run();

#include <memory>

#include "openvcu/core/result.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/service/app.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::ecusim {

inline constexpr signals::WriterId ECU_SIM_WRITER = config::writerOf(config::ServiceId::EcuSim);

struct EcuSimAppImpl;

/// @note restricted thread-safe: lives on the service's loop thread; owns the simulation thread.
using EcuSimApp = service::App<EcuSimAppImpl>;

}  // namespace openvcu::ecusim

// Instantiated once, in ecu_sim_app.cpp (where EcuSimAppImpl is defined).
extern template class openvcu::service::App<openvcu::ecusim::EcuSimAppImpl>;
