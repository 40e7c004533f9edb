#include "openvcu/core/clock.hpp"
#include "openvcu/service/heartbeat.hpp"

#include <unistd.h>

#include "openvcu/ipc/event_bus.hpp"

namespace openvcu::service {

std::string heartbeatKey(std::string_view serviceName) {
  return "internal.service." + std::string(serviceName) + ".heartbeat";
}

HeartbeatPublisher::HeartbeatPublisher(std::string program, std::string instance, ipc::EventBus* events,
                                       signals::SignalTable* table, std::optional<signals::SignalIndex> slot,
                                       signals::WriterId writer)
    : m_program(std::move(program)),
      m_instance(std::move(instance)),
      m_events(events),
      m_table(table),
      m_slot(slot),
      m_writer(writer),
      m_payloadLimit(ipc::datagramPayloadLimit(ipc::channelName(m_instance, ipc::EventKind::Heartbeat))),
      m_start(std::chrono::steady_clock::now()),
      m_pid(static_cast<std::int32_t>(::getpid())) {}

CounterRef HeartbeatPublisher::addCounter(std::string name) {
  m_counters.emplace_back(std::move(name), 0);
  return CounterRef(&m_counters.back().second);
}

void HeartbeatPublisher::addCounterSource(std::string name, std::function<std::int64_t()> read) {
  m_sources.push_back(Source{std::move(name), std::move(read)});
}

void HeartbeatPublisher::addStatSource(std::string name, std::function<std::int64_t()> read) {
  m_statSources.push_back(Source{std::move(name), std::move(read)});
}

void HeartbeatPublisher::addBeatListener(std::function<void()> listener) {
  m_beatListeners.push_back(std::move(listener));
}

namespace {

/// `text` cut to at most `limit` bytes at a UTF-8 character boundary, "..." appended.
std::string cutStatus(const std::string& text, std::size_t limit) {
  if (text.size() <= limit) return text;
  std::size_t end = limit - 3;
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  return text.substr(0, end) + "...";
}

/// LCM's encoding of one counter: the name (int32 length, bytes, NUL) and an int64.
std::size_t counterBytes(const std::string& name) noexcept { return 4 + name.size() + 1 + 8; }

}  // namespace

void HeartbeatPublisher::setStatus(std::string status) {
  m_status = std::move(status);
}

std::size_t HeartbeatPublisher::countersInHeartbeat(std::size_t fixedSize) const noexcept {
  // In registration order while they fit; statsMessage() sends the rest.
  std::size_t size = fixedSize;
  std::size_t count = 0;
  for (const auto& counter : m_counters) {
    if ((size += counterBytes(counter.first)) > m_payloadLimit) return count;
    ++count;
  }
  for (const Source& source : m_sources) {
    if ((size += counterBytes(source.name)) > m_payloadLimit) return count;
    ++count;
  }
  return count;
}

ipc::Heartbeat HeartbeatPublisher::message() const {
  ipc::Heartbeat heartbeat;
  heartbeat.service = m_program;
  heartbeat.instance = m_instance;
  heartbeat.pid = m_pid;
  heartbeat.uptimeMs =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - m_start).count();
  heartbeat.status = cutStatus(m_status, MAX_STATUS_BYTES);
  const std::size_t fitting = countersInHeartbeat(ipc::encodedSize(heartbeat));
  heartbeat.counters.reserve(fitting);
  for (const auto& [name, value] : m_counters) {
    if (heartbeat.counters.size() == fitting) return heartbeat;
    heartbeat.counters.push_back(ipc::Counter{name, value});
  }
  for (const Source& source : m_sources) {
    if (heartbeat.counters.size() == fitting) return heartbeat;
    heartbeat.counters.push_back(ipc::Counter{source.name, source.read()});
  }
  return heartbeat;
}

ipc::Stats HeartbeatPublisher::statsMessage() const {
  ipc::Stats stats;
  stats.service = m_program;
  stats.instance = m_instance;
  stats.pid = m_pid;
  // The heartbeat's fixed part at its largest: the counters that might not fit go here.
  ipc::Heartbeat fixed{.service = m_program, .instance = m_instance, .counters = {}, .status = cutStatus(m_status, MAX_STATUS_BYTES)};
  const std::size_t inHeartbeat = countersInHeartbeat(ipc::encodedSize(fixed));
  stats.counters.reserve(m_statSources.size());
  for (const Source& source : m_statSources) stats.counters.push_back(ipc::Counter{source.name, source.read()});
  std::size_t index = 0;
  for (const auto& [name, value] : m_counters) {
    if (index++ >= inHeartbeat) stats.counters.push_back(ipc::Counter{name, value});
  }
  for (const Source& source : m_sources) {
    if (index++ >= inHeartbeat) stats.counters.push_back(ipc::Counter{source.name, source.read()});
  }
  return stats;
}

void HeartbeatPublisher::beat() {
  ++m_beats;
  if (m_events != nullptr) {
    const ipc::Heartbeat heartbeat = message();
    m_events->publish(heartbeat);
    if (ipc::Stats stats = statsMessage(); !stats.counters.empty()) m_events->publish(stats);
  }
  for (const auto& listener : m_beatListeners) listener();
  if (m_table != nullptr && m_slot) {
    if (!m_tableCount) {
      // Continue the count a previous run of this service left in the table (restart).
      const auto maybeBus = m_table->readBus(*m_slot);
      m_tableCount = (maybeBus && maybeBus->updates > 0) ? maybeBus->value + 1.0 : 1.0;
    }
    m_table->writeBus(*m_slot, *m_tableCount, clock::monotonicNs(), m_writer, signals::Quality::Valid);
    *m_tableCount += 1.0;
  }
}

}  // namespace openvcu::service
