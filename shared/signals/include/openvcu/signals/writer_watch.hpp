#pragma once
// When a watched writer of the signal table counts as lost: one per service whose heartbeat
// slot (internal.service.<name>.heartbeat) a dead-man switch watches (vcu-can-tx for the bus
// commands, docs/design/can-tx.md "writers"; vcu-gpio for its outputs, docs/design/gpio.md),
// driven by explicit time and the slot as read, so that tests set the clock.
//
//   signals::WriterWatch watch(writer.timeoutNs, startNs, table.damageCount());
//   every wake: const auto beat = table.readBus(writer.heartbeat);
//               switch (watch.update(beat, table.damageCount(), now)) { Lost: safe values; Back: ... }
//
// The writer is lost when neither a heartbeat nor anything that resets the wait happened for
// longer than the timeout. The wait starts at the watcher's start, at each heartbeat, and at
// each change of the table's damage count while the writer is not lost: the table lost its
// values then, so the heartbeat reads as never written until its writer's next beat (up to
// 1 s) and gets its full timeout to arrive again. A heartbeat that reads as never written
// after one was seen keeps the last one's time (update counters fall back only when the
// table lost its values).

#include <cstdint>
#include <optional>

#include "openvcu/signals/table.hpp"

namespace openvcu::signals {

enum class WriterChange : std::uint8_t {
  None,  ///< as before
  Lost,  ///< no heartbeat for longer than the timeout: command the safe values
  Back,  ///< a heartbeat arrived again after a loss
};

/// @note restricted thread-safe: one thread; noexcept, allocation-free.
class WriterWatch {
 public:
  WriterWatch(std::int64_t timeoutNs, std::int64_t startNs, std::uint64_t damageCount = 0) noexcept
      : m_timeoutNs(timeoutNs), m_sinceNs(startNs), m_damage(damageCount) {}

  /// `beat`: the heartbeat slot's bus plane as read now (empty when the read failed: the
  /// last heartbeat counts); `damageCount`: the table's, read after the slot.
  WriterChange update(const std::optional<BusValue>& beat, std::uint64_t damageCount, std::int64_t nowNs) noexcept;

  [[nodiscard]] bool lost() const noexcept { return m_lost; }
  /// CLOCK_MONOTONIC of the newest event the timeout counts from.
  [[nodiscard]] std::int64_t sinceNs() const noexcept { return m_sinceNs; }
  /// The first time at which update() returns Lost unless something resets the wait
  /// (sinceNs() + timeout + 1 ns): a watcher that sleeps until then needs no periodic tick.
  [[nodiscard]] std::int64_t lostAtNs() const noexcept { return m_sinceNs + m_timeoutNs + 1; }
  [[nodiscard]] std::int64_t timeoutNs() const noexcept { return m_timeoutNs; }

 private:
  std::int64_t m_timeoutNs;
  std::int64_t m_sinceNs;
  std::uint64_t m_damage;
  bool m_lost{};
};

}  // namespace openvcu::signals
