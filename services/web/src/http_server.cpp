#include "http_server.hpp"

#include <algorithm>
#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <cmath>
#include <exception>

#include "http_connection.hpp"
#include "http_util.hpp"

namespace openvcu::web {

// ---- Request, Response ----------------------------------------------------------------

std::string Request::cookie(std::string_view name) const {
  const std::string cookies = header("cookie");
  std::string_view rest = cookies;
  while (!rest.empty()) {
    const std::size_t semicolon = rest.find(';');
    std::string_view pair = rest.substr(0, semicolon);
    rest = semicolon == std::string_view::npos ? std::string_view{} : rest.substr(semicolon + 1);
    while (!pair.empty() && (pair.front() == ' ' || pair.front() == '\t')) pair.remove_prefix(1);
    while (!pair.empty() && (pair.back() == ' ' || pair.back() == '\t')) pair.remove_suffix(1);
    const std::size_t eq = pair.find('=');
    if (eq == std::string_view::npos || pair.substr(0, eq) != name) continue;
    std::string_view value = pair.substr(eq + 1);
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"') value = value.substr(1, value.size() - 2);
    return std::string(value);
  }
  return {};
}

std::string Request::header(std::string_view lowerCaseName) const {
  const auto it = headers.find(std::string(lowerCaseName));
  return it == headers.end() ? std::string{} : it->second;
}

Response Response::json(unsigned status, std::string json) {
  Response response;
  response.status = status;
  response.body = std::move(json);
  return response;
}

Response Response::error(unsigned status, std::string_view message) {
  return json(status, "{\"error\": \"" + detail::jsonEscape(message) + "\"}");
}

std::string_view methodName(Method method) noexcept {
  switch (method) {
    case Method::Get:
      return "GET";
    case Method::Post:
      return "POST";
    case Method::Delete:
      return "DELETE";
  }
  return "GET";
}

// ---- ServerCore -----------------------------------------------------------------------

namespace detail {
namespace {

bool pathMatches(const std::string& routePath, const std::string& path) {
  if (!routePath.empty() && routePath.back() == '/')
    return path.size() > routePath.size() && path.rfind(routePath, 0) == 0;
  return routePath == path;
}

template <class Entries>
auto findBest(const Entries& entries, const std::string& path) -> decltype(&entries.front().second) {
  decltype(&entries.front().second) best = nullptr;
  std::size_t bestLength = 0;
  for (const auto& [routePath, value] : entries) {
    if (routePath == path) return &value;
    if (pathMatches(routePath, path) && routePath.size() > bestLength) {
      best = &value;
      bestLength = routePath.size();
    }
  }
  return best;
}

/// The 503 sent (best effort, without waiting) to a connection refused for a limit.
std::string refusal(std::string_view reason) {
  const std::string body = "{\"error\": \"" + jsonEscape(reason) + "\"}\n";
  return "HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json\r\nContent-Length: " +
         std::to_string(body.size()) + "\r\nRetry-After: 1\r\nConnection: close\r\n\r\n" + body;
}

}  // namespace

ServerCore::ServerCore(ServerOptions serverOptions)
    : options(std::move(serverOptions)), link(std::make_shared<ResponderLink>()) {
  link->io = &io;
}

ServerCore::~ServerCore() {
  {
    const std::lock_guard<std::mutex> lock(link->mutex);
    link->io = nullptr;
  }
  stopping = true;
  beast::error_code ec;
  acceptor.close(ec);
  closeAll();
}

const Handler* ServerCore::findRoute(Method method, const std::string& path) const {
  const Handler* best = nullptr;
  std::size_t bestLength = 0;
  for (const RouteEntry& entry : routes) {
    if (entry.method != method) continue;
    if (entry.path == path) return &entry.handler;
    if (pathMatches(entry.path, path) && entry.path.size() > bestLength) {
      best = &entry.handler;
      bestLength = entry.path.size();
    }
  }
  return best;
}

const UploadRoute* ServerCore::findUpload(const std::string& path) const {
  return findBest(uploads, path);
}

const StreamOpener* ServerCore::findStream(const std::string& path) const {
  return findBest(streams, path);
}

bool ServerCore::knowsPath(const std::string& path) const {
  const bool routed =
      std::any_of(routes.begin(), routes.end(), [&](const RouteEntry& entry) { return pathMatches(entry.path, path); });
  return routed || findUpload(path) != nullptr || findStream(path) != nullptr;
}

bool ServerCore::takeToken(const std::string& address, unsigned& retryAfterS) {
  const double rate = options.requestsPerSecondPerAddress;
  if (rate <= 0) return true;
  const double burst = std::max(1.0, options.requestBurstPerAddress);
  const auto now = Clock::now();
  auto [it, inserted] = addresses.try_emplace(address);
  AddressState& state = it->second;
  if (inserted) {
    state.tokens = burst;
  } else {
    const double elapsedS = std::chrono::duration<double>(now - state.refilled).count();
    state.tokens = std::min(burst, state.tokens + elapsedS * rate);
  }
  state.refilled = now;
  if (state.tokens >= 1.0) {
    state.tokens -= 1.0;
    return true;
  }
  retryAfterS = static_cast<unsigned>(std::max(1.0, std::ceil((1.0 - state.tokens) / rate)));
  return false;
}

void ServerCore::pruneAddresses(Clock::time_point now) {
  // an entry without connections whose bucket has refilled says nothing a fresh one would not
  const double burst = std::max(1.0, options.requestBurstPerAddress);
  const double rate = options.requestsPerSecondPerAddress;
  for (auto it = addresses.begin(); it != addresses.end();) {
    const double elapsedS = std::chrono::duration<double>(now - it->second.refilled).count();
    const bool full = rate <= 0 || it->second.tokens + elapsedS * rate >= burst;
    const bool unused = it->second.connections == 0 && it->second.streams == 0;
    it = (unused && full) ? addresses.erase(it) : std::next(it);
  }
}

void ServerCore::accept() {
  if (stopping) return;
  acceptor.async_accept(
      [this](const beast::error_code& ec, asio::ip::tcp::socket socket) { onAccept(ec, std::move(socket)); });
}

void ServerCore::onAccept(const beast::error_code& ec, asio::ip::tcp::socket socket) {
  if (stopping || ec == asio::error::operation_aborted) return;
  if (ec) {
    // out of descriptors and the like: try again shortly instead of spinning
    acceptRetry.expires_after(std::chrono::milliseconds(100));
    acceptRetry.async_wait([this](const beast::error_code& waitError) {
      if (!waitError) accept();
    });
    return;
  }
  beast::error_code endpointError;
  const auto endpoint = socket.remote_endpoint(endpointError);
  if (endpointError) {
    accept();
    return;
  }
  try {
    std::string address = endpoint.address().to_string();
    const auto now = Clock::now();
    if (addresses.size() >= ADDRESS_TABLE_PRUNE_SIZE) pruneAddresses(now);
    auto [it, inserted] = addresses.try_emplace(address);
    if (inserted) {
      it->second.tokens = std::max(1.0, options.requestBurstPerAddress);
      it->second.refilled = now;
    }
    // a full table makes room by closing a connection that only waits (an idle keep-alive, a
    // request trickling in); busy ones (answers, uploads, streams) are kept and the new one refused
    AddressState& state = it->second;
    std::string refused;
    if (state.connections >= options.maxConnectionsPerAddress && !evictWaiting(&address)) {
      refused = "too many connections from " + address + ": all " + std::to_string(state.connections) +
                " are busy with requests";
    } else if (connections.size() >= options.maxConnections && !evictWaiting(nullptr)) {
      refused = "too many connections: all " + std::to_string(connections.size()) +
                " are busy with requests or event streams";
    }
    if (!refused.empty()) {
      refusedConnections.fetch_add(1, std::memory_order_relaxed);
      const std::string text = refusal(refused);
      beast::error_code ignored;
      socket.non_blocking(true, ignored);
      socket.write_some(asio::buffer(text.data(), text.size()), ignored);
      socket.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
      socket.close(ignored);
    } else {
      beast::error_code ignored;
      socket.set_option(asio::ip::tcp::no_delay(true), ignored);  // events go out as written
      ++state.connections;
      const std::uint64_t id = nextConnectionId++;
      auto connection = std::make_shared<Connection>(*this, id, std::move(socket), std::move(address));
      connections.emplace(id, connection);
      connectionCount.store(connections.size());
      connection->start();
    }
  } catch (...) {
    // out of memory: this connection is dropped (its socket closes with it), the server goes on
  }
  accept();
}

void ServerCore::closeAll() {
  std::vector<std::shared_ptr<Connection>> open;
  open.reserve(connections.size());
  for (const auto& [id, connection] : connections) open.push_back(connection);
  for (const auto& connection : open) connection->close();
}

bool ServerCore::evictWaiting(const std::string* address) {
  std::shared_ptr<Connection> victim;
  for (const auto& [id, connection] : connections) {
    if (!connection->waiting() || (address != nullptr && connection->address() != *address)) continue;
    if (!victim || connection->waitingSince() < victim->waitingSince()) victim = connection;
  }
  if (!victim) return false;
  evictedConnections.fetch_add(1, std::memory_order_relaxed);
  victim->close();
  return true;
}

std::optional<std::string> ServerCore::makeRoomForStream(const std::string& address) {
  std::size_t own = 0;
  std::size_t most = 0;
  const std::string* holder = nullptr;
  for (const auto& [name, state] : addresses) {
    if (name == address) own = state.streams;
    if (state.streams > most) {
      most = state.streams;
      holder = &name;
    }
  }
  // fair shares: a second page of one address replaces its first before it takes another's
  const std::string* from = nullptr;
  if (own > 0 && own >= most) {
    from = &address;
  } else if (most > own + 1) {
    from = holder;
  }
  std::shared_ptr<Connection> victim;
  if (from != nullptr) {
    for (const auto& [id, connection] : connections) {
      if (!connection->streaming() || connection->address() != *from) continue;
      if (!victim || connection->streamingSince() < victim->streamingSince()) victim = connection;
    }
  }
  if (!victim) {
    return "too many event streams: all " + std::to_string(streamCount.load()) + " are open, at most " +
           std::to_string(most) + " per address";
  }
  evictedStreams.fetch_add(1, std::memory_order_relaxed);
  victim->close();
  return std::nullopt;
}

void ServerCore::connectionBecameStream(const std::string& address) {
  const auto it = addresses.find(address);
  if (it == addresses.end()) return;
  if (it->second.connections > 0) --it->second.connections;
  ++it->second.streams;
}

void ServerCore::connectionClosed(std::uint64_t id, const std::string& address, bool wasStream) {
  connections.erase(id);
  connectionCount.store(connections.size());
  const auto it = addresses.find(address);
  if (it == addresses.end()) return;
  std::size_t& count = wasStream ? it->second.streams : it->second.connections;
  if (count > 0) --count;
}

}  // namespace detail

// ---- HttpServer -----------------------------------------------------------------------

struct HttpServer::Impl : detail::ServerCore {
  using ServerCore::ServerCore;
};

HttpServer::HttpServer(ServerOptions options) : m_impl(std::make_unique<Impl>(std::move(options))) {}

HttpServer::~HttpServer() = default;

void HttpServer::route(Method method, std::string path, Handler handler) {
  m_impl->routes.push_back({method, std::move(path), std::move(handler)});
}

void HttpServer::upload(std::string path, UploadRoute route) {
  m_impl->uploads.emplace_back(std::move(path), std::move(route));
}

void HttpServer::stream(std::string path, StreamOpener opener) {
  m_impl->streams.emplace_back(std::move(path), std::move(opener));
}

Status HttpServer::start() {
  namespace asio = boost::asio;
  const std::string where = m_impl->options.address + ":" + std::to_string(m_impl->options.port);
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(m_impl->options.address, ec);
  if (ec) return Error{where + ": not an IP address"};
  const asio::ip::tcp::endpoint endpoint(address, m_impl->options.port);
  auto& acceptor = m_impl->acceptor;
  acceptor.open(endpoint.protocol(), ec);
  if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    boost::system::error_code ignored;
    acceptor.close(ignored);
    return Error{where + ": " + ec.message()};
  }
  m_impl->boundPort = acceptor.local_endpoint(ec).port();
  m_impl->accept();
  return {};
}

std::uint16_t HttpServer::port() const noexcept {
  return m_impl->boundPort;
}

void HttpServer::run() {
  for (;;) {
    try {
      m_impl->io.run();
      return;
    } catch (...) {
      // a handler of the app threw through the io context: keep serving
    }
  }
}

void HttpServer::stop() {
  detail::ServerCore* core = m_impl.get();
  boost::asio::post(core->io, [core] {
    core->stopping = true;
    boost::system::error_code ec;
    core->acceptor.close(ec);
    core->acceptRetry.cancel();
    core->closeAll();
    // after the completions the closes queued: every connection has let go
    boost::asio::post(core->io, [core] { core->io.stop(); });
  });
}

void HttpServer::post(std::function<void()> work) {
  boost::asio::post(m_impl->io, [work = std::move(work)] {
    try {
      work();
    } catch (...) {
      // the app's work failed; the server goes on
    }
  });
}

boost::asio::io_context& HttpServer::context() noexcept {
  return m_impl->io;
}

ServerCounters HttpServer::counters() const {
  ServerCounters counters;
  counters.requests = m_impl->requests.load();
  counters.refusedConnections = m_impl->refusedConnections.load();
  counters.evictedConnections = m_impl->evictedConnections.load();
  counters.evictedStreams = m_impl->evictedStreams.load();
  counters.rateLimited = m_impl->rateLimited.load();
  counters.eventsSent = m_impl->eventsSent.load();
  counters.eventsSkipped = m_impl->eventsSkipped.load();
  counters.connections = m_impl->connectionCount.load();
  counters.streams = m_impl->streamCount.load();
  return counters;
}

}  // namespace openvcu::web
