#pragma once
// vcu-gpio as an object over the service runtime: opens the back end of the GPIO map,
// requests every line once, runs the outputs on a thread woken by signal-table changes and
// its delays, the inputs on a thread woken by line events and debounce deadlines (neither
// polls), answers commands for its keys, and drives the safe levels when it stops.
//
//   auto appResult = gpio::GpioApp::create(runtime);   // runtime: service::Service
//   if (!appResult) return service::reportStartupError(info, appResult.error());
//   return runtime.run();                              // the app's destructor: safe state

#include <memory>

#include "openvcu/core/result.hpp"
#include "openvcu/service/app.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::gpio {

struct GpioAppImpl;

/// @note restricted thread-safe: lives on the service's loop thread; it owns its two threads.
using GpioApp = service::App<GpioAppImpl>;

/// The command policy of vcu-gpio: it answers for the keys the catalog gives it (its lines'
/// levels "internal.gpio.*" and the signals its input lines are bound to). Accepted: the simulated input levels (sim back end only) and
/// overrides of input-bound signals; refused: the line status keys and plain commands of
/// input-bound signals (vcu-gpio writes those from the line).
service::CommandPolicy gpioCommandPolicy(const signals::Catalog& catalog, const config::GpioMap& map);

}  // namespace openvcu::gpio

// Instantiated once, in gpio_app.cpp (where GpioAppImpl is defined).
extern template class openvcu::service::App<openvcu::gpio::GpioAppImpl>;
