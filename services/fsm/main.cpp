// vcu-fsm: the vehicle's state machine from its JSON file: reads signals from the table,
// commands signals, publishes transitions with their cause, resumes after a restart and
// reloads on command. README.md; the file format: docs/fsm.md.

#include "openvcu/service/main.hpp"

#include "fsm_app.hpp"
#include "openvcu/fsm/engine.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  return service::runApp<openvcu::fsm::FsmApp>(openvcu::config::ServiceId::Fsm,
                                               "the JSON state machine: conditions on signals, commanded values", false,
                                               argc, argv);
}
