#pragma once
// Checked operator commands: a service answers the CommandRequests for the keys it owns,
// checks each one before anything changes, applies it to the signal table and answers
// with exactly one CommandAck (docs/design/ipc.md, "Commands").
//
// Checks, in order (the first failure is the refusal reason):
//   1. the key is owned by this service (policy.owns); otherwise the request is IGNORED:
//      no ack, another service answers. Ownership goes by key text, so the owner of
//      "internal." also answers for a mistyped "internal.operator.Strat";
//   2. the key exists in the catalog ("unknown signal 'X' (did you mean 'Y'?)");
//   3. the kind is one this service accepts (policy.kinds; unknown kind numbers are refused);
//   4. the value is finite and inside the signal's [min, max] when min < max
//      (ClearOverride carries no value);
//   5. the service's own veto (policy.veto), e.g. "overrides are forbidden in state Drive".
// Then SetSignal and OperatorSwitch write the COMMAND plane, SetOverride sets and
// ClearOverride clears the OVERRIDE plane, stamped with the service's writer id.
//
//   service::CommandPolicy policy = service::CommandPolicy::byPrefix("internal.operator.");
//   service::CommandHandler handler(catalog, table, events, "vcu-fsm", FSM_WRITER, policy, &log);
//   if (auto subscribed = handler.subscribe(); !subscribed) return subscribed.error();
//   // answers come out of events.handleAll() in the service loop

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::ipc {
class EventBus;
}

namespace openvcu::service {

class Logger;

/// Which commands a service answers, and what it permits.
struct CommandPolicy {
  /// true for the keys this service answers for (known to the catalog or not).
  std::function<bool(std::string_view key)> owns;
  /// Kinds accepted for owned keys; others are refused.
  std::vector<ipc::CommandKind> kinds{ipc::CommandKind::SetSignal, ipc::CommandKind::SetOverride,
                                      ipc::CommandKind::ClearOverride, ipc::CommandKind::OperatorSwitch};
  /// Last check: a reason to refuse, or empty to accept. Optional.
  std::function<std::optional<std::string>(const ipc::CommandRequest&, const signals::SignalInfo&)> veto;
  /// Kinds that are not table operations and that this service alone answers, whatever
  /// the key (can-tx: ScheduleCycle, ScheduleEnable, ScheduleDefault). Such a request skips
  /// checks 1-5: `custom` checks and applies it and returns a refusal reason, or empty
  /// when it was applied.
  std::vector<ipc::CommandKind> customKinds;
  std::function<std::optional<std::string>(const ipc::CommandRequest&)> custom;
  /// Called after an accepted table command was applied (e.g. to persist it). Optional.
  std::function<void(const ipc::CommandRequest&, signals::SignalIndex)> applied;

  /// Owns every key that starts with `prefix` ("internal.operator.").
  static CommandPolicy byPrefix(std::string prefix);
};

enum class CommandDecision : std::uint8_t {
  Ignored,   ///< not ours: no ack
  Accepted,  ///< applied, ack accepted
  Refused,   ///< nothing changed, ack refused with a reason
};

struct CommandVerdict {
  CommandDecision decision{CommandDecision::Ignored};
  std::string reason;                         ///< refusals only
  std::optional<signals::SignalIndex> index;  ///< the key's index when known
};

/// "SetSignal", "SetOverride", "ClearOverride", "OperatorSwitch", "FaultReset",
/// "ScheduleCycle", "ScheduleEnable", "ScheduleDefault", "FsmReload", "SimFault", "ScheduleAdd", "kind N".
[[nodiscard]] std::string commandKindName(ipc::CommandKind kind);

/// The checks alone (no table, no bus): what CommandHandler::handle would decide. For a
/// custom kind it only says Accepted (with no index) when the policy has a `custom` hook.
[[nodiscard]] CommandVerdict checkCommand(const ipc::CommandRequest& request, const signals::Catalog& catalog,
                                          const CommandPolicy& policy);

/// @note restricted thread-safe: subscribe and handle on the thread that runs the event
///       bus's handle(). Not movable: the subscription refers to this object.
class CommandHandler {
 public:
  /// `responder`: the program name put in acks ("vcu-fsm"); `writer`: the writer id of the
  /// table writes; `log` (optional) gets one line per decided command.
  CommandHandler(const signals::Catalog& catalog, signals::SignalTable& table, ipc::EventBus& events,
                 std::string responder, signals::WriterId writer, CommandPolicy policy, Logger* log = nullptr);
  CommandHandler(const CommandHandler&) = delete;
  CommandHandler& operator=(const CommandHandler&) = delete;
  ~CommandHandler();

  /// Subscribes to the instance's command channel; requests are then handled inside
  /// events.handle()/handleAll().
  Status subscribe();

  /// Checks, applies and acknowledges one request (what the subscription calls).
  CommandVerdict handle(const ipc::CommandRequest& request);

  /// Counters (also reported in the heartbeat when the Service created the handler).
  [[nodiscard]] std::uint64_t accepted() const noexcept { return m_accepted; }
  [[nodiscard]] std::uint64_t refused() const noexcept { return m_refused; }
  [[nodiscard]] std::uint64_t ignored() const noexcept { return m_ignored; }
  [[nodiscard]] const CommandPolicy& policy() const noexcept { return m_policy; }

 private:
  bool apply(const ipc::CommandRequest& request, signals::SignalIndex index) noexcept;

  const signals::Catalog& m_catalog;
  signals::SignalTable& m_table;
  ipc::EventBus& m_events;
  std::string m_responder;
  signals::WriterId m_writer;
  CommandPolicy m_policy;
  Logger* m_log;
  std::optional<std::uint64_t> m_subscription;
  std::uint64_t m_accepted{};
  std::uint64_t m_refused{};
  std::uint64_t m_ignored{};
};

}  // namespace openvcu::service
