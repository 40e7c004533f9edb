// vcu-web's HTTP server (services/web/src/http_server.hpp) on loopback sockets, inside the
// sandbox of tests/harness/run_isolated.sh (a private network namespace): routes, static files
// and the paths that must not leave their root, body and upload limits, rate and connection
// limits. Streams, answers from other threads, downloads and stop(): test_http_streams.cpp.
#include <doctest/doctest.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "harness.hpp"
#include "http_server.hpp"
#include "http_test_client.hpp"
#include "skip.hpp"

namespace harness = openvcu::harness;
namespace web = openvcu::web;
namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace webtest;

TEST_CASE("web server: a route answers with its response and an unknown API path is 404") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  auto& sut = server.make();
  sut.route(web::Method::Get, "/api/info", [](const web::Request& request, web::Responder respond) {
    respond(web::Response::json(200, "{\"q\": \"" + request.query.at("x") + "\"}"));
  });
  sut.route(web::Method::Get, "/api/recordings/", [](const web::Request& request, web::Responder respond) {
    respond(web::Response::json(200, "{\"path\": \"" + request.path + "\"}"));
  });
  const auto port = server.start();

  const Answer info = get(port, "/api/info?x=a%2Cb");
  CHECK(info.status == 200);
  CHECK(info.body == "{\"q\": \"a,b\"}");
  CHECK(info.header("content-type") == "application/json");
  CHECK(info.header("cache-control") == "no-store");
  CHECK(info.header("x-content-type-options") == "nosniff");
  CHECK(get(port, "/api/recordings/drive1/archive").body == "{\"path\": \"/api/recordings/drive1/archive\"}");
  const Answer unknown = get(port, "/api/nothing");
  CHECK(unknown.status == 404);
  CHECK(unknown.body == "{\"error\": \"not found\"}");
  CHECK(request(port, "POST", "/api/info", "{}").status == 405);
  CHECK(request(port, "PUT", "/api/info", "{}").status == 405);
}

TEST_CASE("web server: a malformed request is answered 400 and the connection closed") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  const auto port = server.start();
  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  sendAll(fd, "GET / HTTP/1.1\r\nBroken header line\r\n\r\n");
  const Answer answer = parseAnswer(readFrom(fd, CLIENT_TIMEOUT));  // returns at the server's close
  ::close(fd);
  CHECK(answer.status == 400);
  CHECK(request(port, "GET", "/", {}, "X-Big: " + std::string(9000, 'a') + "\r\n").status == 400);
}

TEST_CASE("web server: static files are served with their content type and index.html for / and 404 when missing") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  writeFile(server.folder / "www/index.html", "<html>hi</html>");
  fs::create_directories(server.folder / "www/js");
  writeFile(server.folder / "www/js/app.js", "let a = 1;");
  const auto port = server.start();

  const Answer index = get(port, "/");
  CHECK(index.status == 200);
  CHECK(index.body == "<html>hi</html>");
  CHECK(index.header("content-type") == "text/html; charset=utf-8");
  CHECK(index.header("content-security-policy").find("default-src 'self'") != std::string::npos);
  CHECK(index.header("x-content-type-options") == "nosniff");
  const Answer script = get(port, "/js/app.js");
  CHECK(script.status == 200);
  CHECK(script.body == "let a = 1;");
  CHECK(script.header("content-type") == "text/javascript; charset=utf-8");
  CHECK(script.header("content-length") == "10");
  CHECK(get(port, "/missing.css").status == 404);
  CHECK(get(port, "/js").status == 404);  // a folder is not a file
}

TEST_CASE(
    "web server: paths that leave the static root are refused: dot-dot and percent-encoded dot-dot and absolute and "
    "backslash and NUL and symlinks") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  const fs::path root = server.folder / "www";
  writeFile(server.folder / "secret.txt", "secret");
  writeFile(root / "ok.txt", "ok");
  fs::create_directories(server.folder / "outside");
  writeFile(server.folder / "outside/secret.txt", "secret");
  fs::create_directory_symlink(server.folder / "outside", root / "link");
  fs::create_symlink(root / "ok.txt", root / "inside.txt");  // a symlink inside the root is fine

  CHECK(web::resolveUnder(root, "ok.txt") == fs::canonical(root / "ok.txt"));
  CHECK(web::resolveUnder(root, "inside.txt") == fs::canonical(root / "ok.txt"));
  CHECK_FALSE(web::resolveUnder(root, "../secret.txt"));
  CHECK_FALSE(web::resolveUnder(root, "a/../../secret.txt"));
  CHECK_FALSE(web::resolveUnder(root, "..").has_value());
  CHECK_FALSE(web::resolveUnder(root, (server.folder / "secret.txt").string()));
  CHECK_FALSE(web::resolveUnder(root, "..\\secret.txt"));
  CHECK_FALSE(web::resolveUnder(root, std::string("ok.txt\0.png", 11)));
  CHECK_FALSE(web::resolveUnder(root, "link/secret.txt"));
  CHECK_FALSE(web::resolveUnder(root, "missing.txt"));

  const auto port = server.start();
  CHECK(get(port, "/ok.txt").body == "ok");
  for (const char* target : {"/../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E%2Fsecret.txt", "/js/..%2f..%2fsecret.txt",
                             "//etc/passwd", "/..%5csecret.txt", "/ok.txt%00.png", "/link/secret.txt", "/%zz"}) {
    CAPTURE(target);
    const Answer answer = get(port, target);
    CHECK((answer.status == 404 || answer.status == 400));
    CHECK(answer.body.find("secret") == std::string::npos);
  }
}

TEST_CASE("web server: a POST body within maxBodyBytes reaches the route and one over it is answered 413") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxBodyBytes = 64;
  auto& sut = server.make();
  sut.route(web::Method::Post, "/api/echo", [](const web::Request& request, web::Responder respond) {
    respond(web::Response::json(200, request.body));
  });
  const auto port = server.start();
  CHECK(request(port, "POST", "/api/echo", "{\"a\": 1}").body == "{\"a\": 1}");
  CHECK(request(port, "POST", "/api/echo", std::string(65, 'x')).status == 413);
  // chunked: the size is only known while reading
  const Answer chunked = request(port, "POST", "/api/echo", {},
                                 "Transfer-Encoding: chunked\r\n\r\n40\r\n" + std::string(64, 'x') + "\r\n10\r\n" +
                                     std::string(16, 'y') + "\r\n0\r\n\r\n");
  CHECK(chunked.status == 413);
}

TEST_CASE("web server: an upload is streamed to a new file that onComplete receives") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  auto& sut = server.make();
  std::string received;
  unsigned mode = 0;
  sut.upload("/api/uploads",
             web::UploadRoute{[](const web::Request&) { return std::optional<web::Response>{}; },
                              [&](const web::Request& request, fs::path file, web::Responder respond) {
                                received = readFile(file);
                                struct stat info {};
                                ::stat(file.c_str(), &info);
                                mode = info.st_mode & 0777u;
                                fs::remove(file);
                                respond(web::Response::json(200, "{\"name\": \"" + request.query.at("name") + "\"}"));
                              }});
  const auto port = server.start();
  std::string body(300 * 1024, '\0');
  for (std::size_t i = 0; i < body.size(); ++i) body[i] = static_cast<char>(i * 7);
  const Answer answer = request(port, "POST", "/api/uploads?name=log.blf", body, "Expect: 100-continue\r\n");
  CHECK(answer.status == 200);
  CHECK(answer.body == "{\"name\": \"log.blf\"}");
  CHECK(received.size() == body.size());
  CHECK((received == body));
  CHECK(mode == 0640u);
  CHECK(filesIn(server.folder / "uploads") == 0);
}

TEST_CASE("web server: an upload over maxUploadBytes is answered 413 and leaves no file") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxUploadBytes = 64 * 1024;
  auto& sut = server.make();
  std::atomic<bool> completed{false};
  sut.upload("/api/uploads", web::UploadRoute{{}, [&](const web::Request&, fs::path, web::Responder respond) {
                                                completed = true;
                                                respond(web::Response::json(200, "{}"));
                                              }});
  const auto port = server.start();
  // declared too large: refused before the body
  CHECK(request(port, "POST", "/api/uploads", std::string(64 * 1024 + 1, 'x')).status == 413);
  // chunked: written to disk until the limit is passed, then removed
  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  sendAll(fd, "POST /api/uploads HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n");
  const std::string chunk = "4000\r\n" + std::string(0x4000, 'z') + "\r\n";
  for (int i = 0; i < 8; ++i) {
    if (!sendAll(fd, chunk)) break;  // the server may have answered and closed already
  }
  const Answer answer = parseAnswer(readFrom(fd, CLIENT_TIMEOUT));
  ::close(fd);
  CHECK(answer.status == 413);
  CHECK_FALSE(completed.load());
  CHECK(eventually([&] { return filesIn(server.folder / "uploads") == 0; }));
}

TEST_CASE("web server: an upload cut off by its client leaves no file") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  auto& sut = server.make();
  std::atomic<bool> completed{false};
  sut.upload("/api/uploads", web::UploadRoute{{}, [&](const web::Request&, fs::path, web::Responder respond) {
                                                completed = true;
                                                respond(web::Response::json(200, "{}"));
                                              }});
  const auto port = server.start();
  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  sendAll(fd, "POST /api/uploads HTTP/1.1\r\nHost: x\r\nContent-Length: 100000\r\n\r\n" + std::string(30000, 'p'));
  // the partial file is there while the body comes in, and gone once the client leaves
  REQUIRE(eventually([&] { return filesIn(server.folder / "uploads") == 1; }));
  ::close(fd);
  CHECK(eventually([&] { return filesIn(server.folder / "uploads") == 0; }));
  CHECK_FALSE(completed.load());
}

TEST_CASE("web server: an upload that authorize refuses is answered with its response and writes nothing") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  auto& sut = server.make();
  std::atomic<bool> completed{false};
  sut.upload("/api/uploads", web::UploadRoute{[](const web::Request& request) -> std::optional<web::Response> {
                                                if (request.cookie("vcu_session") == "good") return std::nullopt;
                                                return web::Response::error(401, "login needed");
                                              },
                                              [&](const web::Request&, fs::path file, web::Responder respond) {
                                                completed = true;
                                                fs::remove(file);
                                                respond(web::Response::json(200, "{}"));
                                              }});
  const auto port = server.start();
  const Answer refused =
      request(port, "POST", "/api/uploads", std::string(100000, 'x'), "Cookie: a=b; vcu_session=bad\r\n");
  CHECK(refused.status == 401);
  CHECK(refused.body == "{\"error\": \"login needed\"}");
  CHECK_FALSE(completed.load());
  CHECK(filesIn(server.folder / "uploads") == 0);
  CHECK(request(port, "POST", "/api/uploads", "data", "Cookie: a=b; vcu_session=good\r\n").status == 200);
  CHECK(completed.load());
}

TEST_CASE("web server: requests beyond the per-address rate are answered 429 with Retry-After") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.requestsPerSecondPerAddress = 0.5;
  server.options.requestBurstPerAddress = 3;
  auto& sut = server.make();
  sut.route(web::Method::Get, "/api/info",
            [](const web::Request&, web::Responder respond) { respond(web::Response::json(200, "{}")); });
  const auto port = server.start();
  for (int i = 0; i < 3; ++i) CHECK(get(port, "/api/info").status == 200);
  const Answer limited = get(port, "/api/info");
  CHECK(limited.status == 429);
  CHECK(limited.header("retry-after") == "2");
  CHECK(server.sut->counters().rateLimited == 1);
}

TEST_CASE("web server: connections beyond the per-address limit are closed at once and counted") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxConnectionsPerAddress = 2;
  auto& sut = server.make();
  sut.route(web::Method::Get, "/api/info",
            [](const web::Request&, web::Responder respond) { respond(web::Response::json(200, "{}")); });
  const auto port = server.start();
  const int first = connectTo(port);
  const int second = connectTo(port);
  REQUIRE(first >= 0);
  REQUIRE(second >= 0);
  REQUIRE(eventually([&] { return sut.counters().connections == 2; }));
  const int third = connectTo(port);
  REQUIRE(third >= 0);
  const std::string refused = readFrom(third, CLIENT_TIMEOUT);  // ends at the server's close
  ::close(third);
  CHECK((refused.empty() || refused.rfind("HTTP/1.1 503", 0) == 0));
  CHECK(sut.counters().refusedConnections == 1);
  // a connection that is let in still works, and a closed one frees its place
  sendAll(first, "GET /api/info HTTP/1.1\r\nHost: x\r\n\r\n");
  CHECK(parseAnswer(readFrom(first, CLIENT_TIMEOUT, [](const std::string& d) {
          return d.find("{}") != std::string::npos;
        })).status == 200);
  ::close(first);
  ::close(second);
  REQUIRE(eventually([&] { return sut.counters().connections == 0; }));
  CHECK(get(port, "/api/info").status == 200);
}
