// vcu-web's HTTP server (services/web/src/http_server.hpp) on loopback sockets, inside the
// sandbox of tests/harness/run_isolated.sh (a private network namespace): routes, static files
// and the paths that must not leave their root, body and upload limits, rate and connection
// limits. Streams, answers from other threads, downloads and stop(): test_http_streams.cpp.
#include <doctest/doctest.h>
#include <poll.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
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

TEST_CASE(
    "web server: a new client of an address at its limit closes that address's idle connection, and when every "
    "connection is busy the 503 names the limit") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxConnectionsPerAddress = 2;
  server.options.maxConnections = 3;
  auto& sut = server.make();
  std::mutex heldMutex;
  std::vector<web::Responder> held;
  sut.route(web::Method::Get, "/api/info",
            [](const web::Request&, web::Responder respond) { respond(web::Response::json(200, "{}")); });
  sut.route(web::Method::Get, "/api/hold", [&](const web::Request&, web::Responder respond) {
    const std::lock_guard<std::mutex> lock(heldMutex);
    held.push_back(std::move(respond));
  });
  const auto heldCount = [&] {
    const std::lock_guard<std::mutex> lock(heldMutex);
    return held.size();
  };
  const auto port = server.start();
  const int idleOldest = connectTo(port);
  REQUIRE(idleOldest >= 0);
  REQUIRE(eventually([&] { return sut.counters().connections == 1; }));
  const int idleNewer = connectTo(port);
  REQUIRE(idleNewer >= 0);
  REQUIRE(eventually([&] { return sut.counters().connections == 2; }));

  // the address is at its limit with two connections that never sent a byte: the one that
  // waited longest gives way, the new client is answered
  CHECK(get(port, "/api/info").status == 200);
  bool oldestClosed = false;
  CHECK(readFrom(idleOldest, 1s, {}, &oldestClosed).empty());
  CHECK(oldestClosed);
  ::close(idleOldest);

  // two requests in progress from 127.0.0.1: nothing of that address can give way
  sendAll(idleNewer, "GET /api/hold HTTP/1.1\r\nHost: x\r\n\r\n");
  REQUIRE(eventually([&] { return heldCount() == 1; }));
  const int busy = connectTo(port);
  REQUIRE(busy >= 0);
  sendAll(busy, "GET /api/hold HTTP/1.1\r\nHost: x\r\n\r\n");
  REQUIRE(eventually([&] { return heldCount() == 2 && sut.counters().connections == 2; }));
  const Answer perAddress = get(port, "/api/info");
  CHECK(perAddress.status == 503);
  CHECK(perAddress.body == "{\"error\": \"too many connections from 127.0.0.1: all 2 are busy with requests\"}\n");

  // another address fills the table with a third request in progress: the 503 names the total
  const int other = connectFrom(port, "127.0.0.2");
  REQUIRE(other >= 0);
  sendAll(other, "GET /api/hold HTTP/1.1\r\nHost: x\r\n\r\n");
  REQUIRE(eventually([&] { return heldCount() == 3; }));
  const int refused = connectFrom(port, "127.0.0.3");
  REQUIRE(refused >= 0);
  const Answer total = parseAnswer(readFrom(refused, CLIENT_TIMEOUT));
  ::close(refused);
  CHECK(total.status == 503);
  CHECK(total.body == "{\"error\": \"too many connections: all 3 are busy with requests or event streams\"}\n");
  CHECK(sut.counters().refusedConnections == 2);

  // the held requests are still answered, and their places are free again afterwards
  {
    const std::lock_guard<std::mutex> lock(heldMutex);
    for (auto& respond : held) respond(web::Response::json(200, "{\"held\": true}"));
  }
  for (const int fd : {idleNewer, busy, other}) {
    CHECK(parseAnswer(readFrom(fd, CLIENT_TIMEOUT, [](const std::string& d) {
            return d.find("true}") != std::string::npos;
          })).status == 200);
    ::close(fd);
  }
  REQUIRE(eventually([&] { return sut.counters().connections == 0; }));
  CHECK(get(port, "/api/info").status == 200);
}

namespace {

/// Connections that send a request header one byte per `interval` and never finish it (a
/// "slowloris" client); one the server closes is opened again from its address, as an
/// attacker would. Runs on a thread of its own until destroyed.
class SlowHeaderSenders {
 public:
  SlowHeaderSenders(std::uint16_t port, const std::vector<std::string>& sources, Clock::duration interval)
      : m_port(port), m_interval(interval) {
    for (const auto& source : sources) m_clients.push_back({source, -1, 0});
    for (auto& client : m_clients) step(client);  // every one connected before the thread runs
    m_thread = std::thread([this] { run(); });
  }
  ~SlowHeaderSenders() {
    {
      const std::lock_guard<std::mutex> lock(m_mutex);
      m_stopping = true;
    }
    m_wake.notify_all();
    m_thread.join();
    for (const auto& client : m_clients) {
      if (client.fd >= 0) ::close(client.fd);
    }
  }
  SlowHeaderSenders(const SlowHeaderSenders&) = delete;
  SlowHeaderSenders& operator=(const SlowHeaderSenders&) = delete;
  [[nodiscard]] std::size_t reconnects() const { return m_reconnects.load(); }

 private:
  struct Client {
    std::string source;
    int fd;
    std::size_t sent;
  };
  static constexpr std::string_view HEADER_START = "GET /api/state HTTP/1.1\r\nHost: x\r\nX-Padding: ";

  void step(Client& client) {
    if (client.fd >= 0) {
      pollfd entry{client.fd, POLLIN, 0};
      if (::poll(&entry, 1, 0) > 0) {  // a 503 or the end: the server let go of it
        ::close(client.fd);
        client.fd = -1;
        ++m_reconnects;
      }
    }
    if (client.fd < 0) {
      client.fd = connectFrom(m_port, client.source.c_str());
      client.sent = 0;
    }
    if (client.fd < 0) return;
    const char byte = client.sent < HEADER_START.size() ? HEADER_START[client.sent] : 'a';
    sendAll(client.fd, std::string_view(&byte, 1));
    ++client.sent;
  }
  void run() {
    std::unique_lock<std::mutex> lock(m_mutex);
    while (!m_wake.wait_for(lock, m_interval, [this] { return m_stopping; })) {
      for (auto& client : m_clients) step(client);
    }
  }

  std::uint16_t m_port;
  Clock::duration m_interval;
  std::vector<Client> m_clients;
  std::atomic<std::size_t> m_reconnects{0};
  std::mutex m_mutex;
  std::condition_variable m_wake;
  bool m_stopping{false};
  std::thread m_thread;
};

}  // namespace

TEST_CASE(
    "web server: 64 connections sending a header byte a second keep no client of their addresses from its answers") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.readTimeout = 15s;  // the service's defaults: the attack outlives the test
  server.options.maxConnections = 64;
  server.options.maxConnectionsPerAddress = 16;
  auto& sut = server.make();
  sut.route(web::Method::Get, "/api/state", [](const web::Request&, web::Responder respond) {
    respond(web::Response::json(200, "{\"state\": \"Running\"}"));
  });
  sut.route(web::Method::Post, "/api/login", [](const web::Request& request, web::Responder respond) {
    respond(web::Response::json(200, request.body));
  });
  const auto port = server.start();
  // 16 from the client's own address (all users behind a reverse proxy share one) and 48 from
  // three others: the connection table and the client's address are both full
  std::vector<std::string> sources;
  for (const char* source : {"127.0.0.1", "127.0.0.2", "127.0.0.3", "127.0.0.4"}) {
    for (int i = 0; i < 16; ++i) sources.emplace_back(source);
  }
  const SlowHeaderSenders attack(port, sources, 1s);
  REQUIRE(eventually([&] { return sut.counters().connections == 64; }));

  constexpr auto ANSWER_BOUND = 1s;
  for (int round = 0; round < 3; ++round) {
    CAPTURE(round);
    auto asked = Clock::now();
    const Answer state = get(port, "/api/state");
    CHECK(state.status == 200);
    CHECK(state.body == "{\"state\": \"Running\"}");
    CHECK(Clock::now() - asked < ANSWER_BOUND);
    asked = Clock::now();
    const Answer login =
        request(port, "POST", "/api/login", "{\"user\": \"alice\"}", "Content-Type: application/json\r\n");
    CHECK(login.status == 200);
    CHECK(Clock::now() - asked < ANSWER_BOUND);
    std::this_thread::sleep_for(700ms);  // the attack goes on between the rounds
  }
  CHECK(sut.counters().refusedConnections == 0);
  CHECK(sut.counters().evictedConnections >= 1);  // slow connections gave way, none was refused
  CHECK(sut.counters().connections <= 64);
  CHECK(attack.reconnects() > 0);
}

TEST_CASE("web server: the request deadline runs from its first byte: an idle connection may wait before it") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.readTimeout = 1s;
  auto& sut = server.make();
  sut.route(web::Method::Get, "/api/info",
            [](const web::Request&, web::Responder respond) { respond(web::Response::json(200, "{}")); });
  const auto port = server.start();
  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  std::this_thread::sleep_for(600ms);  // idle, within readTimeout
  // then a header that takes 0.6 s to arrive: done 1.2 s after the connection (past readTimeout)
  const std::string text = "GET /api/info HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n";
  const std::size_t piece = text.size() / 10 + 1;
  for (std::size_t at = 0; at < text.size(); at += piece) {
    sendAll(fd, std::string_view(text).substr(at, piece));
    std::this_thread::sleep_for(60ms);
  }
  const Answer answer = parseAnswer(readFrom(fd, CLIENT_TIMEOUT));
  ::close(fd);
  CHECK(answer.status == 200);
}

TEST_CASE("web server: a header that keeps trickling in is closed requestTimeout after its first byte") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.requestTimeout = 1s;
  const auto port = server.start();
  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  const auto firstByte = Clock::now();
  bool closed = false;
  for (std::size_t sent = 0; !closed && Clock::now() - firstByte < CLIENT_TIMEOUT; ++sent) {
    const std::string_view start = "GET / HTTP/1.1\r\nX-Padding: ";
    const char byte = sent < start.size() ? start[sent] : 'a';
    sendAll(fd, std::string_view(&byte, 1));
    readFrom(fd, 100ms, {}, &closed);  // a byte every 100 ms until the server lets go
  }
  const auto heldFor = Clock::now() - firstByte;
  ::close(fd);
  CHECK(closed);
  CHECK(heldFor >= 900ms);
  CHECK(heldFor < 1600ms);
}

TEST_CASE("web server: a request naming another host is answered 421 when the hosts are limited") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.allowedHosts = {"localhost", "127.0.0.1"};
  auto& sut = server.make();
  sut.route(web::Method::Get, "/api/info",
            [](const web::Request&, web::Responder respond) { respond(web::Response::json(200, "{}")); });
  const auto port = server.start();
  const auto ask = [port](const std::string& host) {
    const int fd = connectTo(port);
    REQUIRE(fd >= 0);
    sendAll(fd, "GET /api/info HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n\r\n");
    const std::string raw = readFrom(fd, CLIENT_TIMEOUT);
    ::close(fd);
    return parseAnswer(raw).status;
  };
  CHECK(ask("localhost:" + std::to_string(port)) == 200);
  CHECK(ask("127.0.0.1:" + std::to_string(port)) == 200);
  CHECK(ask("evil.example:" + std::to_string(port)) == 421);
  CHECK(ask("127.0.0.1.evil.example") == 421);
}
