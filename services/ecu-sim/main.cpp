// vcu-ecu-sim: the simulated vehicle: every node but this VCU (the HHEA loader's VIC/BMS, PDU,
// OBC, DC-DC, Editron and four HVLP inverters) on the sim bus or a SocketCAN interface, with
// fault injection. README.md.

#include "ecu_sim_app.hpp"
#include "openvcu/service/main.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  const service::ServiceInfo info{.name = "ecu-sim",
                                  .program = {},
                                  .description = "the simulated vehicle: every other node on the bus, with faults",
                                  .version = {},
                                  .writerId = openvcu::ecusim::ECU_SIM_WRITER,
                                  .usesFrameStreams = true};
  return service::runApp<openvcu::ecusim::EcuSimApp>(info, argc, argv);
}
