// vcu-fsm: the vehicle's state machine from its JSON file: reads signals from the table,
// commands signals, publishes transitions with their cause, resumes after a restart and
// reloads on command. README.md; the file format: docs/fsm.md.

#include "engine.hpp"
#include "fsm_app.hpp"
#include "openvcu/service/service.hpp"

namespace service = openvcu::service;

int main(int argc, char** argv) {
  const service::ServiceInfo info{.name = "fsm",
                                  .program = {},
                                  .description = "the JSON state machine: conditions on signals, commanded values",
                                  .version = {},
                                  .writerId = openvcu::fsm::FSM_WRITER,
                                  .usesFrameStreams = false};
  service::CommandLine commandLine(info);
  if (const auto maybeExit = commandLine.parseOrExit(argc, argv)) return *maybeExit;
  auto serviceResult = service::Service::open(info, commandLine.options());
  if (!serviceResult) return service::reportStartupError(info, serviceResult.error());
  service::Service& runtime = **serviceResult;
  auto appResult = openvcu::fsm::FsmApp::create(runtime);
  if (!appResult) return service::reportStartupError(info, appResult.error());
  return runtime.run();
}
