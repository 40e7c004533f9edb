// vcu-web's HTTP server inside the sandbox (see test_http_server.cpp): event streams and
// their update cap, a stalled stream client, answers from other threads, downloads, stop().
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

namespace {

/// An event source that has a new event on every call and notes when it was asked.
struct CountingSource : web::EventSource {
  struct Shared {
    std::mutex mutex;
    std::vector<Clock::time_point> asked;
  };
  std::shared_ptr<Shared> shared;
  std::size_t eventBytes;
  int sequence{0};
  CountingSource(std::shared_ptr<Shared> s, std::size_t bytes) : shared(std::move(s)), eventBytes(bytes) {}
  std::string next() override {
    {
      const std::lock_guard<std::mutex> lock(shared->mutex);
      shared->asked.push_back(Clock::now());
    }
    return "event: update\ndata: " + std::to_string(++sequence) + std::string(eventBytes, 'x') + "\n\n";
  }
};

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

}  // namespace

TEST_CASE("web server: an event stream delivers events no more often than maxUpdatesPerSecond") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxUpdatesPerSecond = 20;
  auto& sut = server.make();
  auto shared = std::make_shared<CountingSource::Shared>();
  sut.stream("/api/live", [&](const web::Request& request) -> openvcu::Result<std::unique_ptr<web::EventSource>> {
    if (request.query.count("signals") == 0) return openvcu::Error{"signals: missing"};
    return std::unique_ptr<web::EventSource>(std::make_unique<CountingSource>(shared, 10));
  });
  const auto port = server.start();
  const Answer refused = get(port, "/api/live");
  CHECK(refused.status == 400);
  CHECK(refused.body == "{\"error\": \"signals: missing\"}");

  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  sendAll(fd, "GET /api/live?signals=a HTTP/1.1\r\nHost: x\r\n\r\n");
  const auto window = 600ms;
  const std::string received = readFrom(fd, window);
  ::close(fd);
  const Answer answer = parseAnswer(received);
  CHECK(answer.status == 200);
  CHECK(answer.header("content-type") == "text/event-stream");
  CHECK(answer.header("cache-control") == "no-store");
  const std::size_t events = count(received, "event: update\n");
  CHECK(events >= 5);
  CHECK(events <= 13);  // 20/s for 0.6 s, with slack for the first tick
  const std::lock_guard<std::mutex> lock(shared->mutex);
  REQUIRE(shared->asked.size() >= 2);
  for (std::size_t i = 1; i < shared->asked.size(); ++i) {
    CHECK(shared->asked[i] - shared->asked[i - 1] >= 45ms);  // 50 ms apart, 5 ms timer slack
  }
}

TEST_CASE("web server: a stream client that stops reading holds up no other client and is closed after writeTimeout") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxUpdatesPerSecond = 50;
  server.options.writeTimeout = 2s;
  auto& sut = server.make();
  auto shared = std::make_shared<CountingSource::Shared>();
  sut.stream("/api/live", [&](const web::Request&) -> openvcu::Result<std::unique_ptr<web::EventSource>> {
    return std::unique_ptr<web::EventSource>(std::make_unique<CountingSource>(shared, 512 * 1024));
  });
  sut.route(web::Method::Get, "/api/info",
            [](const web::Request&, web::Responder respond) { respond(web::Response::json(200, "{}")); });
  const auto port = server.start();
  const int stalled = connectTo(port, 4096);
  REQUIRE(stalled >= 0);
  sendAll(stalled, "GET /api/live HTTP/1.1\r\nHost: x\r\n\r\n");
  // the socket buffers fill: the server stops asking the source and counts skipped events
  REQUIRE(eventually([&] { return sut.counters().eventsSkipped > 0; }));
  const auto asked = Clock::now();
  CHECK(get(port, "/api/info").status == 200);
  CHECK(Clock::now() - asked < 1s);                                    // well before the stalled stream's writeTimeout
  CHECK(eventually([&] { return sut.counters().streams == 0; }, 4s));  // closed after writeTimeout
  ::close(stalled);
}

namespace {

/// Opens an event stream on a new connection from `source`: the socket once its 200 header has
/// arrived, else -1 (and the answer in `refusal` when given).
int openStream(std::uint16_t port, const char* source, Answer* refusal = nullptr) {
  const int fd = connectFrom(port, source);
  if (fd < 0) return -1;
  sendAll(fd, "GET /api/live HTTP/1.1\r\nHost: x\r\n\r\n");
  const std::string head = readFrom(fd, CLIENT_TIMEOUT, [](const std::string& d) {
    return d.find("\r\n\r\n") != std::string::npos &&
           (d.rfind("HTTP/1.1 200", 0) == 0 || d.find("}") != std::string::npos);
  });
  const Answer answer = parseAnswer(head);
  if (answer.status == 200) return fd;
  if (refusal != nullptr) *refusal = answer;
  ::close(fd);
  return -1;
}

/// true when the server ends the stream on `fd` within `timeout` (events before the end are read and dropped).
bool streamEnds(int fd, Clock::duration timeout = 2s) {
  bool closed = false;
  readFrom(fd, timeout, {}, &closed);
  return closed;
}

}  // namespace

TEST_CASE(
    "web server: more than 16 event streams from one address are served, and at maxStreams a new stream of that "
    "address replaces its oldest") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxConnectionsPerAddress = 16;  // the service's defaults
  server.options.maxStreams = 20;
  auto& sut = server.make();
  auto shared = std::make_shared<CountingSource::Shared>();
  sut.stream("/api/live", [&](const web::Request&) -> openvcu::Result<std::unique_ptr<web::EventSource>> {
    return std::unique_ptr<web::EventSource>(std::make_unique<CountingSource>(shared, 10));
  });
  sut.route(web::Method::Get, "/api/info",
            [](const web::Request&, web::Responder respond) { respond(web::Response::json(200, "{}")); });
  const auto port = server.start();
  // 20 pages behind one reverse proxy: one client address for all
  std::vector<int> streams;
  for (int i = 0; i < 20; ++i) {
    CAPTURE(i);
    const int fd = openStream(port, "127.0.0.1");
    CHECK(fd >= 0);
    if (fd >= 0) streams.push_back(fd);
  }
  REQUIRE(streams.size() == 20);
  CHECK(get(port, "/api/info").status == 200);  // requests of the address still get through

  // one more page of the same address: served, the address's oldest stream ends
  const int newest = openStream(port, "127.0.0.1");
  CHECK(newest >= 0);
  CHECK(streamEnds(streams[0]));
  // a page of another address: served, the oldest stream of the address holding the most ends
  const int otherUser = openStream(port, "127.0.0.2");
  CHECK(otherUser >= 0);
  CHECK(streamEnds(streams[1]));
  CHECK(sut.counters().streams == 20);
  for (const int fd : streams) ::close(fd);
  if (newest >= 0) ::close(newest);
  if (otherUser >= 0) ::close(otherUser);
}

TEST_CASE("web server: when maxStreams are open one per address a new address's stream is refused with the reason") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  server.options.maxStreams = 2;
  auto& sut = server.make();
  auto shared = std::make_shared<CountingSource::Shared>();
  sut.stream("/api/live", [&](const web::Request&) -> openvcu::Result<std::unique_ptr<web::EventSource>> {
    return std::unique_ptr<web::EventSource>(std::make_unique<CountingSource>(shared, 10));
  });
  const auto port = server.start();
  const int first = openStream(port, "127.0.0.2");
  const int second = openStream(port, "127.0.0.3");
  REQUIRE(first >= 0);
  REQUIRE(second >= 0);
  Answer refusal;
  CHECK(openStream(port, "127.0.0.4", &refusal) < 0);
  CHECK(refusal.status == 503);
  CHECK(refusal.body == "{\"error\": \"too many event streams: all 2 are open, at most 1 per address\"}");
  // a second page of an address that has one replaces that address's own stream
  const int again = openStream(port, "127.0.0.2");
  CHECK(again >= 0);
  CHECK(streamEnds(first));
  CHECK_FALSE(streamEnds(second, 300ms));
  ::close(first);
  ::close(second);
  if (again >= 0) ::close(again);
}

TEST_CASE("web server: a Responder called from another thread answers the request") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  auto& sut = server.make();
  std::vector<std::thread> workers;
  std::mutex workersMutex;
  sut.route(web::Method::Get, "/api/slow", [&](const web::Request&, web::Responder respond) {
    const std::lock_guard<std::mutex> lock(workersMutex);
    workers.emplace_back([respond] {
      std::this_thread::sleep_for(50ms);
      respond(web::Response::json(200, "{\"worker\": true}"));
      respond(web::Response::json(500, "{}"));  // a second call is ignored
    });
  });
  sut.route(web::Method::Get, "/api/forgotten", [](const web::Request&, web::Responder) {});
  const auto port = server.start();
  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  // two requests on one keep-alive connection: both answered once, in order
  for (int i = 0; i < 2; ++i) {
    sendAll(fd, "GET /api/slow HTTP/1.1\r\nHost: x\r\n\r\n");
    const Answer answer = parseAnswer(
        readFrom(fd, CLIENT_TIMEOUT, [](const std::string& d) { return d.find("true}") != std::string::npos; }));
    CHECK(answer.status == 200);
    CHECK(answer.body == "{\"worker\": true}");
  }
  ::close(fd);
  CHECK(get(port, "/api/forgotten").status == 500);  // a Responder dropped unanswered
  const std::lock_guard<std::mutex> lock(workersMutex);
  for (auto& worker : workers) worker.join();
}

TEST_CASE("web server: a download is sent from its file as an attachment and removed when deleteFileAfter") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  const fs::path archive = server.folder / "drive1.tar.gz";
  const std::string content(200 * 1024, 'a');
  writeFile(archive, content);
  auto& sut = server.make();
  sut.route(web::Method::Get, "/api/archive", [&](const web::Request&, web::Responder respond) {
    web::Response response;
    response.contentType = "application/gzip";
    response.file = archive;
    response.downloadName = "drive1.tar.gz";
    response.deleteFileAfter = true;
    respond(std::move(response));
  });
  const auto port = server.start();
  const Answer answer = get(port, "/api/archive");
  CHECK(answer.status == 200);
  CHECK(answer.header("content-type") == "application/gzip");
  CHECK(answer.header("content-disposition") == "attachment; filename=\"drive1.tar.gz\"");
  CHECK(answer.header("content-length") == std::to_string(content.size()));
  CHECK(answer.body.size() == content.size());
  CHECK((answer.body == content));
  CHECK(eventually([&] { return !fs::exists(archive); }));
}

TEST_CASE("web server: stop() from another thread closes every connection and run() returns") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  TestServer server;
  auto& sut = server.make();
  auto shared = std::make_shared<CountingSource::Shared>();
  sut.stream("/api/live", [&](const web::Request&) -> openvcu::Result<std::unique_ptr<web::EventSource>> {
    return std::unique_ptr<web::EventSource>(std::make_unique<CountingSource>(shared, 10));
  });
  const auto port = server.start();
  const int streaming = connectTo(port);
  const int idle = connectTo(port);
  REQUIRE(streaming >= 0);
  REQUIRE(idle >= 0);
  sendAll(streaming, "GET /api/live HTTP/1.1\r\nHost: x\r\n\r\n");
  REQUIRE(eventually([&] { return sut.counters().streams == 1 && sut.counters().connections == 2; }));
  sut.stop();
  CHECK(eventually([&] { return server.runReturned.load(); }));
  // both clients see the end of their connection
  bool streamClosed = false;
  bool idleClosed = false;
  readFrom(streaming, CLIENT_TIMEOUT, {}, &streamClosed);
  CHECK(readFrom(idle, CLIENT_TIMEOUT, {}, &idleClosed).empty());
  CHECK(streamClosed);
  CHECK(idleClosed);
  ::close(streaming);
  ::close(idle);
  server.thread.join();
}
