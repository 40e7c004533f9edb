#pragma once
// A plain POSIX-socket HTTP client and a server on its own thread for the tests of vcu-web's
// HTTP server (test_http_server.cpp, test_http_streams.cpp). Loopback only, port 0.
#include <arpa/inet.h>
#include <doctest/doctest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "http_server.hpp"

namespace webtest {

namespace web = openvcu::web;
namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

inline constexpr auto CLIENT_TIMEOUT = 5s;

inline fs::path makeTempFolder() {
  static int counter = 0;
  const fs::path folder =
      fs::temp_directory_path() / ("openvcu-http-" + std::to_string(::getpid()) + "-" + std::to_string(++counter));
  fs::remove_all(folder);
  fs::create_directories(folder / "www");
  fs::create_directories(folder / "uploads");
  return folder;
}

inline void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

inline std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline std::size_t filesIn(const fs::path& folder) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(folder), fs::directory_iterator()));
}

/// A connected loopback socket, or -1. `receiveBuffer` > 0: SO_RCVBUF before connecting.
inline int connectTo(std::uint16_t port, int receiveBuffer = 0) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  if (receiveBuffer > 0) ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receiveBuffer, sizeof receiveBuffer);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

/// A loopback socket connected from the local address `source` ("127.0.0.2": another client as
/// the server counts clients), or -1.
inline int connectFrom(std::uint16_t port, const char* source) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in local{};
  local.sin_family = AF_INET;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::inet_pton(AF_INET, source, &local.sin_addr) != 1 ||
      ::bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0 ||
      ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

inline bool sendAll(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n <= 0) return false;
    data.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

/// Reads until the peer closes, `until` returns true for what has arrived, or the deadline.
/// `closed` (when given) tells whether the peer closed.
inline std::string readFrom(int fd, Clock::duration timeout, const std::function<bool(const std::string&)>& until = {},
                            bool* closed = nullptr) {
  if (closed != nullptr) *closed = false;
  std::string data;
  const auto deadline = Clock::now() + timeout;
  char buffer[16384];
  while (Clock::now() < deadline) {
    pollfd entry{fd, POLLIN, 0};
    const auto leftMs = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (::poll(&entry, 1, static_cast<int>(std::max<long long>(leftMs, 1))) <= 0) continue;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) {
      if (closed != nullptr) *closed = true;
      break;
    }
    data.append(buffer, static_cast<std::size_t>(n));
    if (until && until(data)) break;
  }
  return data;
}

struct Answer {
  unsigned status{0};
  std::map<std::string, std::string> headers;  ///< lower-case names
  std::string body;
  [[nodiscard]] std::string header(const std::string& name) const {
    const auto it = headers.find(name);
    return it == headers.end() ? std::string{} : it->second;
  }
};

inline Answer parseAnswer(std::string raw) {
  Answer answer;
  // interim answers ("HTTP/1.1 100 Continue") come before the answer
  while (raw.rfind("HTTP/1.1 1", 0) == 0 && raw.find("\r\n\r\n") != std::string::npos)
    raw.erase(0, raw.find("\r\n\r\n") + 4);
  const std::size_t end = raw.find("\r\n\r\n");
  if (raw.size() < 12 || end == std::string::npos) return answer;
  answer.status = static_cast<unsigned>(std::stoul(raw.substr(9, 3)));
  std::size_t lineStart = raw.find("\r\n") + 2;
  while (lineStart < end) {
    const std::size_t lineEnd = raw.find("\r\n", lineStart);
    const std::string line = raw.substr(lineStart, lineEnd - lineStart);
    const std::size_t colon = line.find(':');
    if (colon != std::string::npos) {
      std::string name = line.substr(0, colon);
      for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      answer.headers[name] = line.substr(line.find_first_not_of(' ', colon + 1));
    }
    lineStart = lineEnd + 2;
  }
  answer.body = raw.substr(end + 4);
  return answer;
}

/// One request on a fresh connection ("Connection: close"), the answer read to the end.
inline Answer request(std::uint16_t port, const std::string& method, const std::string& target,
                      const std::string& body = {}, const std::string& extraHeaders = {}) {
  const int fd = connectTo(port);
  REQUIRE(fd >= 0);
  std::string text = method + " " + target + " HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n" + extraHeaders;
  if (!body.empty()) text += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  text += "\r\n" + body;
  sendAll(fd, text);
  const std::string raw = readFrom(fd, CLIENT_TIMEOUT);
  ::close(fd);
  return parseAnswer(raw);
}

inline Answer get(std::uint16_t port, const std::string& target) {
  return request(port, "GET", target);
}

/// Waits (polling, bounded) until `condition` holds.
inline bool eventually(const std::function<bool()>& condition, Clock::duration timeout = 3s) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return condition();
}

/// A server on a free loopback port with its own folders, served on a thread of its own.
struct TestServer {
  fs::path folder = makeTempFolder();
  web::ServerOptions options = [this] {
    web::ServerOptions defaults;
    defaults.port = 0;
    defaults.staticRoot = folder / "www";
    defaults.uploadFolder = folder / "uploads";
    defaults.readTimeout = 2s;
    defaults.writeTimeout = 2s;
    return defaults;
  }();
  std::optional<web::HttpServer> sut;
  std::thread thread;
  std::atomic<bool> runReturned{false};

  web::HttpServer& make() {
    sut.emplace(options);
    return *sut;
  }
  std::uint16_t start() {
    if (!sut) make();
    auto started = sut->start();
    REQUIRE(started.ok());
    thread = std::thread([this] {
      sut->run();
      runReturned = true;
    });
    return sut->port();
  }
  TestServer() = default;
  TestServer(const TestServer&) = delete;
  TestServer& operator=(const TestServer&) = delete;
  ~TestServer() {
    if (thread.joinable()) {
      sut->stop();
      thread.join();
    }
    sut.reset();
    std::error_code ec;
    fs::remove_all(folder, ec);
  }
};

}  // namespace webtest
