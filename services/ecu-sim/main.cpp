// vcu-ecu-sim: the simulated vehicle: every node but this VCU on the sim bus or a SocketCAN
// interface (the generic model: the DBC's cyclic messages and the file's rules; "hhea": the
// HHEA loader's VIC/BMS, PDU, OBC, DC-DC, Editron and four HVLP inverters), with fault
// injection. README.md.

#include "openvcu/service/main.hpp"

#include "ecu_sim_app.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  return service::runApp<openvcu::ecusim::EcuSimApp>(openvcu::config::ServiceId::EcuSim,
                                                     "the simulated vehicle: every other node on the bus, with faults",
                                                     true, argc, argv);
}
