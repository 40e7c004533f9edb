#pragma once
// The HMI's display logic without Qt: which value of a slot a person sees and how it
// becomes text and a status (shownValue, classify, staleAfterFor, formatValue), which
// operator switches the state machine allows (FsmRules), the service health seen through
// heartbeats (HealthTracker), the commands waiting for their acknowledgement
// (CommandTracker) and the log ring (LogBuffer). The Qt models in the screen folders
// (header/, vehicle/, dashboard/, can/, setup/, debug/) wrap these; the unit tests
// (tests/services/hmi/test_display_logic.cpp) drive them directly.
//
//   classify(bus, nowNs, 2 s) -> ValueStatus::Stale for a bus value 3 s old
//   formatValue(info, 87.456, "%.1f") -> "87.5 %" ; formatValue(relay, 1, "") -> "On"

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/service/logger.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::hmi {

/// Short name for the signals namespace in the Qt headers (moc reads `signals` as a keyword).
namespace sig = openvcu::signals;

/// What a model or a value shows about its freshness (bound by QML as colour/marking).
enum class ValueStatus : std::uint8_t {
  Ready,         ///< a valid value within its timeout
  Stale,         ///< a value older than its timeout, or marked Stale/OutOfRange by can-rx
  NotConnected,  ///< never received, or no signal table / no event bus
  Error,         ///< the configuration or the connection failed
};

/// "Ready", "Stale", "NotConnected", "Error".
[[nodiscard]] std::string_view statusName(ValueStatus status) noexcept;

/// How the HMI judges one slot at `nowNs` (CLOCK_MONOTONIC), along the same order as
/// shownValue: a slot with a bus value by that value's quality and age; without one, a
/// command or an active override counts as Ready; nothing written: NotConnected.
/// @note noexcept, allocation-free (display-rate path).
[[nodiscard]] ValueStatus classify(const signals::SlotSnapshot& slot, std::int64_t nowNs,
                                   std::int64_t staleAfterNs) noexcept;

/// The age after which a value counts as Stale: `busTimeoutNs` for DBC signals; 0 (no age
/// limit, quality only) for internal signals, which are written on change (a relay, a fault
/// line, the FSM state) and may rightly stay unchanged for hours.
[[nodiscard]] std::int64_t staleAfterFor(const signals::SignalInfo& signal, std::int64_t busTimeoutNs) noexcept;

/// The one place that decides which value of a slot the HMI shows (the dashboard, the
/// status table, the DBC tree, the header, the live plot, the operator switches), by the
/// signal's direction in the catalog: the bus value once one was received (what another
/// node sent, what can-tx sent, a status); for a transmitted or internal signal without
/// one, the effective command (override, then command plane: signals::effectiveCommand);
/// a received signal shows only what came from the bus. Empty when nothing applies.
[[nodiscard]] std::optional<double> shownValue(const signals::SignalInfo& signal,
                                               const signals::SlotSnapshot& slot) noexcept;

/// The value-table text of a value (shared/signals).
using signals::valueText;

/// "87.5 %" with a printf format for the number ("%.1f"; empty: shortest), the value text
/// alone when the signal has one for `value` ("Closed"). A bad format falls back to "%g".
[[nodiscard]] std::string formatValue(const signals::SignalInfo& signal, double value, std::string_view format);

/// A short row label for a key: transmitter and signal ("HVLP_SA71 InverterStatus"), or
/// the last two components of an internal key ("relay Cl15").
[[nodiscard]] std::string shortLabel(std::string_view key);

/// Green/red/neutral class of a value text: "Normal", "OK", "Closed" -> Good; texts with
/// "Fault", "Error", "Fail", "Alarm" -> Bad; else Neutral.
enum class TextTone : std::uint8_t { Neutral, Good, Bad };
[[nodiscard]] TextTone toneOf(std::string_view text) noexcept;

// ---- state machine rules -------------------------------------------------------------

/// The FSM file seen from the HMI: state names by index (internal.fsm.state holds the
/// index) and, per state, the signal keys its transition conditions read. An operator
/// switch is offered when the current state reads it (a transition may follow).
class FsmRules {
 public:
  /// Reads the vcu-fsm file. Errors name the file and what is wrong.
  static Result<FsmRules> load(const std::string& path);
  static Result<FsmRules> parse(std::string_view text, const std::string& source);

  [[nodiscard]] std::size_t stateCount() const noexcept { return m_states.size(); }
  /// "Standby", or "state N" for an index the file does not have.
  [[nodiscard]] std::string stateName(double index) const;
  /// True when the transitions of state `index` read `key`.
  [[nodiscard]] bool stateReads(double index, std::string_view key) const;

 private:
  struct State {
    std::string name;
    std::set<std::string, std::less<>> reads;
  };
  std::vector<State> m_states;
};

// ---- service health ------------------------------------------------------------------

struct ServiceHealth {
  std::string name;  ///< "vcu-fsm"
  std::int32_t pid{};
  std::int64_t uptimeMs{};
  int restarts{};                   ///< pid changes seen by this HMI
  std::int64_t lastBeatMonoNs{-1};  ///< when the last heartbeat arrived (receiver clock); -1: never
  std::string status;
  std::int64_t heartbeats{};
};

/// Heartbeats -> one row per service. The expected services (from the configuration) are
/// listed from the start as NotConnected. Beats older than `staleAfterNs` make a service
/// Stale; three times that, NotConnected.
class HealthTracker {
 public:
  HealthTracker(std::vector<std::string> expected, std::int64_t staleAfterNs);
  /// Returns true when a new service appeared (the row list grew).
  bool onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs);
  [[nodiscard]] ValueStatus statusOf(const ServiceHealth& service, std::int64_t nowNs) const noexcept;
  [[nodiscard]] const std::vector<ServiceHealth>& services() const noexcept { return m_services; }
  [[nodiscard]] const ServiceHealth* find(std::string_view name) const noexcept;

 private:
  std::vector<ServiceHealth> m_services;
  std::int64_t m_staleAfterNs;
};

// ---- commands and their acknowledgements ----------------------------------------------

/// What became of one command.
struct CommandOutcome {
  enum class State : std::uint8_t { Pending, Accepted, Refused, TimedOut };
  State state{State::Pending};
  std::string text;  ///< "accepted by vcu-fsm", "refused by vcu-fsm: <reason>", "no answer within 2 s"
};

/// Request ids of this HMI and the answers to them. Ids are unique per issuer: a counter
/// seeded from the clock, so a restarted HMI does not reuse the previous ids.
class CommandTracker {
 public:
  CommandTracker(std::string issuer, std::int64_t firstId, std::int64_t timeoutNs);
  /// Fills requestId and issuer and remembers the request as pending from `nowNs`.
  void prepare(ipc::CommandRequest& request, std::int64_t nowNs);
  /// The outcome for an ack to one of ours; empty for anyone else's.
  std::optional<std::pair<std::int64_t, CommandOutcome>> onAck(const ipc::CommandAck& ack);
  /// Pending requests whose time ran out, now TimedOut (removed from pending).
  std::vector<std::pair<std::int64_t, CommandOutcome>> expire(std::int64_t nowNs);
  /// Drops a pending request that failed before any answer (not sent, no owner, expired);
  /// true when it was pending.
  bool forget(std::int64_t requestId) { return m_pending.erase(requestId) > 0; }
  /// The monotonic time at which the pending request `requestId` times out (0: not pending).
  [[nodiscard]] std::int64_t deadlineOf(std::int64_t requestId) const noexcept {
    const auto found = m_pending.find(requestId);
    return found == m_pending.end() ? 0 : found->second;
  }
  [[nodiscard]] std::size_t pending() const noexcept { return m_pending.size(); }
  [[nodiscard]] const std::string& issuer() const noexcept { return m_issuer; }

 private:
  std::string m_issuer;
  std::int64_t m_nextId;
  std::int64_t m_timeoutNs;
  std::map<std::int64_t, std::int64_t> m_pending;  ///< id -> deadline
};

// ---- log ring --------------------------------------------------------------------------

/// The newest `capacity` log records of all services; filters by service and minimum level.
class LogBuffer {
 public:
  explicit LogBuffer(std::size_t capacity);
  /// Appends; returns true when the oldest record was dropped to make room.
  bool add(ipc::LogRecord record);
  [[nodiscard]] std::size_t size() const noexcept { return m_records.size(); }
  [[nodiscard]] const ipc::LogRecord& at(std::size_t index) const { return m_records[index]; }
  /// Indices (oldest first) of the records of `service` (empty: all) at `minimum` or above.
  [[nodiscard]] std::vector<std::size_t> select(std::string_view service, ipc::LogLevel minimum) const;
  /// One line per record: "2026-11-26T06:00:00.123Z warning vcu-fsm: text".
  [[nodiscard]] std::string exportText(const std::vector<std::size_t>& indices) const;
  [[nodiscard]] std::set<std::string> services() const;

 private:
  std::size_t m_capacity;
  std::deque<ipc::LogRecord> m_records;
};

/// "trace", "debug", "info", "warning", "error", "critical".
[[nodiscard]] std::string_view levelName(ipc::LogLevel level) noexcept;
/// "2026-11-26T06:00:00.123Z" for CLOCK_REALTIME ns: the services' log format.
using service::formatUtc;

}  // namespace openvcu::hmi
