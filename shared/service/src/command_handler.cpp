#include "openvcu/service/command_handler.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <exception>
#include <limits>

#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/service/logger.hpp"

namespace openvcu::service {

namespace {

bool knownKind(ipc::CommandKind kind) noexcept {
  switch (kind) {
    case ipc::CommandKind::SetSignal:
    case ipc::CommandKind::SetOverride:
    case ipc::CommandKind::ClearOverride:
    case ipc::CommandKind::OperatorSwitch:
    case ipc::CommandKind::FaultReset:
    case ipc::CommandKind::ScheduleCycle:
    case ipc::CommandKind::ScheduleEnable:
    case ipc::CommandKind::ScheduleDefault:
    case ipc::CommandKind::FsmReload:
    case ipc::CommandKind::SimFault:
    case ipc::CommandKind::ScheduleAdd:
      return true;
  }
  return false;
}

bool isCustom(const CommandPolicy& policy, ipc::CommandKind kind) noexcept {
  return std::find(policy.customKinds.begin(), policy.customKinds.end(), kind) != policy.customKinds.end();
}

bool carriesValue(ipc::CommandKind kind) noexcept {
  return kind == ipc::CommandKind::SetSignal || kind == ipc::CommandKind::SetOverride ||
         kind == ipc::CommandKind::OperatorSwitch || kind == ipc::CommandKind::ScheduleCycle ||
         kind == ipc::CommandKind::ScheduleEnable || kind == ipc::CommandKind::ScheduleDefault ||
         kind == ipc::CommandKind::ScheduleAdd;
}

/// Shortest text that reads back as the same double ("0.1", "100", "1e+20").
std::string number(double value) {
  std::array<char, 32> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{}) return "?";
  return std::string(text.data(), end);
}

CommandVerdict refuse(std::string reason, std::optional<signals::SignalIndex> index = {}) {
  return CommandVerdict{CommandDecision::Refused, std::move(reason), index};
}

std::string describe(const ipc::CommandRequest& request) {
  std::string text = commandKindName(request.kind) + " " + request.key;
  if (carriesValue(request.kind)) text += " = " + number(request.value);
  text += " from " + (request.issuer.empty() ? "?" : request.issuer) + " (request " +
          std::to_string(request.requestId) + ")";
  if (!request.text.empty()) text += ", note '" + request.text + "'";
  return text;
}

}  // namespace

CommandPolicy CommandPolicy::byPrefix(std::string prefix) {
  CommandPolicy policy;
  policy.owns = [prefix = std::move(prefix)](std::string_view key) { return key.starts_with(prefix); };
  return policy;
}

std::string commandKindName(ipc::CommandKind kind) {
  switch (kind) {
    case ipc::CommandKind::SetSignal:
      return "SetSignal";
    case ipc::CommandKind::SetOverride:
      return "SetOverride";
    case ipc::CommandKind::ClearOverride:
      return "ClearOverride";
    case ipc::CommandKind::OperatorSwitch:
      return "OperatorSwitch";
    case ipc::CommandKind::FaultReset:
      return "FaultReset";
    case ipc::CommandKind::ScheduleCycle:
      return "ScheduleCycle";
    case ipc::CommandKind::ScheduleEnable:
      return "ScheduleEnable";
    case ipc::CommandKind::ScheduleDefault:
      return "ScheduleDefault";
    case ipc::CommandKind::FsmReload:
      return "FsmReload";
    case ipc::CommandKind::SimFault:
      return "SimFault";
    case ipc::CommandKind::ScheduleAdd:
      return "ScheduleAdd";
  }
  return "kind " + std::to_string(static_cast<int>(kind));
}

CommandVerdict checkCommand(const ipc::CommandRequest& request, const signals::Catalog& catalog,
                            const CommandPolicy& policy) {
  if (isCustom(policy, request.kind)) {
    if (!policy.custom) return refuse(commandKindName(request.kind) + " has no handler in this service");
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
  if (policy.veto) {
    if (auto maybeReason = policy.veto(request, info)) return refuse(std::move(*maybeReason), index);
  }
  return CommandVerdict{CommandDecision::Accepted, {}, index};
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
  if (m_subscription) m_events.unsubscribe(ipc::Subscription{*m_subscription});
}

Status CommandHandler::subscribe() {
  if (m_subscription) return {};
  auto subscribed = m_events.onCommand([this](const ipc::CommandRequest& request) { handle(request); });
  if (!subscribed) return subscribed.error();
  m_subscription = subscribed->id;
  return {};
}

bool CommandHandler::apply(const ipc::CommandRequest& request, signals::SignalIndex index) noexcept {
  const std::int64_t now = signals::monotonicNowNs();
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
  CommandVerdict verdict = checkCommand(request, m_catalog, m_policy);
  if (verdict.decision == CommandDecision::Ignored) {
    ++m_ignored;
    return verdict;
  }
  if (verdict.decision == CommandDecision::Accepted && isCustom(m_policy, request.kind)) {
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
  const bool accepted = verdict.decision == CommandDecision::Accepted;
  ++(accepted ? m_accepted : m_refused);
  m_events.publish(ipc::CommandAck{0, request.requestId, request.issuer, m_responder, accepted, verdict.reason});
  if (m_log != nullptr) {
    if (!accepted) {
      m_log->warning("refused " + describe(request) + ": " + verdict.reason);
    } else if (request.kind == ipc::CommandKind::SetOverride || request.kind == ipc::CommandKind::ClearOverride) {
      m_log->warning("accepted " + describe(request));  // overrides are always visible in the log
    } else {
      m_log->info("accepted " + describe(request));
    }
  }
  return verdict;
}

}  // namespace openvcu::service
