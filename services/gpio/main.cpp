// vcu-gpio: the VCU's relay outputs and hard-wired fault inputs (libgpiod or the simulated
// chip): outputs follow their bound signals with on/off delays, inputs become signals on edge
// events, safe levels on SIGTERM. README.md; the GPIO map: docs/gpio.md.

#include "openvcu/service/main.hpp"

#include "controller.hpp"
#include "gpio_app.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  return service::runApp<openvcu::gpio::GpioApp>(
      openvcu::config::ServiceId::Gpio, "GPIO lines: relay outputs follow their signals, inputs become signals", false,
      argc, argv);
}
