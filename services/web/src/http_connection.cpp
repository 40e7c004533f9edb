#include "http_connection.hpp"

#include <algorithm>
#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/http/read.hpp>
#include <boost/beast/http/serializer.hpp>
#include <boost/beast/http/write.hpp>
#include <exception>
#include <limits>
#include <system_error>

#include "http_util.hpp"

namespace openvcu::web::detail {
namespace {

/// Removes a file when the last owner lets go (a download with deleteFileAfter, sent or not).
struct FileRemover {
  std::filesystem::path path;
  ~FileRemover() {
    std::error_code ec;
    if (!path.empty()) std::filesystem::remove(path, ec);
  }
};

/// A Responder's shared state: answers once; an answer never given becomes a 500.
struct PendingAnswer {
  std::shared_ptr<ResponderLink> link;
  std::weak_ptr<Connection> connection;
  std::uint64_t sequence{};
  std::atomic<bool> answered{false};

  void deliver(Response response) noexcept {
    try {
      const std::lock_guard<std::mutex> lock(link->mutex);
      if (link->io == nullptr) return;
      asio::post(*link->io, [connection = connection, sequence = sequence, response = std::move(response)]() mutable {
        if (auto alive = connection.lock()) alive->answer(sequence, std::move(response));
      });
    } catch (...) {
      // out of memory while posting: the connection keeps waiting until the client leaves
    }
  }
  ~PendingAnswer() {
    if (!answered.exchange(true)) deliver(Response::error(500, "the request was not answered"));
  }
};

std::optional<Method> methodOf(http::verb verb) noexcept {
  switch (verb) {
    case http::verb::get:
      return Method::Get;
    case http::verb::post:
      return Method::Post;
    case http::verb::delete_:
      return Method::Delete;
    default:
      return std::nullopt;
  }
}

bool isApiPath(const std::string& path) {
  return path == "/api" || path.rfind("/api/", 0) == 0;
}

/// A file name safe inside a quoted Content-Disposition parameter.
std::string dispositionName(std::string_view name) {
  std::string out;
  for (const char c : name) {
    if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      out.push_back('_');
    } else {
      out.push_back(c);
    }
  }
  return out;
}

}  // namespace

Connection::Connection(ServerCore& core, std::uint64_t id, asio::ip::tcp::socket socket, std::string address)
    : m_core(core), m_id(id), m_stream(std::move(socket)), m_address(std::move(address)), m_tick(core.io) {}

Connection::~Connection() {
  std::error_code ec;
  if (!m_uploadFile.empty()) std::filesystem::remove(m_uploadFile, ec);
}

void Connection::start() {
  readHeader();
}

void Connection::close() {
  if (m_closed) return;
  m_closed = true;
  const auto self = shared_from_this();  // the registry may hold the last reference
  beast::error_code ec;
  m_stream.socket().shutdown(asio::ip::tcp::socket::shutdown_both, ec);
  m_stream.close();
  m_tick.cancel();
  const bool wasStream = m_source != nullptr;
  if (m_source) {
    m_source.reset();
    m_core.streamCount.fetch_sub(1);
  }
  m_uploadParser.reset();  // closes the upload file before it is removed
  if (!m_uploadFile.empty()) {
    std::error_code removeError;
    std::filesystem::remove(m_uploadFile, removeError);
    m_uploadFile.clear();
  }
  m_core.connectionClosed(m_id, m_address, wasStream);
}

// ---- requests -------------------------------------------------------------------------

void Connection::readHeader() {
  if (m_closed) return;
  m_headerParser.emplace();
  m_headerParser->header_limit(static_cast<std::uint32_t>(HEADER_LIMIT_BYTES));
  // the body limit depends on the route: checked after the header (see onHeader)
  m_headerParser->body_limit(std::numeric_limits<std::uint64_t>::max());
  m_bodyParser.reset();
  m_uploadParser.reset();
  m_upload = nullptr;
  m_request = Request{};
  m_waiting = true;
  m_waitingSince = Clock::now();
  if (m_buffer.size() > 0) {  // the client sent its next request already
    readRequestHeader();
    return;
  }
  // idle until the first byte (readTimeout); from there the request has its own deadline
  m_stream.expires_after(m_core.options.readTimeout);
  m_stream.async_read_some(m_buffer.prepare(FIRST_READ_BYTES),
                           [self = shared_from_this()](const beast::error_code& ec, std::size_t n) {
                             if (self->m_closed) return;
                             if (ec) {
                               self->close();  // gone, or idle for readTimeout: nothing to answer
                               return;
                             }
                             self->m_buffer.commit(n);
                             self->readRequestHeader();
                           });
}

void Connection::readRequestHeader() {
  // one deadline for the whole request, not renewed by each byte: a client trickling its
  // header or body holds a connection for requestTimeout at most
  m_requestDeadline = Clock::now() + m_core.options.requestTimeout;
  m_stream.expires_at(m_requestDeadline);
  http::async_read_header(
      m_stream, m_buffer, *m_headerParser,
      [self = shared_from_this()](const beast::error_code& ec, std::size_t) { self->onHeader(ec); });
}

bool Connection::requestHasBody() const {
  if (!m_headerParser) return false;
  const auto length = m_headerParser->content_length();
  return m_headerParser->chunked() || (length && *length > 0);
}

void Connection::onHeader(const beast::error_code& ec) {
  if (m_closed) return;
  if (ec) {
    // a client that closed or went quiet gets nothing; a broken header gets a 400
    if (ec == http::error::end_of_stream || ec == beast::error::timeout || ec == asio::error::operation_aborted ||
        ec == asio::error::connection_reset || ec == asio::error::eof) {
      close();
    } else {
      m_version = 11;
      m_clientKeepAlive = false;
      respond(Response::error(400, ec == http::error::header_limit ? "request header too large" : "malformed request"),
              true);
    }
    return;
  }
  m_core.requests.fetch_add(1, std::memory_order_relaxed);
  const auto& header = m_headerParser->get();
  m_version = header.version();
  m_clientKeepAlive = m_headerParser->keep_alive();
  m_request.clientAddress = m_address;
  for (const auto& field : header) {
    const auto rawName = field.name_string();
    std::string name = lowerCase(std::string_view(rawName.data(), rawName.size()));
    auto [it, inserted] = m_request.headers.try_emplace(std::move(name), std::string(field.value()));
    if (!inserted) {
      it->second += it->first == "cookie" ? "; " : ", ";
      it->second.append(field.value().data(), field.value().size());
    }
  }
  m_expectContinue = lowerCase(m_request.header("expect")) == "100-continue";

  unsigned retryAfterS = 0;
  if (!m_core.takeToken(m_address, retryAfterS)) {
    m_core.rateLimited.fetch_add(1, std::memory_order_relaxed);
    Response refusal = Response::error(429, "too many requests");
    refusal.headers.emplace_back("Retry-After", std::to_string(retryAfterS));
    respond(std::move(refusal), requestHasBody());
    return;
  }
  if (!m_core.options.allowedHosts.empty()) {
    // DNS rebinding: a page of another site resolved to this address sends its own Host
    std::string host = lowerCase(m_request.header("host"));
    if (host.starts_with('[')) {
      host = host.substr(0, host.find(']') + 1);
    } else if (const auto colon = host.rfind(':'); colon != std::string::npos) {
      host.resize(colon);
    }
    const auto& allowed = m_core.options.allowedHosts;
    if (std::find(allowed.begin(), allowed.end(), host) == allowed.end()) {
      respond(Response::error(421, "Host '" + host + "' is not this VCU's; open it by its address"), requestHasBody());
      return;
    }
  }
  const auto method = methodOf(header.method());
  if (!method) {
    Response refusal = Response::error(405, "method not allowed");
    refusal.headers.emplace_back("Allow", "GET, POST, DELETE");
    respond(std::move(refusal), requestHasBody());
    return;
  }
  m_request.method = *method;
  const auto rawTarget = header.target();
  auto target = parseTarget(std::string_view(rawTarget.data(), rawTarget.size()));
  if (!target) {
    respond(Response::error(400, "malformed request target"), true);
    return;
  }
  m_request.path = std::move(target->path);
  m_request.query = std::move(target->query);

  if (m_request.method == Method::Post) {
    if (const UploadRoute* upload = m_core.findUpload(m_request.path)) {
      m_waiting = false;  // authorized uploads are busy connections with a timeout per read
      startUpload(*upload);
      return;
    }
  }
  const auto length = m_headerParser->content_length();
  if (length && *length > m_core.options.maxBodyBytes) {
    respond(Response::error(413, "request body too large"), true);
    return;
  }
  if (m_headerParser->is_done()) {
    dispatchRequest();
    return;
  }
  m_bodyParser.emplace(std::move(*m_headerParser));
  m_headerParser.reset();
  m_bodyParser->body_limit(static_cast<std::uint64_t>(m_core.options.maxBodyBytes));
  continueThen(&Connection::readBody);
}

void Connection::continueThen(void (Connection::*next)()) {
  if (!m_expectContinue) {
    (this->*next)();
    return;
  }
  static constexpr std::string_view CONTINUE = "HTTP/1.1 100 Continue\r\n\r\n";
  m_stream.expires_after(m_core.options.writeTimeout);
  asio::async_write(m_stream, asio::buffer(CONTINUE.data(), CONTINUE.size()),
                    [self = shared_from_this(), next](const beast::error_code& ec, std::size_t) {
                      if (self->m_closed) return;
                      if (ec) {
                        self->close();
                        return;
                      }
                      ((*self).*next)();
                    });
}

void Connection::readBody() {
  if (m_closed) return;
  m_stream.expires_at(m_requestDeadline);  // the header's deadline: the body is part of the request
  http::async_read_some(m_stream, m_buffer, *m_bodyParser,
                        [self = shared_from_this()](const beast::error_code& ec, std::size_t) {
                          if (self->m_closed) return;
                          if (ec == http::error::body_limit) {
                            self->respond(Response::error(413, "request body too large"), true);
                          } else if (ec) {
                            self->close();
                          } else if (self->m_bodyParser->is_done()) {
                            self->m_request.body = std::move(self->m_bodyParser->get().body());
                            self->m_bodyParser.reset();
                            self->dispatchRequest();
                          } else {
                            self->readBody();
                          }
                        });
}

void Connection::dispatchRequest() {
  m_waiting = false;
  const std::string& path = m_request.path;
  if (m_request.method == Method::Get) {
    if (const StreamOpener* opener = m_core.findStream(path)) {
      startStream(*opener);
      return;
    }
  }
  if (const Handler* handler = m_core.findRoute(m_request.method, path)) {
    Responder responder = makeResponder();
    try {
      (*handler)(m_request, responder);
    } catch (const std::exception& error) {
      responder(Response::error(500, error.what()));
    } catch (...) {
      responder(Response::error(500, "internal error"));
    }
    return;
  }
  if (m_core.knowsPath(path)) {
    Response refusal = Response::error(405, "method not allowed");
    respond(std::move(refusal));
    return;
  }
  if (m_request.method == Method::Get && !isApiPath(path)) {
    serveStatic();
    return;
  }
  respond(Response::error(404, "not found"));
}

void Connection::serveStatic() {
  const std::string& path = m_request.path;
  std::optional<std::filesystem::path> file;
  if (!m_core.options.staticRoot.empty()) {
    file = resolveUnder(m_core.options.staticRoot,
                        path == "/" ? std::string_view("index.html") : std::string_view(path).substr(1));
  }
  std::error_code ec;
  if (!file || !std::filesystem::is_regular_file(*file, ec)) {
    respond(Response::error(404, "not found"));
    return;
  }
  Response response;
  response.contentType = std::string(contentTypeFor(file->filename().string()));
  response.file = *file;
  response.headers.emplace_back("Cache-Control", "no-cache");
  if (response.contentType.rfind("text/html", 0) == 0) {
    response.headers.emplace_back("Content-Security-Policy",
                                  "default-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'none'; "
                                  "form-action 'self'");
  }
  respond(std::move(response));
}

// ---- answers --------------------------------------------------------------------------

Responder Connection::makeResponder() {
  ++m_sequence;
  m_awaiting = true;
  auto pending = std::make_shared<PendingAnswer>();
  pending->link = m_core.link;
  pending->connection = weak_from_this();
  pending->sequence = m_sequence;
  return [pending](Response response) {
    if (!pending->answered.exchange(true)) pending->deliver(std::move(response));
  };
}

void Connection::answer(std::uint64_t sequence, Response response) {
  if (m_closed || !m_awaiting || sequence != m_sequence) {
    std::error_code ec;
    if (response.file && response.deleteFileAfter) std::filesystem::remove(*response.file, ec);
    return;
  }
  m_awaiting = false;
  respond(std::move(response));
}

template <class Body>
void Connection::prepareHeaders(http::response<Body>& message, const Response& response, bool keepAlive) const {
  const unsigned status = (response.status >= 100 && response.status <= 999) ? response.status : 500;
  message.result(status);
  message.version(m_version);
  message.set(http::field::content_type, response.contentType);
  message.set("X-Content-Type-Options", "nosniff");
  bool cacheControlSet = false;
  for (const auto& [name, value] : response.headers) {
    if (beast::iequals(name, "cache-control")) cacheControlSet = true;
    message.insert(name, value);
  }
  if (!cacheControlSet && isApiPath(m_request.path)) message.set(http::field::cache_control, "no-store");
  if (!response.downloadName.empty()) {
    message.set(http::field::content_disposition,
                "attachment; filename=\"" + dispositionName(response.downloadName) + "\"");
  }
  message.keep_alive(keepAlive);
  message.prepare_payload();
}

void Connection::respond(Response response, bool closeAfter) {
  if (m_closed) return;
  m_awaiting = false;
  m_waiting = false;
  const bool keepAlive = m_clientKeepAlive && !closeAfter && !m_core.stopping;
  try {
    if (response.file) {
      std::shared_ptr<FileRemover> remover;
      if (response.deleteFileAfter) {
        remover = std::make_shared<FileRemover>();
        remover->path = *response.file;
      }
      http::file_body::value_type body;
      beast::error_code ec;
      body.open(response.file->c_str(), beast::file_mode::scan, ec);
      if (ec) {
        respond(Response::error(404, "not found"), closeAfter);
        return;
      }
      auto message = std::make_shared<http::response<http::file_body>>();
      message->body() = std::move(body);
      prepareHeaders(*message, response, keepAlive);
      sendMessage(std::move(message), std::move(remover));
    } else {
      auto message = std::make_shared<http::response<http::string_body>>();
      message->body() = std::move(response.body);
      prepareHeaders(*message, response, keepAlive);
      sendMessage(std::move(message), nullptr);
    }
  } catch (...) {
    close();  // out of memory or a header Beast refused: nothing sensible to send
  }
}

template <class Body>
void Connection::sendMessage(std::shared_ptr<http::response<Body>> message, std::shared_ptr<void> keep) {
  // write_some per chunk, each with its own deadline: a large download that keeps moving is
  // fine, a client that stops reading is closed after writeTimeout
  struct Write {
    std::shared_ptr<http::response<Body>> message;
    http::response_serializer<Body> serializer;
    std::shared_ptr<void> keep;
    explicit Write(std::shared_ptr<http::response<Body>> m, std::shared_ptr<void> k)
        : message(std::move(m)), serializer(*message), keep(std::move(k)) {}
  };
  auto write = std::make_shared<Write>(std::move(message), std::move(keep));
  struct Step {
    static void next(const std::shared_ptr<Connection>& self, const std::shared_ptr<Write>& write) {
      self->m_stream.expires_after(self->m_core.options.writeTimeout);
      http::async_write_some(self->m_stream, write->serializer,
                             [self, write](const beast::error_code& ec, std::size_t) {
                               if (self->m_closed) return;
                               if (ec) {
                                 self->close();
                               } else if (!write->serializer.is_done()) {
                                 next(self, write);
                               } else {
                                 self->afterResponse(write->message->keep_alive());
                               }
                             });
    }
  };
  Step::next(shared_from_this(), write);
}

void Connection::afterResponse(bool keepAlive) {
  if (m_closed) return;
  if (keepAlive && !m_core.stopping) {
    readHeader();
    return;
  }
  beast::error_code ec;
  m_stream.socket().shutdown(asio::ip::tcp::socket::shutdown_send, ec);
  m_stream.expires_after(LINGER_TIME);
  m_waiting = true;  // answered: the first to give way when the table is full
  m_waitingSince = Clock::time_point{};
  lingerThenClose(0);
}

void Connection::lingerThenClose(std::size_t drained) {
  m_stream.async_read_some(asio::buffer(m_discard),
                           [self = shared_from_this(), drained](const beast::error_code& ec, std::size_t n) {
                             if (self->m_closed) return;
                             if (ec || drained + n >= LINGER_BYTES) {
                               self->close();
                             } else {
                               self->lingerThenClose(drained + n);
                             }
                           });
}

}  // namespace openvcu::web::detail
