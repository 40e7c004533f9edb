#pragma once
// The heartbeat of a service, once a second on both planes:
//   - LCM (OPENVCU_<INSTANCE>_HEARTBEAT): ipc::Heartbeat with the program name, pid,
//     uptime, the named counters the service registered and a one-line status
//     ("starting", "ready", "stopping", or the service's own text). `vcu status` lists them.
//   - the signal table: the slot "internal.service.<name>.heartbeat" counts beats on the
//     BUS plane (writeBus, quality Valid, source = the service's writer id). It is an
//     observation the service publishes about itself, like a received value, not a command:
//     the command plane stays free for operators, and staleness marking works on it like
//     on any received signal. The count continues from the table's value after a restart,
//     so a watcher never sees it go backwards (docs/design/service-runtime.md).
//
//   - LCM (OPENVCU_<INSTANCE>_STATS), right after the heartbeat: ipc::Stats with the
//     per-bus and per-message statistics the service registered with addStatSource
//     ("vehicle.frames_rx", "rx.EEC1.period_us"), in parts of one datagram each. The
//     heartbeat itself always fits one datagram (ipc::LCM_DATAGRAM_BYTES): its status is
//     cut to MAX_STATUS_BYTES and counters that do not fit move to the stats message.
//
//   service::CounterRef framesRx = heartbeat.addCounter("frames_rx");
//   framesRx.increment();                       // per frame: one add, no allocation
//   heartbeat.addCounterSource("event_decode_errors", [&] { return std::int64_t(events.decodeErrors()); });
//   heartbeat.addStatSource("rx.EEC1.frames", [&] { return std::int64_t(counters.frames); });

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>

#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::ipc {
class EventBus;
}

namespace openvcu::service {

/// A counter owned by a HeartbeatPublisher (stable address for the publisher's lifetime).
/// @note noexcept, allocation-free; one thread at a time (the service's loop thread).
class CounterRef {
 public:
  CounterRef() = default;
  void increment(std::int64_t by = 1) noexcept {
    if (m_value != nullptr) *m_value += by;
  }
  void set(std::int64_t value) noexcept {
    if (m_value != nullptr) *m_value = value;
  }
  [[nodiscard]] std::int64_t value() const noexcept { return m_value != nullptr ? *m_value : 0; }

 private:
  friend class HeartbeatPublisher;
  explicit CounterRef(std::int64_t* value) noexcept : m_value(value) {}
  std::int64_t* m_value{nullptr};
};

/// The heartbeat's slot key: "internal.service.<name>.heartbeat".
[[nodiscard]] std::string heartbeatKey(std::string_view serviceName);

/// @note restricted thread-safe: one thread (the service's loop) registers, counts and beats.
class HeartbeatPublisher {
 public:
  /// `events` and `table` may be null (that plane is then skipped); `slot` is the
  /// heartbeat slot in `table`, empty when the catalog has none.
  HeartbeatPublisher(std::string program, std::string instance, ipc::EventBus* events, signals::SignalTable* table,
                     std::optional<signals::SignalIndex> slot, signals::WriterId writer);

  /// A counter starting at 0, reported under `name` in registration order.
  CounterRef addCounter(std::string name);
  /// A counter read at each beat from elsewhere (e.g. a library's own count).
  void addCounterSource(std::string name, std::function<std::int64_t()> read);

  /// A per-bus or per-message statistic read at each beat and sent on the STATS channel.
  void addStatSource(std::string name, std::function<std::int64_t()> read);
  /// Called after each beat (e.g. can-tx publishes its live schedule with it).
  void addBeatListener(std::function<void()> listener);

  /// The longest status a heartbeat carries (bytes; a longer one is cut at a UTF-8
  /// character boundary and ends in "...").
  static constexpr std::size_t MAX_STATUS_BYTES = 200;

  void setStatus(std::string status);
  [[nodiscard]] const std::string& status() const noexcept { return m_status; }

  /// The message the next beat publishes (tests, and `beat` itself): fits one datagram.
  [[nodiscard]] ipc::Heartbeat message() const;
  /// The statistics the next beat publishes: the stat sources, then the counters that did
  /// not fit the heartbeat. Empty counters: nothing is sent.
  [[nodiscard]] ipc::Stats statsMessage() const;
  /// Publishes one heartbeat on the bus and advances the table counter.
  void beat();
  /// Beats published by this process.
  [[nodiscard]] std::uint64_t beats() const noexcept { return m_beats; }

 private:
  struct Source {
    std::string name;
    std::function<std::int64_t()> read;
  };
  /// How many counters (m_counters, then m_sources) fit after a heartbeat of `fixedSize`
  /// encoded bytes without counters.
  [[nodiscard]] std::size_t countersInHeartbeat(std::size_t fixedSize) const noexcept;
  std::string m_program;
  std::string m_instance;
  ipc::EventBus* m_events;
  signals::SignalTable* m_table;
  std::optional<signals::SignalIndex> m_slot;
  signals::WriterId m_writer;
  std::deque<std::pair<std::string, std::int64_t>> m_counters;  // deque: stable addresses
  std::vector<Source> m_sources;
  std::vector<Source> m_statSources;
  std::vector<std::function<void()>> m_beatListeners;
  std::size_t m_payloadLimit;  // the heartbeat channel's one-datagram payload
  std::string m_status{"starting"};
  std::chrono::steady_clock::time_point m_start;
  std::uint64_t m_beats{};
  std::optional<double> m_tableCount;  // next value for the slot, seeded from the table
  std::int32_t m_pid;
};

}  // namespace openvcu::service
