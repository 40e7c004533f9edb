#pragma once
// vcu-ecu-sim as an object over the service runtime: opens the configuration's buses as the
// other nodes (sim bus or SocketCAN), runs the node models (vehicle_model.hpp) on one thread
// with absolute deadlines (the model tick and each message's cycle), answers `vcu sim fault`
// (CommandKind::SimFault) and reports in its heartbeat and LCM fault events.
//
//   auto appResult = ecusim::EcuSimApp::create(runtime);
//   if (!appResult) return service::reportStartupError(info, appResult.error());
//   return runtime.run();

#include <memory>

#include "openvcu/core/result.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::ecusim {

inline constexpr signals::WriterId ECU_SIM_WRITER = config::writerOf(config::ServiceId::EcuSim);

struct EcuSimAppImpl;

/// @note restricted thread-safe: lives on the service's loop thread; owns the simulation thread.
class EcuSimApp {
 public:
  static Result<std::unique_ptr<EcuSimApp>> create(service::Service& runtime);
  ~EcuSimApp();
  EcuSimApp(const EcuSimApp&) = delete;
  EcuSimApp& operator=(const EcuSimApp&) = delete;

 private:
  explicit EcuSimApp(std::unique_ptr<EcuSimAppImpl> impl) noexcept;
  std::unique_ptr<EcuSimAppImpl> m_impl;
};

}  // namespace openvcu::ecusim
