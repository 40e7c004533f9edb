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
      m_start(std::chrono::steady_clock::now()),
      m_pid(static_cast<std::int32_t>(::getpid())) {}

CounterRef HeartbeatPublisher::addCounter(std::string name) {
  m_counters.emplace_back(std::move(name), 0);
  return CounterRef(&m_counters.back().second);
}

void HeartbeatPublisher::addCounterSource(std::string name, std::function<std::int64_t()> read) {
  m_sources.push_back(Source{std::move(name), std::move(read)});
}

void HeartbeatPublisher::setStatus(std::string status) {
  m_status = std::move(status);
}

ipc::Heartbeat HeartbeatPublisher::message() const {
  ipc::Heartbeat heartbeat;
  heartbeat.service = m_program;
  heartbeat.instance = m_instance;
  heartbeat.pid = m_pid;
  heartbeat.uptimeMs =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - m_start).count();
  heartbeat.counters.reserve(m_counters.size() + m_sources.size());
  for (const auto& [name, value] : m_counters) heartbeat.counters.push_back(ipc::Counter{name, value});
  for (const Source& source : m_sources) heartbeat.counters.push_back(ipc::Counter{source.name, source.read()});
  heartbeat.status = m_status;
  return heartbeat;
}

void HeartbeatPublisher::beat() {
  ++m_beats;
  if (m_events != nullptr) m_events->publish(message());
  if (m_table != nullptr && m_slot) {
    if (!m_tableCount) {
      // Continue the count a previous run of this service left in the table (restart).
      const auto maybeBus = m_table->readBus(*m_slot);
      m_tableCount = (maybeBus && maybeBus->updates > 0) ? maybeBus->value + 1.0 : 1.0;
    }
    m_table->writeBus(*m_slot, *m_tableCount, signals::monotonicNowNs(), m_writer, signals::Quality::Valid);
    *m_tableCount += 1.0;
  }
}

}  // namespace openvcu::service
