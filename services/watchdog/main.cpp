// vcu-watchdog: watches the heartbeat slots of the stack's services, raises
// service_silent.<name> when one stops beating, kills the hung process for its supervisor to
// restart it, and feeds the board's watchdog device only while every watched service beats.
// README.md; docs/design/watchdog.md.

#include "openvcu/service/main.hpp"

#include "watchdog_app.hpp"

namespace service = openvcu::service;

namespace {

/// Not in config::SERVICES (shared/config): vcu-watchdog writes nothing to the signal table,
/// so it has no heartbeat slot and its writer id stamps nothing; 9 is the next free id.
constexpr openvcu::signals::WriterId WATCHDOG_WRITER = 9;

}  // namespace

int main(int argc, char** argv) {
  const service::ServiceInfo info{
      .name = "watchdog",
      .program = {},
      .description = "service watchdog: a silent service is reported, killed for its supervisor to restart it",
      .version = {},
      .writerId = WATCHDOG_WRITER,
      .usesFrameStreams = false};
  return service::runApp<openvcu::watchdog::WatchdogApp>(info, argc, argv);
}
