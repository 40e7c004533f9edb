#pragma once
// vcu-telemetry's engine (docs/design/telemetry.md, "Payloads"): what goes out, decided
// without threads, sockets or clocks of its own (the caller passes the time), so tests drive
// it on a set clock. Fed by the events (FSM transitions, faults, heartbeats, other nodes' DM1)
// and the signal table (the configured signals); each tick() returns the queue records of that
// tick, each "<topic suffix>\n<JSON>", numbered from the sequence the queue gives next.
//
//   auto engine = Engine::create(settings, runtime.catalog(), runtime.table());
//   engine->onTransition(event);                // state message at the next tick
//   engine->sample(clock::monotonicNs());       // often (vcu-telemetry: every 10 ms)
//   auto records = engine->tick(queue.stats().nextSequence, inputs);   // once a second
//   -> {"state\n{\"v\":1,\"seq\":41,\"t\":...,\"state\":\"Ready\",...}", "signals\n{...\"seq\":42...}"}

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "disk_queue.hpp"
#include "openvcu/config/telemetry.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/display/health.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::telemetry {

/// A signal that does not move is sent again after this long, so a consumer sees it alive.
inline constexpr std::int64_t SIGNAL_KEEPALIVE_NS = 60'000'000'000;
/// The health message goes out at least this often (and on any change of a service's status,
/// of the link's counters, or a drop at the queue's limit).
inline constexpr std::int64_t HEALTH_PERIOD_NS = 10'000'000'000;
/// A signals message is cut at this many bytes (a queue record must fit one segment).
inline constexpr std::size_t MAX_SIGNALS_MESSAGE_BYTES = 32 * 1024;

/// CLOCK_MONOTONIC and CLOCK_REALTIME read together: table stamps become Unix ms through them.
struct ClockPair {
  std::int64_t monoNs{};
  std::int64_t unixMs{};
};

/// The link's counters for the health message (from the sender).
struct LinkCounters {
  std::uint64_t connects{};
  std::uint64_t refused{};
};

struct TickInputs {
  ClockPair clocks;
  QueueStats queue;
  std::vector<QueueDrop> drops;
  LinkCounters link;
};

/// @note restricted thread-safe: one thread (vcu-telemetry's loop thread); the table is read lock-free.
class Engine {
 public:
  /// Error: a configured signal is not in the catalog.
  static Result<Engine> create(const config::TelemetryConfig& settings, const signals::Catalog& catalog,
                               const signals::SignalTable& table);

  void onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs);
  void onFault(const ipc::FaultEvent& fault);
  void onTransition(const ipc::FsmTransition& transition);
  /// Keeps the node's last DM1 (can-rx's DM1 event): its DTCs go into the faults message.
  void onDm1(const ipc::NodeDm1& dm1);

  /// Reads the configured signals; keeps a sample of each that its rate allows and that moved
  /// past its deadband (or changed status, or was not sent for SIGNAL_KEEPALIVE_NS).
  void sample(std::int64_t nowMonoNs);

  /// The records of this tick in order (state transitions, faults when the active set changed,
  /// health when due or changed, the signal samples), numbered from `firstSequence`.
  std::vector<std::string> tick(std::uint64_t firstSequence, const TickInputs& inputs);

  /// Samples kept since the start (for the heartbeat).
  [[nodiscard]] std::uint64_t samplesKept() const noexcept { return m_samplesKept; }

 private:
  struct Watched {
    std::string name;
    signals::SignalIndex index{};
    std::int64_t minPeriodNs{};
    double deadband{};
    bool sent{false};
    double lastValue{};
    int lastStatus{-1};
    std::int64_t lastSentNs{};
  };
  struct Sample {
    std::size_t signal{};
    std::int64_t timestampMonoNs{};
    double value{};
  };
  struct FaultKey {
    std::string name;
    std::string source;
    auto operator<=>(const FaultKey&) const = default;
  };
  Engine(const signals::Catalog& catalog, const signals::SignalTable& table);
  std::string faultsBody(std::int64_t nowMonoNs) const;
  std::string healthSignature(std::int64_t nowMonoNs) const;

  const signals::Catalog* m_catalog;
  const signals::SignalTable* m_table;
  std::vector<Watched> m_watched;
  std::vector<Sample> m_samples;
  std::vector<ipc::FsmTransition> m_transitions;
  std::map<FaultKey, ipc::FaultEvent> m_faults;
  std::map<std::string, ipc::NodeDm1> m_dm1;  ///< by node: its last DM1
  display::HealthTracker m_health;
  std::string m_sentFaults;  ///< the faults body last sent
  std::string m_sentHealth;  ///< the health signature last sent
  LinkCounters m_sentLink;   ///< the link counters last sent
  std::int64_t m_healthSentNs{-1};
  std::uint64_t m_samplesKept{};
};

}  // namespace openvcu::telemetry
