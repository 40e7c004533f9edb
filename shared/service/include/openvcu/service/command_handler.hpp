#pragma once
// Checked operator commands: a service takes CommandRequests from its command socket
// (ipc::CommandListener: only root, the stack's user and the command group can connect),
// checks each one before anything changes, applies it to the signal table and answers
// with exactly one CommandAck on the same connection (decided acks also go to the event bus
// for people and recorders). docs/design/security.md says who may command and why.
//
// Checks, in order (the first failure is the refusal reason):
//   0. the request carries a deadline (CLOCK_MONOTONIC), it has not passed and it is at most
//      30 s ahead: a request that waited past its deadline is refused "expired", never applied;
//   1. the key is owned by this service (policy.owns); otherwise the request is IGNORED:
//      the answer says owner = false, another service decides. The services own what the
//      catalog says they own (CommandPolicy::byOwner); a policy by prefix (the test fixture's
//      "internal.") also answers for a mistyped "internal.operator.Strat";
//   2. the key exists in the catalog ("unknown signal 'X' (did you mean 'Y'?)");
//   3. the kind is one this service accepts (policy.kinds; unknown kind numbers are refused);
//   4. the value is finite and inside the signal's [min, max] when min < max
//      (ClearOverride carries no value); for a signal whose value table names every whole
//      number of its range (a switch), only those values;
//   5. the service's own veto (policy.veto), e.g. "overrides are forbidden in state Drive".
// Then SetSignal and OperatorSwitch write the COMMAND plane, SetOverride sets and
// ClearOverride clears the OVERRIDE plane, stamped with the service's writer id.
//
//   service::CommandPolicy policy = service::CommandPolicy::byPrefix("internal.operator.");
//   service::CommandHandler handler(catalog, table, events, "vcu-fsm", FSM_WRITER, policy, &log);
//   if (auto listening = handler.listen("hhea", "openvcu"); !listening) return listening.error();
//   loop.addFd(handler.fd(), [&] { handler.onReadable(); });

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::ipc {
class EventBus;
}

namespace openvcu::service {

class Logger;

/// The one answer still owed to a deferred command (CommandPolicy::defer). Move-only; call
/// accept() or refuse() once, on the loop thread (the one that runs the service's Loop).
/// Destroyed unanswered, it refuses with "internal error: the command was dropped".
class CommandReply {
 public:
  using Finish = std::function<void(std::optional<std::string> refusal)>;
  CommandReply(Finish finish, std::int64_t deadlineNs) : m_finish(std::move(finish)), m_deadlineNs(deadlineNs) {}
  CommandReply(CommandReply&& other) noexcept
      : m_finish(std::exchange(other.m_finish, nullptr)), m_deadlineNs(other.m_deadlineNs) {}
  CommandReply& operator=(CommandReply&&) = delete;
  CommandReply(const CommandReply&) = delete;
  CommandReply& operator=(const CommandReply&) = delete;
  ~CommandReply() {
    if (m_finish) m_finish(std::string("internal error: the command was dropped"));
  }

  /// The request's deadline (CLOCK_MONOTONIC ns).
  [[nodiscard]] std::int64_t deadlineNs() const noexcept { return m_deadlineNs; }
  /// true once CLOCK_MONOTONIC is past the deadline: answer with expire(), apply nothing.
  [[nodiscard]] bool expired() const noexcept;
  /// Applied: answers "accepted".
  void accept() { finish(std::nullopt); }
  /// Nothing changed: answers "refused: <reason>".
  void refuse(std::string reason) { finish(std::move(reason)); }
  /// Past the deadline, nothing applied: answers "expired ...".
  void expire();
  [[nodiscard]] bool answered() const noexcept { return !m_finish; }

 private:
  void finish(std::optional<std::string> refusal) {
    if (auto call = std::exchange(m_finish, nullptr)) call(std::move(refusal));
  }
  Finish m_finish;
  std::int64_t m_deadlineNs;
};

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
  /// Custom kinds decided later, off the command path (vcu-fsm's FsmReload reads and checks a
  /// file on a worker thread). The request passed checks 1-5 like a custom kind; `defer`
  /// starts the work and returns at once; the service answers later, on the loop thread,
  /// through the CommandReply (exactly once). Before applying anything the service must ask
  /// `reply.expired()`: a request past its deadline is answered "expired" and never applied.
  std::vector<ipc::CommandKind> deferredKinds;
  std::function<void(const ipc::CommandRequest&, CommandReply)> defer;
  /// Called after an accepted table command was applied (e.g. to persist it). Optional.
  std::function<void(const ipc::CommandRequest&, signals::SignalIndex)> applied;

  /// Owns every key that starts with `prefix` ("internal.operator."; the test fixtures).
  static CommandPolicy byPrefix(std::string prefix);
  /// Owns the keys whose catalog owner (signals::SignalInfo::owner, decided by shared/config)
  /// is `owner`: what every service of the stack answers for. A key the catalog does not know
  /// is nobody's (`vcu signal set` answers it itself, with a did-you-mean). `catalog` must
  /// outlive the policy.
  static CommandPolicy byOwner(const signals::Catalog& catalog, signals::WriterId owner);
};

/// The refusal for a status the stack reports (SignalInfo::reported): "'K' is a status the
/// stack reports; it cannot be commanded"; empty for any other signal. Vetoes call it first.
[[nodiscard]] std::optional<std::string> statusRefusal(const signals::SignalInfo& info);

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

/// @note restricted thread-safe: listen, onReadable and handle on the service's loop thread.
///       Not movable: deferred replies refer to this object.
/// Per issuing process: requests decided at once, and per second after that.
inline constexpr double ISSUER_BURST = 50;
inline constexpr double ISSUER_RATE = 20;

class CommandHandler {
 public:
  /// `responder`: the program name put in acks ("vcu-fsm"); `writer`: the writer id of the
  /// table writes; `log` (optional) gets one line per decided command.
  CommandHandler(const signals::Catalog& catalog, signals::SignalTable& table, ipc::EventBus& events,
                 std::string responder, signals::WriterId writer, CommandPolicy policy, Logger* log = nullptr);
  CommandHandler(const CommandHandler&) = delete;
  CommandHandler& operator=(const CommandHandler&) = delete;
  ~CommandHandler();

  /// Opens this service's command socket (ipc::CommandListener, <program>.sock of
  /// `instance`; members of `groupName` may command). Then put fd() into the loop and call
  /// onReadable() when it is readable.
  Status listen(const std::string& instance, const std::string& groupName);
  /// The socket's fd (readable when requests wait), -1 before listen().
  [[nodiscard]] int fd() const noexcept;
  /// The listener (after listen()), for its path and counters.
  [[nodiscard]] const ipc::CommandListener* listener() const noexcept { return m_listener.get(); }
  /// Takes the requests waiting on the socket (at most one per connection: a flood on one
  /// connection cannot starve the others), operator commands (OperatorSwitch, FaultReset)
  /// first, and decides and answers each. One issuing process gets at most ISSUER_BURST
  /// requests at once and ISSUER_RATE per second after that; beyond, requests are refused
  /// "rate limit" on its socket only (a flood never floods the event bus with acks and logs).
  void onReadable();

  /// Decides one request that did not come through the socket (tests, in-process callers):
  /// checks it (deadline included), applies it and publishes the decided ack on the bus.
  CommandVerdict handle(const ipc::CommandRequest& request);

  /// Counters (also reported in the heartbeat when the Service created the handler).
  [[nodiscard]] std::uint64_t accepted() const noexcept { return m_accepted; }
  [[nodiscard]] std::uint64_t refused() const noexcept { return m_refused; }
  [[nodiscard]] std::uint64_t ignored() const noexcept { return m_ignored; }
  /// Requests refused because they arrived (or their deferred work ended) past their deadline.
  [[nodiscard]] std::uint64_t expired() const noexcept { return m_expired; }
  /// Requests refused by the per-issuer limit (answered on the socket only, not logged one
  /// by one, not published).
  [[nodiscard]] std::uint64_t limited() const noexcept { return m_limited; }
  [[nodiscard]] const CommandPolicy& policy() const noexcept { return m_policy; }

 private:
  CommandVerdict decide(const ipc::CommandRequest& request, std::optional<std::uint64_t> connection,
                        const std::string& from);
  void finish(const ipc::CommandRequest& request, std::optional<std::uint64_t> connection, const std::string& from,
              const CommandVerdict& verdict);
  bool apply(const ipc::CommandRequest& request, signals::SignalIndex index) noexcept;

  const signals::Catalog& m_catalog;
  signals::SignalTable& m_table;
  ipc::EventBus& m_events;
  std::string m_responder;
  signals::WriterId m_writer;
  CommandPolicy m_policy;
  Logger* m_log;
  std::unique_ptr<ipc::CommandListener> m_listener;
  std::vector<ipc::ReceivedCommand> m_batch;
  std::shared_ptr<bool> m_alive = std::make_shared<bool>(true);  ///< deferred replies check it
  std::uint64_t m_accepted{};
  std::uint64_t m_refused{};
  std::uint64_t m_ignored{};
  std::uint64_t m_expired{};
  std::uint64_t m_limited{};
  /// Per issuing process (pid): a token bucket of ISSUER_BURST, refilled at ISSUER_RATE per s.
  struct Bucket {
    double tokens{};
    std::int64_t refilledNs{};
    std::uint64_t limitedSinceLog{};
    std::int64_t loggedNs{};
  };
  std::map<std::int32_t, Bucket> m_buckets;
};

}  // namespace openvcu::service
