#include "openvcu/core/clock.hpp"
#include "openvcu/service/command_handler.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <iterator>
#include <limits>
#include <utility>

#include "openvcu/core/text.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/service/logger.hpp"

namespace openvcu::service {

namespace {

/// Every command kind with its name (ipc::CommandKind, 1..11 in order).
constexpr std::pair<ipc::CommandKind, std::string_view> COMMAND_KINDS[] = {
    {ipc::CommandKind::SetSignal, "SetSignal"},         {ipc::CommandKind::SetOverride, "SetOverride"},
    {ipc::CommandKind::ClearOverride, "ClearOverride"}, {ipc::CommandKind::OperatorSwitch, "OperatorSwitch"},
    {ipc::CommandKind::FaultReset, "FaultReset"},       {ipc::CommandKind::ScheduleCycle, "ScheduleCycle"},
    {ipc::CommandKind::ScheduleEnable, "ScheduleEnable"}, {ipc::CommandKind::ScheduleDefault, "ScheduleDefault"},
    {ipc::CommandKind::FsmReload, "FsmReload"},         {ipc::CommandKind::SimFault, "SimFault"},
    {ipc::CommandKind::ScheduleAdd, "ScheduleAdd"},
};

bool knownKind(ipc::CommandKind kind) noexcept {
  return std::any_of(std::begin(COMMAND_KINDS), std::end(COMMAND_KINDS),
                     [kind](const auto& entry) { return entry.first == kind; });
}

bool isCustom(const CommandPolicy& policy, ipc::CommandKind kind) noexcept {
  return std::find(policy.customKinds.begin(), policy.customKinds.end(), kind) != policy.customKinds.end();
}

bool isDeferred(const CommandPolicy& policy, ipc::CommandKind kind) noexcept {
  return std::find(policy.deferredKinds.begin(), policy.deferredKinds.end(), kind) != policy.deferredKinds.end();
}

/// A signal whose value table names every whole number of its range (a switch, a state):
/// only those values mean anything. A table that names a few special values of a
/// continuous signal (J1939's 254 "Error", 255 "Not available") is not an enumeration.
bool enumeration(const signals::SignalInfo& info) {
  if (info.valueTexts.empty() || !(info.minimum < info.maximum)) return false;
  const double span = std::floor(info.maximum) - std::ceil(info.minimum) + 1;
  if (span > static_cast<double>(info.valueTexts.size())) return false;
  std::int64_t named = 0;
  for (const auto& entry : info.valueTexts) {
    const auto value = static_cast<double>(entry.first);
    if (value >= info.minimum && value <= info.maximum) ++named;
  }
  return static_cast<double>(named) >= span;
}

/// Operator intent first: a flood of other commands never delays Start/Stop or a fault reset.
int priority(ipc::CommandKind kind) noexcept {
  return kind == ipc::CommandKind::OperatorSwitch || kind == ipc::CommandKind::FaultReset ? 0 : 1;
}

/// The deadline check (check 0); empty when the request may still be applied at `nowNs`.
std::optional<std::string> deadlineProblem(const ipc::CommandRequest& request, std::int64_t nowNs) {
  if (request.deadlineNs <= 0) return std::string("the request carries no deadline; nothing applied");
  if (nowNs > request.deadlineNs) {
    return "expired: taken " + std::to_string((nowNs - request.deadlineNs) / 1'000'000) +
           " ms after its deadline; nothing applied";
  }
  if (request.deadlineNs - nowNs > ipc::MAX_COMMAND_HORIZON_NS) {
    return std::string("the request's deadline is more than 30 s ahead; nothing applied");
  }
  return std::nullopt;
}

bool carriesValue(ipc::CommandKind kind) noexcept {
  return kind == ipc::CommandKind::SetSignal || kind == ipc::CommandKind::SetOverride ||
         kind == ipc::CommandKind::OperatorSwitch || kind == ipc::CommandKind::ScheduleCycle ||
         kind == ipc::CommandKind::ScheduleEnable || kind == ipc::CommandKind::ScheduleDefault ||
         kind == ipc::CommandKind::ScheduleAdd;
}

/// Shortest text that reads back as the same double ("0.1", "100", "1e+20").
using text::number;

CommandVerdict refuse(std::string reason, std::optional<signals::SignalIndex> index = {}) {
  return CommandVerdict{CommandDecision::Refused, std::move(reason), index};
}

std::string describe(const ipc::CommandRequest& request, const std::string& from) {
  std::string text = commandKindName(request.kind) + " " + request.key;
  if (carriesValue(request.kind)) text += " = " + number(request.value);
  text += " from " + from + " (request " + std::to_string(request.requestId) + ")";
  if (!request.text.empty()) text += ", note '" + request.text + "'";
  return text;
}

}  // namespace

CommandPolicy CommandPolicy::byPrefix(std::string prefix) {
  CommandPolicy policy;
  policy.owns = [prefix = std::move(prefix)](std::string_view key) { return key.starts_with(prefix); };
  return policy;
}

CommandPolicy CommandPolicy::byOwner(const signals::Catalog& catalog, signals::WriterId owner) {
  CommandPolicy policy;
  policy.owns = [&catalog, owner](std::string_view key) {
    const auto index = catalog.indexOf(key);
    return index && catalog[*index].owner == owner;
  };
  return policy;
}

std::optional<std::string> statusRefusal(const signals::SignalInfo& info) {
  if (!info.reported) return std::nullopt;
  return "'" + info.key + "' is a status the stack reports; it cannot be commanded";
}

std::string commandKindName(ipc::CommandKind kind) {
  for (const auto& [known, name] : COMMAND_KINDS) {
    if (known == kind) return std::string(name);
  }
  return "kind " + std::to_string(static_cast<int>(kind));
}

CommandVerdict checkCommand(const ipc::CommandRequest& request, const signals::Catalog& catalog,
                            const CommandPolicy& policy) {
  if (isCustom(policy, request.kind)) {
    if (!policy.custom) return refuse(commandKindName(request.kind) + " has no handler in this service");
    return CommandVerdict{CommandDecision::Accepted, {}, {}};
  }
  if (isDeferred(policy, request.kind)) {
    if (!policy.defer) return refuse(commandKindName(request.kind) + " has no handler in this service");
    return CommandVerdict{CommandDecision::Accepted, {}, {}};
  }
  if (!policy.owns || !policy.owns(request.key)) return CommandVerdict{};
  const auto found = catalog.find(request.key);
  if (!found) return refuse(found.error().message);
  const signals::SignalIndex index = *found;
  if (!knownKind(request.kind)) {
    return refuse("unknown command kind " + std::to_string(static_cast<int>(request.kind)), index);
  }
  if (std::find(policy.kinds.begin(), policy.kinds.end(), request.kind) == policy.kinds.end()) {
    return refuse(commandKindName(request.kind) + " is not permitted for '" + request.key + "'", index);
  }
  const signals::SignalInfo& info = catalog[index];
  if (carriesValue(request.kind)) {
    if (!std::isfinite(request.value))
      return refuse("value " + number(request.value) + " is not a finite number", index);
    if (info.minimum < info.maximum && (request.value < info.minimum || request.value > info.maximum)) {
      return refuse("value " + number(request.value) + " is outside the range [" + number(info.minimum) + ", " +
                        number(info.maximum) + "]" + (info.unit.empty() ? "" : " " + info.unit) + " of '" +
                        request.key + "'",
                    index);
    }
  }
  if (carriesValue(request.kind) && enumeration(info)) {
    const bool named = std::any_of(info.valueTexts.begin(), info.valueTexts.end(), [&](const auto& entry) {
      return static_cast<double>(entry.first) == request.value;
    });
    if (!named) {
      std::string table;
      for (const auto& [value, text] : info.valueTexts) {
        table += (table.empty() ? "" : ", ") + std::to_string(value) + " " + text;
      }
      return refuse("value " + number(request.value) + " is not one of the values of '" + request.key + "' (" +
                        table + ")",
                    index);
    }
  }
  if (policy.veto) {
    if (auto maybeReason = policy.veto(request, info)) return refuse(std::move(*maybeReason), index);
  }
  return CommandVerdict{CommandDecision::Accepted, {}, index};
}

bool CommandReply::expired() const noexcept {
  return clock::monotonicNs() > m_deadlineNs;
}

void CommandReply::expire() {
  finish(std::string("expired: the deadline passed before it could be applied; nothing applied"));
}

CommandHandler::CommandHandler(const signals::Catalog& catalog, signals::SignalTable& table, ipc::EventBus& events,
                               std::string responder, signals::WriterId writer, CommandPolicy policy, Logger* log)
    : m_catalog(catalog),
      m_table(table),
      m_events(events),
      m_responder(std::move(responder)),
      m_writer(writer),
      m_policy(std::move(policy)),
      m_log(log) {}

CommandHandler::~CommandHandler() {
  *m_alive = false;
}

Status CommandHandler::listen(const std::string& instance, const std::string& groupName) {
  if (m_listener) return {};
  ipc::CommandListener::Options options;
  options.instance = instance;
  options.program = m_responder;
  options.groupName = groupName;
  auto listenerResult = ipc::CommandListener::open(std::move(options));
  if (!listenerResult) return listenerResult.error();
  m_listener = std::make_unique<ipc::CommandListener>(std::move(*listenerResult));
  m_batch.reserve(64);
  return {};
}

int CommandHandler::fd() const noexcept {
  return m_listener ? m_listener->fd() : -1;
}

void CommandHandler::onReadable() {
  if (!m_listener) return;
  m_batch.clear();
  m_listener->poll(m_batch);
  std::stable_sort(m_batch.begin(), m_batch.end(), [](const ipc::ReceivedCommand& a, const ipc::ReceivedCommand& b) {
    return priority(a.request.kind) < priority(b.request.kind);
  });
  const std::int64_t now = clock::monotonicNs();
  // Forget issuers quiet for 10 s (their bucket is full again anyway).
  if (m_buckets.size() > 64) {
    std::erase_if(m_buckets, [now](const auto& entry) { return now - entry.second.refilledNs > 10'000'000'000; });
  }
  for (const ipc::ReceivedCommand& received : m_batch) {
    Bucket& bucket = m_buckets[received.peer.pid];
    bucket.tokens = bucket.refilledNs == 0
                        ? ISSUER_BURST
                        : std::min(ISSUER_BURST,
                                   bucket.tokens + static_cast<double>(now - bucket.refilledNs) * 1e-9 * ISSUER_RATE);
    bucket.refilledNs = now;
    if (bucket.tokens < 1.0) {
      ++m_limited;
      ++bucket.limitedSinceLog;
      const ipc::CommandAck ack{0,     received.request.requestId,
                                received.request.issuer, m_responder,
                                false, "rate limit: more than " + number(ISSUER_RATE) + " commands/s from pid " +
                                           std::to_string(received.peer.pid) + "; nothing applied",
                                true};
      (void)m_listener->reply(received.connection, ack);
      if (m_log != nullptr && now - bucket.loggedNs >= 1'000'000'000) {
        m_log->warning("rate limit: refused " + std::to_string(bucket.limitedSinceLog) + " commands from pid " +
                       std::to_string(received.peer.pid) + " (uid " + std::to_string(received.peer.uid) + ")");
        bucket.loggedNs = now;
        bucket.limitedSinceLog = 0;
      }
      continue;
    }
    bucket.tokens -= 1.0;
    const std::string from = (received.request.issuer.empty() ? std::string("?") : received.request.issuer) +
                             ", uid " + std::to_string(received.peer.uid) + " pid " +
                             std::to_string(received.peer.pid);
    decide(received.request, received.connection, from);
  }
}

bool CommandHandler::apply(const ipc::CommandRequest& request, signals::SignalIndex index) noexcept {
  const std::int64_t now = clock::monotonicNs();
  switch (request.kind) {
    case ipc::CommandKind::SetSignal:
    case ipc::CommandKind::OperatorSwitch:
      return m_table.writeCommand(index, request.value, now, m_writer);
    case ipc::CommandKind::SetOverride:
      return m_table.setOverride(index, request.value, now, m_writer);
    case ipc::CommandKind::ClearOverride:
      return m_table.clearOverride(index, now, m_writer);
    case ipc::CommandKind::FaultReset:
    case ipc::CommandKind::ScheduleCycle:
    case ipc::CommandKind::ScheduleEnable:
    case ipc::CommandKind::ScheduleDefault:
    case ipc::CommandKind::FsmReload:
    case ipc::CommandKind::SimFault:
    case ipc::CommandKind::ScheduleAdd:
      return false;  // not table operations: a service handles them as custom kinds (or in its veto)
  }
  return false;
}

CommandVerdict CommandHandler::handle(const ipc::CommandRequest& request) {
  return decide(request, std::nullopt, request.issuer.empty() ? std::string("?") : request.issuer);
}

CommandVerdict CommandHandler::decide(const ipc::CommandRequest& request, std::optional<std::uint64_t> connection,
                                      const std::string& from) {
  CommandVerdict verdict = checkCommand(request, m_catalog, m_policy);
  if (verdict.decision == CommandDecision::Ignored) {
    ++m_ignored;
    if (connection && m_listener) {
      ipc::CommandAck ack{0, request.requestId, request.issuer, m_responder, false, {}, false};
      (void)m_listener->reply(*connection, ack);
    }
    return verdict;
  }
  if (auto problem = deadlineProblem(request, clock::monotonicNs())) {
    if (request.deadlineNs > 0 && problem->starts_with("expired")) ++m_expired;
    verdict = CommandVerdict{CommandDecision::Refused, std::move(*problem), verdict.index};
  } else if (verdict.decision == CommandDecision::Accepted && isDeferred(m_policy, request.kind)) {
    // Answered later, on this thread, through the reply; unless this handler is gone by then.
    std::weak_ptr<bool> alive = m_alive;
    CommandReply reply(
        [this, alive, request, connection, from](std::optional<std::string> refusal) {
          if (alive.expired()) return;
          if (refusal && refusal->starts_with("expired")) ++m_expired;
          finish(request, connection, from,
                 refusal ? CommandVerdict{CommandDecision::Refused, std::move(*refusal), {}}
                         : CommandVerdict{CommandDecision::Accepted, {}, {}});
        },
        request.deadlineNs);
    try {
      m_policy.defer(request, std::move(reply));
    } catch (const std::exception& error) {
      // `reply` was moved into the call: destroyed there unanswered, it refused already.
      if (m_log != nullptr) m_log->error(std::string("deferred command failed to start: ") + error.what());
    }
    return verdict;
  } else if (verdict.decision == CommandDecision::Accepted && isCustom(m_policy, request.kind)) {
    std::optional<std::string> refusal;
    try {
      refusal = m_policy.custom(request);
    } catch (const std::exception& error) {
      refusal = std::string("internal error: ") + error.what();
    }
    if (refusal) verdict = CommandVerdict{CommandDecision::Refused, std::move(*refusal), {}};
  } else if (verdict.decision == CommandDecision::Accepted && !apply(request, *verdict.index)) {
    verdict = CommandVerdict{CommandDecision::Refused, "the signal table did not take the write", verdict.index};
  } else if (verdict.decision == CommandDecision::Accepted && m_policy.applied) {
    m_policy.applied(request, *verdict.index);
  }
  finish(request, connection, from, verdict);
  return verdict;
}

void CommandHandler::finish(const ipc::CommandRequest& request, std::optional<std::uint64_t> connection,
                            const std::string& from, const CommandVerdict& verdict) {
  const bool accepted = verdict.decision == CommandDecision::Accepted;
  ++(accepted ? m_accepted : m_refused);
  const ipc::CommandAck ack{0, request.requestId, request.issuer, m_responder, accepted, verdict.reason, true};
  if (connection && m_listener) (void)m_listener->reply(*connection, ack);
  m_events.publish(ack);
  if (m_log != nullptr) {
    const std::string text = describe(request, from);
    if (!accepted) {
      m_log->warning("refused " + text + ": " + verdict.reason);
    } else if (request.kind == ipc::CommandKind::SetOverride || request.kind == ipc::CommandKind::ClearOverride) {
      m_log->warning("accepted " + text);  // overrides are always visible in the log
    } else {
      m_log->info("accepted " + text);
    }
  }
}

}  // namespace openvcu::service
