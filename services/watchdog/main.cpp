// vcu-watchdog: watches the heartbeat slots of the stack's services, raises
// service_silent.<name> when one stops beating, kills the hung process for its supervisor to
// restart it, and feeds the board's watchdog device only while every watched service beats.
// README.md; docs/design/watchdog.md.

#include "openvcu/service/main.hpp"

#include "watchdog_app.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  return service::runApp<openvcu::watchdog::WatchdogApp>(
      openvcu::config::ServiceId::Watchdog,
      "service watchdog: a silent service is reported, killed for its supervisor to restart it", false, argc, argv);
}
