// vcu-can-rx: reads every configured bus, decodes into the signal table, handles the
// receive side of J1939 (requests, transport protocol, DM1, J1939-76), staleness and
// forwarding, and publishes every frame on the iceoryx "rx" stream. README.md.

#include "can_rx_app.hpp"
#include "openvcu/service/main.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  const service::ServiceInfo info{.name = "can-rx",
                                  .program = {},
                                  .description = "CAN receive: decode every bus into the signal table",
                                  .version = {},
                                  .writerId = openvcu::canrx::CAN_RX_WRITER,
                                  .usesFrameStreams = true};
  return service::runApp<openvcu::canrx::CanRxApp>(info, argc, argv);
}
