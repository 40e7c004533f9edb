#pragma once
// vcu-watchdog as an object over the service runtime: every WATCH_PERIOD it reads the
// heartbeat slot of each watched service (policy.hpp), raises the critical fault
// `service_silent.<name>` when one stays silent past silentAfterMs and clears it when it
// beats again, kills a silent service's process (SIGKILL; a sibling under the same
// supervisor, process_finder.hpp) so that its supervisor restarts it, and feeds the
// board's watchdog device once per FEED_PERIOD while every watched service beats.
//
//   auto appResult = watchdog::WatchdogApp::create(runtime);   // runtime: service::Service
//   if (!appResult) return service::reportStartupError(info, appResult.error());
//   return runtime.run();   // the app's destructor: magic close of the board watchdog

#include <chrono>

#include "openvcu/service/app.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::watchdog {

/// How often the heartbeat slots are read: a silence is seen at most this late.
inline constexpr std::chrono::milliseconds WATCH_PERIOD{100};
/// How often the board watchdog is fed while every watched service beats.
inline constexpr std::chrono::seconds FEED_PERIOD{1};

struct WatchdogAppImpl;

/// @note restricted thread-safe: lives on the service's loop thread; it starts no thread.
using WatchdogApp = service::App<WatchdogAppImpl>;

}  // namespace openvcu::watchdog

// Instantiated once, in watchdog_app.cpp (where WatchdogAppImpl is defined).
extern template class openvcu::service::App<openvcu::watchdog::WatchdogAppImpl>;
