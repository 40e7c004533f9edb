#pragma once
// The transmit schedule: the file named by "schedule" in the vehicle configuration
// (config/hhea/schedule.json), resolved against the DBC, plus the overlay of runtime changes.
// vcu-can-tx sends by it and `vcu check` checks it with this loader. Format and rules:
// docs/design/can-tx.md.
//
//   auto scheduleResult = schedule::loadSchedule(vehicle, catalog);
//   if (!scheduleResult) return scheduleResult.error();   // "schedule.json: /messages/X/cycleMs: ..."

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::schedule {

enum class FieldAlgorithm : std::uint8_t { Counter, Sum8, Xor8, Crc8SaeJ1850, J1939Checksum4 };

/// "counter", "sum8", ...
[[nodiscard]] std::string_view fieldAlgorithmName(FieldAlgorithm algorithm) noexcept;

struct ComputedField {
  std::uint32_t signal{};  ///< index into the DBC message's signals
  FieldAlgorithm algorithm{FieldAlgorithm::Counter};
  std::uint64_t modulo{};  ///< counter: wraps here (0: 2^bits)
  std::uint64_t start{};   ///< counter: the first value
};

struct ScheduledMessage {
  std::size_t message{};           ///< index into the database's messages
  std::size_t bus{};               ///< index into VehicleConfig::buses
  std::uint32_t canId{};           ///< after destination/source substitution
  bool extended{};
  std::int64_t cycleNs{};          ///< 0: not cyclic
  std::int64_t offsetNs{};
  bool enabled{true};
  std::optional<std::size_t> group;  ///< index into Schedule::groups
  /// Per DBC signal (same order as the message's signals): the value sent while nothing
  /// commands it, or empty to keep the initial payload's bits.
  std::vector<std::optional<double>> defaults;
  /// Per DBC signal: its catalog index (empty for signals the catalog does not hold).
  std::vector<std::optional<signals::SignalIndex>> keys;
  std::vector<ComputedField> computed;
  bool onChange{};
  std::int64_t minIntervalNs{10'000'000};
  std::optional<std::int64_t> safetyDeltaNs;  ///< J1939-76 SDM: SHM first, SDM this much later
  bool added{};  ///< added at run time (ScheduleAdd, the overlay's "added"), not by the schedule file
};

struct SendGroup {
  std::string name;
  signals::SignalIndex signal{};
  double initial{};  ///< the signal's initial value (catalog)
};

struct WatchedWriter {
  std::string service;  ///< "fsm"
  signals::SignalIndex heartbeat{};
  std::int64_t timeoutNs{};
};

struct SafeValue {
  signals::SignalIndex signal{};
  double value{};
};

/// Default of "sdmSpinUs": about this VM's SCHED_FIFO wake-up latency p99.9 (190-503 us by
/// cyclictest, docs/benchmarks.md "can-tx"); covers HHEA's shortest delta, S1_ES's 292 us.
inline constexpr std::int64_t DEFAULT_SDM_SPIN_US = 500;
/// The largest "sdmSpinUs" accepted (10 ms): a spin is CPU time.
inline constexpr std::int64_t MAX_SDM_SPIN_US = 10'000;

struct Schedule {
  std::string file;     ///< the schedule file ("" = defaults only)
  std::string overlay;  ///< the overlay file path
  std::vector<ScheduledMessage> messages;
  std::vector<SendGroup> groups;
  std::vector<WatchedWriter> writers;
  std::vector<SafeValue> safeValues;
  std::int8_t localHourOffset{};
  std::int8_t localMinuteOffset{};
  int realtimePriority{};
  /// "sdmSpinUs": an SDM due within this of now is waited for on the CPU, not by a second
  /// sleep (vcu-can-tx's transmit thread, issue 27); 0: always sleep.
  std::int64_t sdmSpinNs{DEFAULT_SDM_SPIN_US * 1000};

  /// The scheduled entry of a DBC message, or nullptr.
  [[nodiscard]] const ScheduledMessage* find(std::size_t messageIndex) const noexcept;
  [[nodiscard]] ScheduledMessage* find(std::size_t messageIndex) noexcept;
};

/// The runtime changes kept across restarts (docs/design/can-tx.md, "The overlay").
struct MessageChange {
  std::string message;
  std::optional<double> cycleMs;
  std::optional<bool> enabled;
  bool added{};  ///< the message was added at run time (then cycleMs is set)
};
struct Overlay {
  std::vector<MessageChange> messages;
  std::vector<std::pair<std::string, double>> defaults;   ///< signal key -> value
  std::vector<std::pair<std::string, double>> overrides;  ///< signal key -> value
  [[nodiscard]] bool empty() const noexcept { return messages.empty() && defaults.empty() && overrides.empty(); }
};

/// The schedule of `vehicle` (its "schedule" file, or the defaults). Errors name the file
/// and the JSON path; nothing is partially applied. A schedule whose cyclic frames exceed
/// config::MAX_CYCLIC_BUS_LOAD on a bus is refused (checkBusLoad).
Result<Schedule> loadSchedule(const config::VehicleConfig& vehicle, const signals::Catalog& catalog);

/// Empty when on every bus the schedule's cyclic messages (enabled or not, group-switched
/// or not: all may be on at once; a J1939-76 SDM with its SHM) take at most
/// config::MAX_CYCLIC_BUS_LOAD of the bus' time (config::cyclicBusLoad), else the reason,
/// naming the bus, the load and the three heaviest messages. Frames sent on change or on
/// request are not counted (their rate depends on the signals and the requesters).
std::optional<std::string> checkBusLoad(const Schedule& schedule, const config::VehicleConfig& vehicle);

/// Pairs of scheduled messages a J1939-76 receiver cannot tell apart: on the same bus, with
/// equal PGN, SA and DA (j1939::sameSafetyIdentity; priority not compared), at least one an
/// SDM. One warning per pair, naming both, e.g. "S1_ES_PGN61427 (0x0CEFF321, J1939-76 SDM)
/// and PropA_C4_PGN61184 (0x18EFF321) have the same PGN 0xEF00, source 0x21 and destination
/// 0xF3 on bus vehicle: ...". can-tx logs them at start; the Scheduler keeps such a message
/// out of the SHM-SDM gap. `only`: just the pairs that include this schedule index.
std::vector<std::string> safetyIdentityWarnings(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                                std::optional<std::size_t> only = std::nullopt);

/// Parses the overlay file; empty when it does not exist. Errors name the file and path.
Result<Overlay> loadOverlay(const std::string& path);
/// Checks every entry of `overlay` against `schedule` and applies it to a copy, which is
/// returned (all or nothing). Overrides are only checked here (the caller sets them).
Result<Schedule> applyOverlay(const Schedule& schedule, const Overlay& overlay, const config::VehicleConfig& vehicle,
                              const signals::Catalog& catalog);
/// Writes `overlay` atomically (temporary file, fsync, rename, fsync of the folder).
Status saveOverlay(const std::string& path, const Overlay& overlay);

/// A physical value `signal` can carry (finite, inside its DBC range): empty when fine,
/// else the reason.
std::optional<std::string> checkSignalValue(const dbc::Signal& signal, double value);

/// Check of one runtime change, shared by commands and overlay loading: empty when fine,
/// else the reason. `cycleMs` must pass config::checkCycleMs (a whole number of ms,
/// 1..3600000) and be longer than the safety delta.
std::optional<std::string> checkCycle(const ScheduledMessage& message, double cycleMs);

/// The entry for DBC message `name` added at run time with cycle `cycleMs` (ScheduleAdd): its
/// DBC start values, no group, no computed fields, no safety pair. A reason when the message
/// is unknown, pseudo, on no configured bus, a J1939-76 safety header, longer than a frame,
/// already scheduled, the cycle is out of range, or the schedule with it would fail
/// checkBusLoad. (A runtime cycle change is checked against the bus load by vcu-can-tx too.)
Result<ScheduledMessage> runtimeMessage(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                        const signals::Catalog& catalog, std::string_view name, double cycleMs);

/// The scheduled message named `name`, or a reason ("unknown message 'X' (did you mean
/// 'Y'?)", "'X' is not in the schedule").
Result<std::size_t> findScheduled(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                  std::string_view name);
/// The scheduled message and signal position of signal key `key`, or a reason.
struct SignalRef {
  std::size_t scheduled{};  ///< index into Schedule::messages
  std::uint32_t signal{};   ///< index into the message's signals
};
Result<SignalRef> findScheduledSignal(const Schedule& schedule, const config::VehicleConfig& vehicle,
                                      const signals::Catalog& catalog, std::string_view key);

}  // namespace openvcu::schedule
