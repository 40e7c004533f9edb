// Connection's event-stream part (http_connection.hpp): text/event-stream answers whose events
// are pulled from an EventSource on a per-stream timer, only when the previous one is written.
#include <algorithm>
#include <boost/asio/write.hpp>
#include <chrono>
#include <exception>

#include "http_connection.hpp"

namespace openvcu::web::detail {

void Connection::startStream(const StreamOpener& opener) {
  std::unique_ptr<EventSource> source;
  try {
    auto opened = opener(m_request);
    if (!opened) {
      respond(Response::error(400, opened.error().toString()));
      return;
    }
    source = std::move(*opened);
  } catch (const std::exception& error) {
    respond(Response::error(500, error.what()));
    return;
  }
  if (!source) {
    respond(Response::error(500, "no event source"));
    return;
  }
  if (m_core.streamCount.load() >= m_core.options.maxStreams) {
    if (auto refused = m_core.makeRoomForStream(m_address)) {
      respond(Response::error(503, *refused));
      return;
    }
  }
  m_source = std::move(source);
  m_streamingSince = Clock::now();
  m_core.streamCount.fetch_add(1);
  m_core.connectionBecameStream(m_address);
  const double rate = std::clamp(m_core.options.maxUpdatesPerSecond, 0.01, 1000.0);
  m_tickPeriod = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
  m_stream.expires_never();  // the stream keeps its own write deadline (onTick)
  m_eventText =
      "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n"
      "X-Content-Type-Options: nosniff\r\nX-Accel-Buffering: no\r\nConnection: close\r\n\r\n";
  if (m_version == 10) m_eventText.replace(0, 8, "HTTP/1.0");
  writeEvent();
  readDiscard();
  scheduleTick();
}

void Connection::writeEvent() {
  m_writing = true;
  m_writeStarted = Clock::now();
  asio::async_write(m_stream.socket(), asio::buffer(m_eventText),
                    [self = shared_from_this()](const beast::error_code& ec, std::size_t) {
                      if (self->m_closed) return;
                      self->m_writing = false;
                      if (ec) {
                        self->close();
                        return;
                      }
                      self->m_lastWrite = Clock::now();
                    });
}

void Connection::readDiscard() {
  // a stream's client sends nothing more; reading finds out at once when it leaves
  m_stream.socket().async_read_some(asio::buffer(m_discard),
                                    [self = shared_from_this()](const beast::error_code& ec, std::size_t) {
                                      if (self->m_closed) return;
                                      if (ec) {
                                        self->close();
                                        return;
                                      }
                                      self->readDiscard();
                                    });
}

void Connection::scheduleTick() {
  m_tick.expires_after(m_tickPeriod);
  m_tick.async_wait([self = shared_from_this()](const beast::error_code& ec) {
    if (ec || self->m_closed) return;
    self->onTick();
  });
}

void Connection::onTick() {
  const auto now = Clock::now();
  if (m_writing) {
    if (now - m_writeStarted > m_core.options.writeTimeout) {
      close();  // the client stopped reading
      return;
    }
    m_core.eventsSkipped.fetch_add(1, std::memory_order_relaxed);
    scheduleTick();
    return;
  }
  std::string event;
  try {
    event = m_source->next();
  } catch (...) {
    close();
    return;
  }
  if (!event.empty()) {
    m_eventText = std::move(event);
    m_core.eventsSent.fetch_add(1, std::memory_order_relaxed);
    writeEvent();
  } else if (now - m_lastWrite >= KEEP_ALIVE_INTERVAL) {
    m_eventText = ": keep-alive\n\n";
    writeEvent();
  }
  scheduleTick();
}

}  // namespace openvcu::web::detail
