#pragma once
// vcu-web's HTTP server (Boost.Beast over one Boost.Asio thread; docs/design/web.md): routes,
// static files, bodies with a size limit, uploads streamed to disk, server-sent-event streams
// with a per-client update cap, and the limits that keep a slow or malicious client from
// stalling the service (connections total and per address, requests per second per address,
// header/body limits, a deadline per request, read and write timeouts). A full connection table
// closes connections that are only waiting, so idle or trickling clients never lock others out.
//
//   web::HttpServer server(options);               // nothing listens yet
//   server.route(web::Method::Get, "/api/info", [&](const web::Request& request, web::Responder respond) {
//     respond(web::Response::json(200, R"({"instance":"hhea"})"));
//   });
//   server.stream("/api/live", [&](const web::Request& request) -> Result<std::unique_ptr<web::EventSource>> { ... });
//   auto listening = server.start();               // bound; "127.0.0.1:8080"
//   server.run();                                  // serves on the calling thread until stop()
//
// Everything the server does runs on the thread that called run() (the "io thread"); route
// handlers are called there and must not block. Work that blocks (a command waiting for its
// answer, an archive, a report) moves to a worker thread and calls the Responder from there:
// a Responder may be called from any thread, once.
// No exception leaves this API: Beast/Asio errors become Errors or closed connections.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"

namespace boost::asio {
class io_context;
}

namespace openvcu::web {

enum class Method : std::uint8_t { Get, Post, Delete };

/// One request as handlers see it: the whole header; the body only for routes that take one
/// (Post to a route(): up to ServerOptions::maxBodyBytes; an upload route gets the file instead).
struct Request {
  Method method{Method::Get};
  std::string path;                            ///< "/api/recordings/drive1/archive", percent-decoded
  std::map<std::string, std::string> query;    ///< "?signals=a,b" -> {"signals": "a,b"}, percent-decoded
  std::map<std::string, std::string> headers;  ///< names lower-case: "cookie", "content-type"
  std::string body;                            ///< empty for GET
  std::string clientAddress;                   ///< "127.0.0.1"
  /// The value of cookie `name` from the Cookie header, empty when absent.
  [[nodiscard]] std::string cookie(std::string_view name) const;
  /// The header `lowerCaseName`, empty when absent.
  [[nodiscard]] std::string header(std::string_view lowerCaseName) const;
};

/// One answer. Either `body` (with `contentType`) or `file` (sent from disk in chunks,
/// `downloadName` as Content-Disposition attachment when set; `deleteFileAfter` removes a
/// temporary archive once sent or on a broken connection).
struct Response {
  unsigned status{200};
  std::string contentType{"application/json"};
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  ///< extra: Set-Cookie, Cache-Control
  std::optional<std::filesystem::path> file;
  std::string downloadName;
  bool deleteFileAfter{false};

  /// A JSON body (`json` is already serialized).
  static Response json(unsigned status, std::string json);
  /// {"error": "<message>"} with `status` (400, 401, 403, 404, 409, 413, 429, 503, ...).
  static Response error(unsigned status, std::string_view message);
};

/// Called once, from any thread, with the answer to a request. Calling it after the client
/// went away is harmless (the answer is dropped).
using Responder = std::function<void(Response)>;
using Handler = std::function<void(const Request&, Responder)>;

/// An upload route: the body is streamed into `file` (a new file the server created in
/// ServerOptions::uploadFolder; at most maxUploadBytes, else 413 and the file is removed)
/// and the handler is called when the whole body is on disk. The handler owns the file from
/// then on (moves or removes it). `authorize` runs on the header alone, before any byte of
/// the body is read: a Response refuses the upload (401 without a login) and nothing is written.
struct UploadRoute {
  std::function<std::optional<Response>(const Request&)> authorize;
  std::function<void(const Request&, std::filesystem::path file, Responder)> onComplete;
};

/// A server-sent-event stream (text/event-stream) of one client. The server asks `next()`
/// for the client's next event at most `maxUpdatesPerSecond` times a second, and only when
/// the previous event has been written to the socket (a slow client gets fewer, newer
/// events; nothing queues up). `next()` returns the event text ("event: update\ndata: {...}\n\n")
/// or empty when there is nothing new. The server adds a comment line every 15 s so proxies
/// keep the connection.
class EventSource {
 public:
  virtual ~EventSource() = default;
  virtual std::string next() = 0;
};
using StreamOpener = std::function<Result<std::unique_ptr<EventSource>>(const Request&)>;

struct ServerOptions {
  std::string address{"127.0.0.1"};
  std::uint16_t port{8080};             ///< 0: any free port (tests); see HttpServer::port()
  std::filesystem::path staticRoot;     ///< GET of any other path: a file under this folder
  std::filesystem::path uploadFolder;   ///< where UploadRoute bodies are written
  std::size_t maxBodyBytes{64 * 1024};  ///< JSON bodies of route() POSTs; beyond: 413
  std::uint64_t maxUploadBytes{256ull << 20};
  /// Connections at once, event streams included. A new connection beyond it closes the
  /// connection that has waited longest for a request (idle, or its request not complete yet);
  /// when every connection is busy (a request being answered, an upload, a stream), the new one
  /// gets a 503 naming the limit, sent without waiting, and is closed.
  std::size_t maxConnections{64};
  /// The same per client address, event streams not counted (they have maxStreams): beyond it
  /// the address's own connection that has waited longest gives way, else a 503.
  std::size_t maxConnectionsPerAddress{16};
  double requestsPerSecondPerAddress{50};  ///< token bucket; beyond: 429
  double requestBurstPerAddress{100};
  /// Event streams at once. A new stream beyond it ends the oldest stream of the address that
  /// holds the most (its own address on a tie) when that address holds more than the new
  /// stream's would; else 503 ("all N are open, at most M per address").
  std::size_t maxStreams{32};
  double maxUpdatesPerSecond{20};        ///< per event stream
  std::chrono::seconds readTimeout{15};  ///< idle before a request's first byte; each read of an upload
  /// From a request's first byte until its header and (for a route) its body have arrived, however
  /// the bytes trickle in: a whole request (8 KiB header, maxBodyBytes body) or the connection is closed.
  std::chrono::seconds requestTimeout{10};
  std::chrono::seconds writeTimeout{15};  ///< a response or event not accepted by the client
  /// Host header names (lower case, without the port; IPv6 in brackets) a request may carry;
  /// another is answered 421 (a DNS-rebinding page). Empty: any.
  std::vector<std::string> allowedHosts;
};

/// Counters for the heartbeat and the benchmark.
struct ServerCounters {
  std::uint64_t requests{};
  std::uint64_t refusedConnections{};  ///< refused with a 503 at accept
  std::uint64_t evictedConnections{};  ///< closed while waiting for a request, to let a new one in
  std::uint64_t evictedStreams{};      ///< ended to let a new stream in (maxStreams)
  std::uint64_t rateLimited{};
  std::uint64_t eventsSent{};
  std::uint64_t eventsSkipped{};  ///< next() not asked because the previous event was still being written
  std::size_t connections{};
  std::size_t streams{};
};

/// @note restricted thread-safe: configure (route, stream, upload) before start(); run() on
/// one thread; stop(), post() and counters() from any thread.
class HttpServer {
 public:
  explicit HttpServer(ServerOptions options);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// Exact path, or a prefix when `path` ends with '/' ("/api/recordings/").
  void route(Method method, std::string path, Handler handler);
  void upload(std::string path, UploadRoute route);
  void stream(std::string path, StreamOpener opener);

  /// Binds and listens (an error names the address and the reason: "127.0.0.1:8080: address in use").
  Status start();
  /// The bound port (after start()).
  [[nodiscard]] std::uint16_t port() const noexcept;
  /// Serves until stop(); returns when every connection is closed.
  void run();
  void stop();
  /// Runs `work` on the io thread.
  void post(std::function<void()> work);
  /// The io context (timers of the app on the io thread).
  boost::asio::io_context& context() noexcept;
  [[nodiscard]] ServerCounters counters() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// "GET", "POST", "DELETE".
[[nodiscard]] std::string_view methodName(Method method) noexcept;

/// `relative` (from a request: "css/app.css", "drive1") resolved under `root`, or empty when it
/// would leave `root` (.., absolute, symlink out of the root, NUL, backslash) or does not exist.
[[nodiscard]] std::optional<std::filesystem::path> resolveUnder(const std::filesystem::path& root,
                                                                std::string_view relative);

}  // namespace openvcu::web
