// Connection's upload part (http_connection.hpp): an UploadRoute's body streamed into a new
// file in ServerOptions::uploadFolder, authorized on the header before any byte is read.
#include <sys/stat.h>
#include <unistd.h>

#include <boost/beast/core/file.hpp>
#include <boost/beast/http/read.hpp>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <system_error>

#include "http_connection.hpp"

namespace openvcu::web::detail {

void Connection::startUpload(const UploadRoute& route) {
  if (route.authorize) {
    std::optional<Response> refusal;
    try {
      refusal = route.authorize(m_request);
    } catch (const std::exception& error) {
      refusal = Response::error(500, error.what());
    } catch (...) {
      refusal = Response::error(500, "internal error");
    }
    if (refusal) {
      respond(std::move(*refusal), requestHasBody());
      return;
    }
  }
  const auto length = m_headerParser->content_length();
  if (length && *length > m_core.options.maxUploadBytes) {
    respond(Response::error(413, "upload too large"), true);
    return;
  }
  std::string pattern = (m_core.options.uploadFolder / "upload-XXXXXX").string();
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0) {
    const int error = errno;
    respond(Response::error(500, "cannot create the upload file in " + m_core.options.uploadFolder.string() + ": " +
                                     std::strerror(error)),
            true);
    return;
  }
  m_uploadFile = pattern;
  (void)::fchmod(fd, 0640);
  m_uploadParser.emplace(std::move(*m_headerParser));
  m_headerParser.reset();
  m_uploadParser->body_limit(m_core.options.maxUploadBytes);
  beast::file file;
  beast::error_code ec;
  file.native_handle(fd);  // the file now owns fd
  m_uploadParser->get().body().reset(std::move(file), ec);
  if (ec) {
    respond(Response::error(500, "cannot write the upload file: " + ec.message()), true);
    return;
  }
  m_upload = &route;
  if (m_uploadParser->is_done()) {
    finishUpload();
    return;
  }
  continueThen(&Connection::readUpload);
}

void Connection::readUpload() {
  if (m_closed) return;
  m_stream.expires_after(m_core.options.readTimeout);
  http::async_read_some(m_stream, m_buffer, *m_uploadParser,
                        [self = shared_from_this()](const beast::error_code& ec, std::size_t) {
                          if (self->m_closed) return;
                          if (ec == http::error::body_limit) {
                            self->m_uploadParser.reset();
                            std::error_code removeError;
                            std::filesystem::remove(self->m_uploadFile, removeError);
                            self->m_uploadFile.clear();
                            self->respond(Response::error(413, "upload too large"), true);
                          } else if (ec) {
                            self->close();  // removes the partial file
                          } else if (self->m_uploadParser->is_done()) {
                            self->finishUpload();
                          } else {
                            self->readUpload();
                          }
                        });
}

void Connection::finishUpload() {
  m_uploadParser->get().body().close();
  m_uploadParser.reset();
  std::filesystem::path file = std::move(m_uploadFile);
  m_uploadFile.clear();  // the handler owns it from here
  const UploadRoute* route = m_upload;
  m_upload = nullptr;
  Responder responder = makeResponder();
  try {
    route->onComplete(m_request, file, responder);
  } catch (const std::exception& error) {
    responder(Response::error(500, error.what()));
  } catch (...) {
    responder(Response::error(500, "internal error"));
  }
}

}  // namespace openvcu::web::detail
