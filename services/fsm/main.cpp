// vcu-fsm: the vehicle's state machine from its JSON file: reads signals from the table,
// commands signals, publishes transitions with their cause, resumes after a restart and
// reloads on command. README.md; the file format: docs/fsm.md.

#include "fsm_app.hpp"
#include "openvcu/fsm/engine.hpp"
#include "openvcu/service/main.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  const service::ServiceInfo info{.name = "fsm",
                                  .program = {},
                                  .description = "the JSON state machine: conditions on signals, commanded values",
                                  .version = {},
                                  .writerId = openvcu::fsm::FSM_WRITER,
                                  .usesFrameStreams = false};
  return service::runApp<openvcu::fsm::FsmApp>(info, argc, argv);
}
