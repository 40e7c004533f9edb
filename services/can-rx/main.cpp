// vcu-can-rx: reads every configured bus, decodes into the signal table, handles the
// receive side of J1939 (requests, transport protocol, DM1, J1939-76), staleness and
// forwarding, and publishes every frame on the iceoryx "rx" stream. README.md.

#include "openvcu/service/main.hpp"

#include "can_rx_app.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  return service::runApp<openvcu::canrx::CanRxApp>(
      openvcu::config::ServiceId::CanRx, "CAN receive: decode every bus into the signal table", true, argc, argv);
}
