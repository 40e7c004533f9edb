#pragma once
// The newest log records of all services, filtered and exported as the services write them.
//
//   exportText -> "2026-11-26T06:00:00.123Z warning vcu-fsm: text\n"

#include <cstddef>
#include <deque>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/ipc/events.hpp"

namespace openvcu::display {

/// The newest `capacity` log records of all services; filters by service and minimum level.
/// @note not thread-safe: one thread adds and reads it.
class LogBuffer {
 public:
  /// A capacity of 0 counts as 1.
  explicit LogBuffer(std::size_t capacity);
  /// Appends; returns true when the oldest record was dropped to make room.
  bool add(ipc::LogRecord record);
  [[nodiscard]] std::size_t size() const noexcept { return m_records.size(); }
  [[nodiscard]] const ipc::LogRecord& at(std::size_t index) const { return m_records[index]; }
  /// Indices (oldest first) of the records of `service` (empty: all) at `minimum` or above.
  [[nodiscard]] std::vector<std::size_t> select(std::string_view service, ipc::LogLevel minimum) const;
  /// One line per record: "2026-11-26T06:00:00.123Z warning vcu-fsm: text". Indices past
  /// the end are skipped.
  [[nodiscard]] std::string exportText(const std::vector<std::size_t>& indices) const;
  [[nodiscard]] std::set<std::string> services() const;

 private:
  std::size_t m_capacity;
  std::deque<ipc::LogRecord> m_records;
};

/// "trace", "debug", "info", "warning", "error", "critical".
[[nodiscard]] std::string_view levelName(ipc::LogLevel level) noexcept;

}  // namespace openvcu::display
