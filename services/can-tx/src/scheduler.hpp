#pragma once
// The transmit engine of vcu-can-tx, free of threads and clocks so that tests drive it
// with a fake clock: run(now) sends what is due, nextDeadlineNs() says when to call again.
//
//   cantx::Scheduler scheduler = *cantx::Scheduler::create(vehicle, schedule, catalog, table, port, clock);
//   for (;;) { scheduler.run(clock.monotonicNs()); sleepUntil(scheduler.nextDeadlineNs()); }
//
// Rules (docs/design/can-tx.md):
//   - each cyclic message is due at start + offset + k x cycle (absolute deadlines, no
//     drift); after a stall the cycles that passed are skipped and counted as missed,
//     never sent in a burst;
//   - messages due at the same time go out shortest cycle first, then in the schedule's
//     order, so a message has the same frames before it in every burst it is in;
//   - a J1939-76 SDM: its SHM goes out when the message is due, the SDM (the same bytes the
//     SHM's CRC covers) deltaNs after the SHM; the sequence number starts at 0 when the
//     process starts, advances by one per pair and wraps at 32 (receivers resynchronise);
//   - between an SHM and its SDM nothing else with the SDM's PGN, SA and DA goes out on that
//     bus (a J1939-76 receiver would take it for the SDM; priority is not compared): such a
//     frame (cyclic, on change, a one-shot, a request's answer) is held and sent right after
//     the SDM; a second SHM of that identity first sends the pending SDM;
//   - the value of each signal: override, else command (signal table), else the schedule's
//     default, else the DBC initial payload's bits; computed fields after that;
//   - a message whose send group's signal is 0, or that is disabled, keeps its phase but
//     sends nothing (not counted as missed);
//   - every sent frame's values go to the table's bus plane (source = its J1939 SA);
//   - after the table lost its values (a truncated segment, issue 18) a signal or send group
//     whose command was seen and now reads as never written keeps that command for
//     TABLE_DAMAGE_GRACE_NS, so frames do not fall back to their defaults before the FSM
//     has written its commands again.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/can/link.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/j1939/request.hpp"
#include "openvcu/schedule/schedule_config.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"
#include "error_histogram.hpp"

namespace openvcu::cantx {

// can-tx sends by the schedule model of shared/schedule (the loader `vcu check` runs too)
// and names its parts without the namespace.
using schedule::applyOverlay;
using schedule::checkBusLoad;
using schedule::checkCycle;
using schedule::checkSignalValue;
using schedule::ComputedField;
using schedule::FieldAlgorithm;
using schedule::fieldAlgorithmName;
using schedule::findScheduled;
using schedule::findScheduledSignal;
using schedule::loadOverlay;
using schedule::loadSchedule;
using schedule::MessageChange;
using schedule::Overlay;
using schedule::runtimeMessage;
using schedule::safetyIdentityWarnings;
using schedule::saveOverlay;
using schedule::SafeValue;
using schedule::Schedule;
using schedule::ScheduledMessage;
using schedule::SendGroup;
using schedule::SignalRef;
using schedule::WatchedWriter;

inline constexpr signals::WriterId CAN_TX_WRITER = config::writerOf(config::ServiceId::CanTx);
/// After the table lost its values (issue 18), how long a signal or send group whose command
/// reads as never written keeps the command it last had: until the FSM (which notices within
/// its 250 ms sleep) has written its commands again, with margin; then the defaults apply.
inline constexpr std::int64_t TABLE_DAMAGE_GRACE_NS = 1'500'000'000;

/// Where frames go (the links and the "tx" stream in the service; a recorder in tests).
class TxPort {
 public:
  virtual ~TxPort() = default;
  /// Sends one frame on bus `bus` now. Called on the scheduler's thread.
  virtual can::SendStatus send(std::size_t bus, const can::Frame& frame) noexcept = 0;
};

/// The scheduler's clocks (monotonic for timing, realtime for the Time/Date answer).
class Clock {
 public:
  virtual ~Clock() = default;
  [[nodiscard]] virtual std::int64_t monotonicNs() noexcept = 0;
  [[nodiscard]] virtual std::int64_t realtimeNs() noexcept = 0;
};

/// Per scheduled message; written by the scheduler's thread, readable from any thread.
struct MessageStats {
  std::atomic<std::uint64_t> frames{};        ///< frames of this message sent (SDMs, not their SHMs)
  std::atomic<std::uint64_t> missed{};        ///< cycles skipped because they were already past
  std::atomic<std::uint64_t> sendFailures{};  ///< the link refused the frame (or its SHM)
  std::atomic<std::uint64_t> encodeErrors{};  ///< a value the signal cannot carry (its bits kept)
  ErrorHistogram periodError;                 ///< |measured period - cycle| of consecutive cyclic sends
  ErrorHistogram deltaError;                  ///< |SHM->SDM time - delta| (safety pairs)
};

struct SchedulerCounters {
  std::atomic<std::uint64_t> oneShots{};       ///< frames from the send-request stream
  std::atomic<std::uint64_t> oneShotFailures{};
  std::atomic<std::uint64_t> requestsAnswered{};
  std::atomic<std::uint64_t> requestsNacked{};
  std::atomic<std::uint64_t> held{};       ///< frames held until a pending SDM of their PGN, SA, DA went out
  std::atomic<std::uint64_t> sdmsEarly{};  ///< SDMs sent before their delta because the hold was full
};

/// One scheduled message's state (defined in scheduler.cpp).
struct ScheduledEntry;
struct ScheduledEntryDeleter {
  void operator()(ScheduledEntry* entry) const noexcept;
};
using PreparedMessage = std::unique_ptr<ScheduledEntry, ScheduledEntryDeleter>;

/// @note not thread-safe: one thread runs it. run() and every change are noexcept and
///       allocation-free.
class Scheduler {
 public:
  /// `port`, `clock`, `table` and `catalog` must outlive the scheduler. `startNs` is the
  /// origin of every message's phase.
  static Result<std::unique_ptr<Scheduler>> create(const config::VehicleConfig& vehicle, const Schedule& schedule,
                                                   const signals::Catalog& catalog, signals::SignalTable& table,
                                                   TxPort& port, Clock& clock, std::int64_t startNs);
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  /// Sends everything due at `nowNs` (SHMs, SDMs, cyclic and on-change messages).
  void run(std::int64_t nowNs) noexcept;
  /// The earliest time run() has something to do (INT64_MAX: nothing scheduled).
  [[nodiscard]] std::int64_t nextDeadlineNs() const noexcept;
  /// The earliest deadline of a pending SDM (its SHM went out, deltaNs not yet passed), or
  /// INT64_MAX. The transmit thread stays on the CPU for an SDM due soon instead of sleeping
  /// again (tx_thread.hpp, planWait). nextDeadlineNs() is never later than it.
  [[nodiscard]] std::int64_t nextDataDeadlineNs() const noexcept;

  // ---- changes (by index into Schedule::messages; checked by the caller) ----------------
  void setCycle(std::size_t scheduled, std::int64_t cycleNs, std::int64_t nowNs) noexcept;
  void setEnabled(std::size_t scheduled, bool enabled) noexcept;
  void setDefault(std::size_t scheduled, std::uint32_t signal, double value) noexcept;

  // ---- adding a message at run time (ScheduleAdd) ---------------------------------------
  /// Builds the state of a message to add (allocates; any thread, the scheduler's
  /// configuration is read only). Its statistics live as long as the scheduler once added.
  [[nodiscard]] Result<PreparedMessage> prepare(const ScheduledMessage& message) const;
  [[nodiscard]] static const MessageStats& statsOf(const ScheduledEntry& entry) noexcept;
  /// Appends a prepared message after the last one; its first frame goes out at `nowNs`, then
  /// every cycle. Never reallocates: room for every DBC message is reserved at create().
  /// false (the message is left in `message`) when that room is used up.
  bool add(PreparedMessage& message, std::int64_t nowNs) noexcept;
  /// The number of messages the scheduler can hold (those scheduled plus what add() may append).
  [[nodiscard]] std::size_t capacity() const noexcept;

  /// Sends a frame other processes asked for, once, now (or right after a pending SDM with
  /// its PGN, SA and DA).
  void sendOnce(std::size_t bus, const can::Frame& frame) noexcept;
  /// Answers a J1939 request on `bus`: the Time/Date from the clock, a scheduled message's
  /// current frame, else (destination-specific requests) a NACK (J1939-21 Acknowledgement,
  /// shared/j1939 acknowledgement.hpp).
  void answerRequest(std::size_t bus, const j1939::Request& request) noexcept;

  [[nodiscard]] const MessageStats& stats(std::size_t scheduled) const noexcept;
  [[nodiscard]] const SchedulerCounters& counters() const noexcept;

 private:
  struct Impl;
  explicit Scheduler(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace openvcu::cantx
