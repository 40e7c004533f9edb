#pragma once
// The inside of HttpServer (http_server.hpp): the state every connection shares (routes,
// limits, per-address accounting, counters, the io context) and one client connection.
// Everything here runs on the io thread, except the atomics of ServerCore and ResponderLink.

#include <array>
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/file_body.hpp>
#include <boost/beast/http/parser.hpp>
#include <boost/beast/http/string_body.hpp>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "http_server.hpp"

namespace openvcu::web::detail {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using Clock = std::chrono::steady_clock;

/// Request headers beyond this size: 400 and the connection is closed.
inline constexpr std::size_t HEADER_LIMIT_BYTES = 8 * 1024;
/// A comment line on an idle event stream so proxies keep it open.
inline constexpr std::chrono::seconds KEEP_ALIVE_INTERVAL{15};
/// After an answer with "Connection: close": how long and how much of the rest of the
/// request is read and dropped, so the client sees the answer instead of a reset.
inline constexpr std::chrono::seconds LINGER_TIME{2};
inline constexpr std::size_t LINGER_BYTES = 1024 * 1024;
/// Address entries without connections are pruned beyond this many.
inline constexpr std::size_t ADDRESS_TABLE_PRUNE_SIZE = 1024;
/// The first read of a request (which starts its deadline) takes up to this much.
inline constexpr std::size_t FIRST_READ_BYTES = 4096;

/// How a Responder (any thread) reaches the io context; `io` is cleared under the mutex when
/// the server is destroyed, so a late Responder drops its answer instead of touching it.
struct ResponderLink {
  std::mutex mutex;
  asio::io_context* io{nullptr};
};

class Connection;

struct ServerCore {
  explicit ServerCore(ServerOptions serverOptions);
  ~ServerCore();
  ServerCore(const ServerCore&) = delete;
  ServerCore& operator=(const ServerCore&) = delete;

  struct RouteEntry {
    Method method;
    std::string path;  ///< ends with '/': a prefix
    Handler handler;
  };
  struct AddressState {
    std::size_t connections{};  ///< open, event streams not included
    std::size_t streams{};      ///< open event streams
    double tokens{};
    Clock::time_point refilled{};
  };

  /// The handler of (method, path): an exact route, else the longest prefix route.
  [[nodiscard]] const Handler* findRoute(Method method, const std::string& path) const;
  [[nodiscard]] const UploadRoute* findUpload(const std::string& path) const;
  [[nodiscard]] const StreamOpener* findStream(const std::string& path) const;
  /// true when any route, upload or stream answers `path` (with another method: 405).
  [[nodiscard]] bool knowsPath(const std::string& path) const;

  /// One request of `address` against its token bucket; false (and the seconds until the
  /// next token in `retryAfterS`) when the bucket is empty.
  bool takeToken(const std::string& address, unsigned& retryAfterS);
  void accept();
  void closeAll();
  /// Closes the connection that has waited longest for a request (of `address` when given);
  /// false when every such connection is busy. O(connections), only when a limit is reached.
  bool evictWaiting(const std::string* address);
  /// Called when maxStreams are open and `address` asks for one more: ends the oldest stream of
  /// the address holding the most streams (`address` itself on a tie) when that address holds
  /// more than `address` would; otherwise returns why the new stream is refused.
  std::optional<std::string> makeRoomForStream(const std::string& address);
  /// Called by a Connection that became an event stream: its address counts it as a stream.
  void connectionBecameStream(const std::string& address);
  /// Called once by Connection::close().
  void connectionClosed(std::uint64_t id, const std::string& address, bool wasStream);

  ServerOptions options;
  std::vector<RouteEntry> routes;
  std::vector<std::pair<std::string, UploadRoute>> uploads;
  std::vector<std::pair<std::string, StreamOpener>> streams;

  std::unordered_map<std::string, AddressState> addresses;
  std::unordered_map<std::uint64_t, std::shared_ptr<Connection>> connections;
  std::uint64_t nextConnectionId{1};
  bool stopping{false};
  std::uint16_t boundPort{0};

  std::atomic<std::uint64_t> requests{0};
  std::atomic<std::uint64_t> refusedConnections{0};
  std::atomic<std::uint64_t> evictedConnections{0};
  std::atomic<std::uint64_t> evictedStreams{0};
  std::atomic<std::uint64_t> rateLimited{0};
  std::atomic<std::uint64_t> eventsSent{0};
  std::atomic<std::uint64_t> eventsSkipped{0};
  std::atomic<std::size_t> connectionCount{0};
  std::atomic<std::size_t> streamCount{0};

  std::shared_ptr<ResponderLink> link;
  // declared last: destroyed first, while the tables above still exist for the handlers
  // (and their connections) that the io context destroys
  asio::io_context io;
  asio::ip::tcp::acceptor acceptor{io};
  asio::steady_timer acceptRetry{io};

 private:
  void onAccept(const beast::error_code& ec, asio::ip::tcp::socket socket);
  void pruneAddresses(Clock::time_point now);
};

/// One client connection: requests one after the other (keep-alive, no pipelining), then
/// possibly one event stream until either side ends it.
class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(ServerCore& core, std::uint64_t id, asio::ip::tcp::socket socket, std::string address);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  void start();
  /// Closes the socket, stops the stream, removes a partial upload; idempotent.
  void close();
  /// Waiting for a request, receiving one, or lingering after its last answer: closing it
  /// loses no answer. Since when (the oldest gives way first; lingering ones before all).
  [[nodiscard]] bool waiting() const noexcept { return m_waiting && !m_closed; }
  [[nodiscard]] Clock::time_point waitingSince() const noexcept { return m_waitingSince; }
  /// An open event stream, and since when.
  [[nodiscard]] bool streaming() const noexcept { return m_source != nullptr && !m_closed; }
  [[nodiscard]] Clock::time_point streamingSince() const noexcept { return m_streamingSince; }
  [[nodiscard]] const std::string& address() const noexcept { return m_address; }
  /// The answer to request `sequence` (posted by its Responder); dropped when stale.
  void answer(std::uint64_t sequence, Response response);

 private:
  /// Waits (readTimeout) for the first byte of the next request, then reads its header.
  void readHeader();
  /// Reads the header with the request deadline (requestTimeout from the first byte).
  void readRequestHeader();
  void onHeader(const beast::error_code& ec);
  void readBody();
  void dispatchRequest();
  void serveStatic();
  void startUpload(const UploadRoute& route);
  void readUpload();
  void finishUpload();
  void startStream(const StreamOpener& opener);
  void scheduleTick();
  void onTick();
  void writeEvent();
  void readDiscard();
  /// "HTTP/1.1 100 Continue" when the client asked for it, then `next`.
  void continueThen(void (Connection::*next)());
  Responder makeResponder();
  /// Sends `response`; the connection stays open when both sides allow it and not `closeAfter`.
  void respond(Response response, bool closeAfter = false);
  void afterResponse(bool keepAlive);
  void lingerThenClose(std::size_t drained);
  [[nodiscard]] bool requestHasBody() const;
  template <class Body>
  void prepareHeaders(http::response<Body>& message, const Response& response, bool keepAlive) const;
  template <class Body>
  void sendMessage(std::shared_ptr<http::response<Body>> message, std::shared_ptr<void> keep);

  ServerCore& m_core;
  std::uint64_t m_id;
  beast::tcp_stream m_stream;
  std::string m_address;
  beast::flat_buffer m_buffer;
  std::optional<http::request_parser<http::empty_body>> m_headerParser;
  std::optional<http::request_parser<http::string_body>> m_bodyParser;
  std::optional<http::request_parser<http::file_body>> m_uploadParser;
  const UploadRoute* m_upload{nullptr};
  std::filesystem::path m_uploadFile;  ///< owned (removed on close) until handed to onComplete
  Request m_request;
  unsigned m_version{11};
  bool m_clientKeepAlive{false};
  bool m_expectContinue{false};
  std::uint64_t m_sequence{0};
  bool m_awaiting{false};
  bool m_closed{false};
  bool m_waiting{false};
  Clock::time_point m_waitingSince{};
  Clock::time_point m_requestDeadline{};

  // event stream
  std::unique_ptr<EventSource> m_source;
  Clock::time_point m_streamingSince{};
  asio::steady_timer m_tick;
  Clock::duration m_tickPeriod{};
  std::string m_eventText;
  bool m_writing{false};
  Clock::time_point m_writeStarted{};
  Clock::time_point m_lastWrite{};
  std::array<char, 512> m_discard{};
};

}  // namespace openvcu::web::detail
