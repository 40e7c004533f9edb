#pragma once
// vcu-web's application (docs/design/web.md): the HTTP server on its io thread, the live state
// fed by the service's events, logins, checked commands through the command sockets, the
// recordings and uploads of the data folder with their archives and trace reports.
//
//   auto appResult = web::WebApp::create(runtime, overrides);   // bound and serving
//   return runtime.run();                                        // LCM events, heartbeat, until SIGTERM
//
// Threads: the service's loop thread (LCM events, heartbeat counters), the io thread (HTTP,
// the live state), a command worker (commands, password checks) and a file worker (archives,
// reports). Events cross to the io thread by HttpServer::post.

#include <memory>
#include <string>

#include "openvcu/core/result.hpp"
#include "openvcu/service/service.hpp"

namespace openvcu::web {

/// Command-line overrides of web.json (empty: the file's value).
struct WebOverrides {
  std::string listen;      ///< --listen ADDR:PORT
  std::string dataFolder;  ///< --data-folder DIR
  std::string usersFile;   ///< --users FILE
  std::string www;         ///< --www DIR: the pages (default: the installed or source folder)
};

struct WebAppImpl;

/// @note restricted thread-safe: created and destroyed on the service's loop thread.
class WebApp {
 public:
  static Result<std::unique_ptr<WebApp>> create(service::Service& runtime, const WebOverrides& overrides);
  ~WebApp();
  WebApp(const WebApp&) = delete;
  WebApp& operator=(const WebApp&) = delete;

 private:
  explicit WebApp(std::unique_ptr<WebAppImpl> impl);
  std::unique_ptr<WebAppImpl> m_impl;
};

}  // namespace openvcu::web
