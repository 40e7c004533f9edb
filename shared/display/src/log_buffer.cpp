#include "openvcu/display/log_buffer.hpp"

#include "openvcu/service/logger.hpp"

namespace openvcu::display {

LogBuffer::LogBuffer(std::size_t capacity) : m_capacity(capacity > 0 ? capacity : 1) {}

bool LogBuffer::add(ipc::LogRecord record) {
  m_records.push_back(std::move(record));
  if (m_records.size() <= m_capacity) return false;
  m_records.pop_front();
  return true;
}

std::vector<std::size_t> LogBuffer::select(std::string_view service, ipc::LogLevel minimum) const {
  std::vector<std::size_t> indices;
  for (std::size_t i = 0; i < m_records.size(); ++i) {
    const ipc::LogRecord& record = m_records[i];
    if (record.level < minimum) continue;
    if (!service.empty() && record.service != service) continue;
    indices.push_back(i);
  }
  return indices;
}

std::string LogBuffer::exportText(const std::vector<std::size_t>& indices) const {
  std::string out;
  for (const std::size_t index : indices) {
    if (index >= m_records.size()) continue;
    const ipc::LogRecord& record = m_records[index];
    out += service::formatUtc(record.timestampNs) + " " + std::string(levelName(record.level)) + " " + record.service +
           ": " + record.text + "\n";
  }
  return out;
}

std::set<std::string> LogBuffer::services() const {
  std::set<std::string> names;
  for (const ipc::LogRecord& record : m_records) names.insert(record.service);
  return names;
}

std::string_view levelName(ipc::LogLevel level) noexcept {
  switch (level) {
    case ipc::LogLevel::Trace:
      return "trace";
    case ipc::LogLevel::Debug:
      return "debug";
    case ipc::LogLevel::Info:
      return "info";
    case ipc::LogLevel::Warning:
      return "warning";
    case ipc::LogLevel::Error:
      return "error";
    case ipc::LogLevel::Critical:
      return "critical";
  }
  return "?";
}

}  // namespace openvcu::display
