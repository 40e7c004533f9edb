// vcu-can-tx: sends this VCU's schedule (cyclic messages, J1939-76 safety pairs, send
// groups, computed fields), answers J1939 requests, sends one-shot frames for other
// processes and commands safe values when a command writer dies. README.md.

#include "openvcu/service/main.hpp"

#include "can_tx_app.hpp"
#include "scheduler.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  return service::runApp<openvcu::cantx::CanTxApp>(openvcu::config::ServiceId::CanTx,
                                                   "CAN transmit: the schedule, J1939-76 pairs, requests, one-shots",
                                                   true, argc, argv);
}
