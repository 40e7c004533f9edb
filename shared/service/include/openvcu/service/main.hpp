#pragma once
// The whole main of a service whose work lives in an App class with
// `static Result<std::unique_ptr<App>> create(service::Service&)`:
//
//   int main(int argc, char** argv) {
//     return service::runApp<fsm::FsmApp>(INFO, argc, argv);
//   }
//
// Parses the command line (--help, --version exit here), opens the runtime, creates the
// app and runs the loop until SIGTERM/SIGINT; any start-up error is one line on stderr and
// exit code 1 (service.hpp). The app is destroyed before the runtime it uses.

#include <string>
#include <string_view>

#include "openvcu/config/services.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::service {

template <typename App>
int runApp(const ServiceInfo& info, int argc, char** argv) {
  CommandLine commandLine(info);
  if (const auto maybeExit = commandLine.parseOrExit(argc, argv)) return *maybeExit;
  auto serviceResult = Service::open(info, commandLine.options());
  if (!serviceResult) return reportStartupError(info, serviceResult.error());
  Service& runtime = **serviceResult;
  auto appResult = App::create(runtime);
  if (!appResult) return reportStartupError(info, appResult.error());
  return runtime.run();
}

/// The same for a service of the stack: its name and writer id come from config::SERVICES.
///
///   return service::runApp<canrx::CanRxApp>(config::ServiceId::CanRx, "CAN receive: ...", true, argc, argv);
template <typename App>
int runApp(config::ServiceId id, std::string_view description, bool usesFrameStreams, int argc, char** argv) {
  const config::ServiceEntry& entry = config::serviceEntry(id);
  const ServiceInfo info{.name = std::string(entry.name),
                         .program = {},
                         .description = std::string(description),
                         .version = {},
                         .writerId = entry.writer,
                         .usesFrameStreams = usesFrameStreams};
  return runApp<App>(info, argc, argv);
}

}  // namespace openvcu::service
