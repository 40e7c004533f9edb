#pragma once
// The schedule commands of vcu-can-tx (`vcu schedule cycle|enable|default|add`, and the
// overrides the operator sets): each is checked against the schedule's rules, saved to the
// overlay file, and only then posted to the transmit thread; the answer is empty
// (accepted) or the reason of the refusal, which the command socket sends back.
//
//   cantx::ScheduleCommands commands(vehicle, catalog, schedule, overlay, *scheduler, sink);
//   std::optional<std::string> refusal = commands.apply(request);   // ScheduleCycle ...
//   // request {ScheduleCycle, "CMD_SYS_1", 0.5} -> "cycle 0.5 ms is below ..." (nothing changed)
//
// Rules (docs/design/can-tx.md, "Runtime changes"):
//   - the value is finite; a cycle passes checkCycle and the bus-load limit; enable is 0 or
//     1; a default is inside the signal's DBC range and never on a computed field; an added
//     message is a DBC message this node sends, within the scheduler's room;
//   - the overlay is saved before the change is posted; a save that fails refuses the
//     command, a post the transmit thread's inbox refuses puts the previous overlay back
//     and leaves `schedule` as it was: the file, the loop's view and the running schedule
//     never disagree.

#include <cstddef>
#include <optional>
#include <string>

#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "scheduler.hpp"
#include "tx_thread.hpp"

namespace openvcu::cantx {

/// Where accepted schedule changes go (the transmit thread and the heartbeat in the
/// service; a recorder in tests).
class ScheduleChangeSink {
 public:
  virtual ~ScheduleChangeSink() = default;
  /// Hands a change to the transmit thread. false when it cannot take it now (full inbox;
  /// `command` then stays with the caller).
  virtual bool post(TxCommand&& command) noexcept = 0;
  /// Message `scheduled` (index into Schedule::messages) joined the schedule; `stats` lives
  /// as long as the scheduler.
  virtual void added(std::size_t scheduled, const MessageStats& stats) = 0;
};

/// @note restricted thread-safe: the service's loop thread (it changes `schedule`, the
///       loop's view of the schedule, and `overlay`).
class ScheduleCommands {
 public:
  /// Every reference must outlive the object. `schedule` and `overlay` are the service's
  /// (loaded, the overlay applied); `scheduler` is only asked for capacity() and prepare().
  ScheduleCommands(const config::VehicleConfig& vehicle, const signals::Catalog& catalog, Schedule& schedule,
                   Overlay& overlay, const Scheduler& scheduler, ScheduleChangeSink& sink) noexcept;

  /// ScheduleCycle, ScheduleEnable, ScheduleDefault or ScheduleAdd: empty when applied,
  /// else why not (then nothing changed: not the file, not the schedule).
  [[nodiscard]] std::optional<std::string> apply(const ipc::CommandRequest& request);

  /// Keeps (value) or drops (empty) the operator's override of `key` in the overlay file.
  /// Empty when saved, else why not.
  [[nodiscard]] std::optional<std::string> recordOverride(const std::string& key, std::optional<double> value);

 private:
  std::optional<std::string> persist(Overlay changed);
  std::optional<std::string> post(TxCommand&& command, const Overlay& previous);
  std::optional<std::string> add(const ipc::CommandRequest& request);
  std::optional<std::string> setDefault(const ipc::CommandRequest& request);
  std::optional<std::string> setCycle(std::size_t scheduled, const ipc::CommandRequest& request);
  std::optional<std::string> setEnabled(std::size_t scheduled, const ipc::CommandRequest& request);

  const config::VehicleConfig& m_vehicle;
  const signals::Catalog& m_catalog;
  Schedule& m_schedule;
  Overlay& m_overlay;
  const Scheduler& m_scheduler;
  ScheduleChangeSink& m_sink;
};

}  // namespace openvcu::cantx
