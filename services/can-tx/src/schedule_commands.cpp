#include "schedule_commands.hpp"

#include <cmath>

#include "openvcu/core/text.hpp"

namespace openvcu::cantx {
namespace {

constexpr std::int64_t NS_PER_MS = 1'000'000;

using text::number;

MessageChange& changeOf(Overlay& target, const std::string& name) {
  for (MessageChange& change : target.messages) {
    if (change.message == name) return change;
  }
  return target.messages.emplace_back(MessageChange{name, std::nullopt, std::nullopt, false});
}

}  // namespace

ScheduleCommands::ScheduleCommands(const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
                                   Schedule& schedule, Overlay& overlay, const Scheduler& scheduler,
                                   ScheduleChangeSink& sink) noexcept
    : m_vehicle(vehicle),
      m_catalog(catalog),
      m_schedule(schedule),
      m_overlay(overlay),
      m_scheduler(scheduler),
      m_sink(sink) {}

std::optional<std::string> ScheduleCommands::apply(const ipc::CommandRequest& request) {
  if (!std::isfinite(request.value)) return "the value must be a finite number";
  switch (request.kind) {
    case ipc::CommandKind::ScheduleAdd:
      return add(request);
    case ipc::CommandKind::ScheduleDefault:
      return setDefault(request);
    case ipc::CommandKind::ScheduleCycle:
    case ipc::CommandKind::ScheduleEnable: {
      auto found = findScheduled(m_schedule, m_vehicle, request.key);
      if (!found) return found.error().message;
      return request.kind == ipc::CommandKind::ScheduleCycle ? setCycle(*found, request) : setEnabled(*found, request);
    }
    default:
      return "not a schedule command";
  }
}

std::optional<std::string> ScheduleCommands::recordOverride(const std::string& key, std::optional<double> value) {
  Overlay changed = m_overlay;
  std::erase_if(changed.overrides, [&](const auto& item) { return item.first == key; });
  if (value) changed.overrides.emplace_back(key, *value);
  return persist(std::move(changed));
}

/// Saves `changed` as the overlay; the reason when that failed (nothing changed then).
std::optional<std::string> ScheduleCommands::persist(Overlay changed) {
  if (Status saved = saveOverlay(m_schedule.overlay, changed); !saved) {
    return "not applied: " + saved.error().message;
  }
  m_overlay = std::move(changed);
  return std::nullopt;
}

/// Posts an accepted change; when the transmit thread cannot take it, the overlay saved
/// for it is put back to `previous`.
std::optional<std::string> ScheduleCommands::post(TxCommand&& command, const Overlay& previous) {
  if (m_sink.post(std::move(command))) return std::nullopt;
  (void)persist(previous);
  return "the transmit thread's inbox is full; try again";
}

/// ScheduleAdd: a DBC message joins the running schedule (at the end, first frame now).
std::optional<std::string> ScheduleCommands::add(const ipc::CommandRequest& request) {
  auto built = runtimeMessage(m_schedule, m_vehicle, m_catalog, request.key, request.value);
  if (!built) return built.error().message;
  if (m_schedule.messages.size() >= m_scheduler.capacity()) return "the schedule is full";
  auto prepared = m_scheduler.prepare(*built);
  if (!prepared) return prepared.error().message;
  const Overlay previous = m_overlay;
  Overlay changed = m_overlay;
  MessageChange& change = changeOf(changed, request.key);
  change.added = true;
  change.cycleMs = request.value;
  if (auto refusal = persist(std::move(changed))) return refusal;
  const MessageStats& stats = Scheduler::statsOf(**prepared);
  TxCommand command{AddMessage{std::move(*prepared)}};
  if (auto refusal = post(std::move(command), previous)) return refusal;  // the entry is freed with `command`
  m_schedule.messages.push_back(std::move(*built));
  m_sink.added(m_schedule.messages.size() - 1, stats);
  return std::nullopt;
}

std::optional<std::string> ScheduleCommands::setDefault(const ipc::CommandRequest& request) {
  auto found = findScheduledSignal(m_schedule, m_vehicle, m_catalog, request.key);
  if (!found) return found.error().message;
  ScheduledMessage& entry = m_schedule.messages[found->scheduled];
  const dbc::Signal& signal = m_vehicle.database.messages[entry.message].signals[found->signal];
  for (const ComputedField& field : entry.computed) {
    if (field.signal == found->signal) {
      return "'" + request.key + "' is computed (" + std::string(fieldAlgorithmName(field.algorithm)) +
             ") for every frame";
    }
  }
  if (signal.minimum < signal.maximum && (request.value < signal.minimum || request.value > signal.maximum)) {
    return "value " + number(request.value) + " is outside the range [" + number(signal.minimum) + ", " +
           number(signal.maximum) + "] of '" + request.key + "'";
  }
  const Overlay previous = m_overlay;
  Overlay changed = m_overlay;
  std::erase_if(changed.defaults, [&](const auto& item) { return item.first == request.key; });
  changed.defaults.emplace_back(request.key, request.value);
  if (auto refusal = persist(std::move(changed))) return refusal;
  if (auto refusal = post(SetDefault{found->scheduled, found->signal, request.value}, previous)) return refusal;
  entry.defaults[found->signal] = request.value;
  return std::nullopt;
}

std::optional<std::string> ScheduleCommands::setCycle(std::size_t scheduled, const ipc::CommandRequest& request) {
  ScheduledMessage& entry = m_schedule.messages[scheduled];
  if (auto problem = checkCycle(entry, request.value)) return problem;
  // The bus-load limit holds for runtime changes too (the schedule file's rule).
  const std::int64_t previousCycleNs = entry.cycleNs;
  const auto cycleNs = static_cast<std::int64_t>(std::llround(request.value * NS_PER_MS));
  entry.cycleNs = cycleNs;
  const auto overload = checkBusLoad(m_schedule, m_vehicle);
  entry.cycleNs = previousCycleNs;
  if (overload) return *overload;
  const Overlay previous = m_overlay;
  Overlay changed = m_overlay;
  changeOf(changed, request.key).cycleMs = request.value;
  if (auto refusal = persist(std::move(changed))) return refusal;
  if (auto refusal = post(SetCycle{scheduled, cycleNs}, previous)) return refusal;
  entry.cycleNs = cycleNs;
  return std::nullopt;
}

std::optional<std::string> ScheduleCommands::setEnabled(std::size_t scheduled, const ipc::CommandRequest& request) {
  ScheduledMessage& entry = m_schedule.messages[scheduled];
  if (request.value != 0.0 && request.value != 1.0) return "the value is 1 (enable) or 0 (disable)";
  const Overlay previous = m_overlay;
  Overlay changed = m_overlay;
  changeOf(changed, request.key).enabled = request.value == 1.0;
  if (auto refusal = persist(std::move(changed))) return refusal;
  const bool enabled = request.value == 1.0;
  if (auto refusal = post(SetEnabled{scheduled, enabled}, previous)) return refusal;
  entry.enabled = enabled;
  return std::nullopt;
}

}  // namespace openvcu::cantx
