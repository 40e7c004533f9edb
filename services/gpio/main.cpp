// vcu-gpio: the VCU's relay outputs and hard-wired fault inputs (libgpiod or the simulated
// chip): outputs follow their bound signals with on/off delays, inputs become signals on edge
// events, safe levels on SIGTERM. README.md; the GPIO map: docs/gpio.md.

#include "controller.hpp"
#include "gpio_app.hpp"
#include "openvcu/service/main.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  const service::ServiceInfo info{.name = "gpio",
                                  .program = {},
                                  .description = "GPIO lines: relay outputs follow their signals, inputs become signals",
                                  .version = {},
                                  .writerId = openvcu::gpio::GPIO_WRITER,
                                  .usesFrameStreams = false};
  return service::runApp<openvcu::gpio::GpioApp>(info, argc, argv);
}
