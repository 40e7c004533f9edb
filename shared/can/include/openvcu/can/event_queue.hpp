#pragma once
// A small fixed ring of bus events for the link backends: push never allocates; when full
// the oldest event is dropped (and counted), so a storm of error frames cannot grow memory.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "openvcu/can/link.hpp"

namespace openvcu::can::detail {

class EventQueue {
 public:
  static constexpr std::size_t CAPACITY = 64;

  void push(const BusEvent& event) noexcept {
    if (m_size == CAPACITY) {
      m_head = (m_head + 1) % CAPACITY;
      --m_size;
      ++m_dropped;
    }
    m_events[(m_head + m_size) % CAPACITY] = event;
    ++m_size;
  }
  std::optional<BusEvent> pop() noexcept {
    if (m_size == 0) return std::nullopt;
    const BusEvent event = m_events[m_head];
    m_head = (m_head + 1) % CAPACITY;
    --m_size;
    return event;
  }
  [[nodiscard]] std::size_t size() const noexcept { return m_size; }
  [[nodiscard]] std::uint64_t dropped() const noexcept { return m_dropped; }

 private:
  std::array<BusEvent, CAPACITY> m_events{};
  std::size_t m_head{};
  std::size_t m_size{};
  std::uint64_t m_dropped{};
};

}  // namespace openvcu::can::detail
