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

}  // namespace openvcu::service
