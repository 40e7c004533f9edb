// vcu-web: the VCU in a browser (docs/design/web.md). Live pages fed by the signal table and
// the events, commands after a login through the stack's command sockets, recordings and the
// trace analysis of any log. `vcu-web passwd --users FILE NAME` adds a user.

#include <cstring>

#include "auth.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/service/service.hpp"
#include "web_app.hpp"

namespace service = openvcu::service;
namespace web = openvcu::web;

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "passwd") == 0) return web::runPasswdCommand(argc, argv);
  const openvcu::config::ServiceEntry& entry = openvcu::config::serviceEntry(openvcu::config::ServiceId::Web);
  const service::ServiceInfo info{.name = std::string(entry.name),
                                  .program = {},
                                  .description = "The VCU in a browser: live view, commands after a login, recordings "
                                                 "and trace reports (vcu-web passwd --users FILE NAME adds a user)",
                                  .version = {},
                                  .writerId = entry.writer,
                                  .usesFrameStreams = false};
  web::WebOverrides overrides;
  service::CommandLine commandLine(info);
  commandLine.addOption("--listen", overrides.listen, "ADDR:PORT to listen on instead of web.json's (default 127.0.0.1:8080)");
  commandLine.addOption("--data-folder", overrides.dataFolder, "recordings/, uploads/ and the command log instead of web.json's");
  commandLine.addOption("--users", overrides.usersFile, "the users file instead of web.json's");
  commandLine.addOption("--www", overrides.www, "the pages' folder (default: the installed one, else the source tree's)");
  if (const auto maybeExit = commandLine.parseOrExit(argc, argv)) return *maybeExit;
  auto serviceResult = service::Service::open(info, commandLine.options());
  if (!serviceResult) return service::reportStartupError(info, serviceResult.error());
  service::Service& runtime = **serviceResult;
  auto appResult = web::WebApp::create(runtime, overrides);
  if (!appResult) return service::reportStartupError(info, appResult.error());
  return runtime.run();
}
