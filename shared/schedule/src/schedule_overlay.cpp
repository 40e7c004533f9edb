// The overlay: can-tx's runtime schedule changes, kept across restarts (docs/design/can-tx.md,
// "The overlay"): read, checked and applied all or nothing, written atomically.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "openvcu/core/output_file.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/schedule/schedule_config.hpp"

namespace openvcu::schedule {
namespace {

constexpr std::int64_t NS_PER_MS = 1'000'000;

using config::Json;
using config::JsonChecker;

}  // namespace

Result<Overlay> loadOverlay(const std::string& path) {
  std::error_code ignored;
  if (!std::filesystem::exists(path, ignored)) return Overlay{};
  auto jsonResult = config::readJsonFile(path);
  if (!jsonResult) return jsonResult.error();
  const Json& root = *jsonResult;
  JsonChecker check(path);
  Overlay overlay;
  if (!check.isObject(root, "")) return check.firstError();
  check.onlyKeys(root, "", {"format", "messages", "defaults", "overrides", "comment"});
  if (auto format = check.number(root, "", "format"); format && *format != 1) {
    check.error("/format", "unknown overlay format (this vcu-can-tx writes format 1)");
  }
  if (const Json* messages = check.member(root, "", "messages", false); messages && check.isObject(*messages, "/messages")) {
    for (const auto& [name, settings] : messages->items()) {
      const std::string itemPath = JsonChecker::join("/messages", name);
      if (!check.isObject(settings, itemPath)) continue;
      check.onlyKeys(settings, itemPath, {"cycleMs", "enabled", "added"});
      MessageChange change{name, check.number(settings, itemPath, "cycleMs", false),
                           check.boolean(settings, itemPath, "enabled", false),
                           check.boolean(settings, itemPath, "added", false).value_or(false)};
      if (change.added && !change.cycleMs) check.error(itemPath + "/cycleMs", "an added message needs its cycle");
      overlay.messages.push_back(std::move(change));
    }
  }
  for (auto [key, target] : {std::pair{"defaults", &overlay.defaults}, std::pair{"overrides", &overlay.overrides}}) {
    const Json* map = check.member(root, "", key, false);
    if (map == nullptr || !check.isObject(*map, std::string("/") + key)) continue;
    for (const auto& [signal, value] : map->items()) {
      if (!value.is_number()) {
        check.error(JsonChecker::join(std::string("/") + key, signal), "must be a number");
        continue;
      }
      target->emplace_back(signal, value.get<double>());
    }
  }
  if (!check.ok()) return check.firstError();
  return overlay;
}

Result<Schedule> applyOverlay(const Schedule& schedule, const Overlay& overlay, const config::VehicleConfig& vehicle,
                              const signals::Catalog& catalog) {
  Schedule result = schedule;
  const std::string& file = schedule.overlay;
  for (const MessageChange& change : overlay.messages) {
    const std::string path = file + ": /messages/" + change.message;
    if (change.added) {
      auto added = runtimeMessage(result, vehicle, catalog, change.message, change.cycleMs.value_or(0));
      if (!added) return Error{path + ": " + added.error().message};
      result.messages.push_back(std::move(*added));
    }
    auto found = findScheduled(result, vehicle, change.message);
    if (!found) return Error{path + ": " + found.error().message};
    ScheduledMessage& entry = result.messages[*found];
    if (change.cycleMs) {
      if (auto problem = checkCycle(entry, *change.cycleMs)) return Error{path + "/cycleMs: " + *problem};
      entry.cycleNs = static_cast<std::int64_t>(std::llround(*change.cycleMs * NS_PER_MS));
    }
    if (change.enabled) entry.enabled = *change.enabled;
  }
  for (const auto& [key, value] : overlay.defaults) {
    const std::string path = file + ": /defaults/" + key;
    auto found = findScheduledSignal(result, vehicle, catalog, key);
    if (!found) return Error{path + ": " + found.error().message};
    ScheduledMessage& entry = result.messages[found->scheduled];
    const dbc::Signal& signal = vehicle.database.messages[entry.message].signals[found->signal];
    if (auto problem = checkSignalValue(signal, value)) return Error{path + ": " + *problem};
    entry.defaults[found->signal] = value;
  }
  for (const auto& [key, value] : overlay.overrides) {
    const std::string path = file + ": /overrides/" + key;
    auto found = findScheduledSignal(result, vehicle, catalog, key);
    if (!found) return Error{path + ": " + found.error().message};
    const ScheduledMessage& entry = result.messages[found->scheduled];
    const dbc::Signal& signal = vehicle.database.messages[entry.message].signals[found->signal];
    if (auto problem = checkSignalValue(signal, value)) return Error{path + ": " + *problem};
  }
  return result;
}

Status saveOverlay(const std::string& path, const Overlay& overlay) {
  Json root = Json::object();
  root["format"] = 1;
  root["comment"] = "runtime changes of the transmit schedule, written by vcu-can-tx (docs/design/can-tx.md)";
  Json messages = Json::object();
  for (const MessageChange& change : overlay.messages) {
    Json item = Json::object();
    if (change.added) item["added"] = true;
    if (change.cycleMs) item["cycleMs"] = *change.cycleMs;
    if (change.enabled) item["enabled"] = *change.enabled;
    messages[change.message] = std::move(item);
  }
  root["messages"] = std::move(messages);
  Json defaults = Json::object();
  for (const auto& [key, value] : overlay.defaults) defaults[key] = value;
  root["defaults"] = std::move(defaults);
  Json overrides = Json::object();
  for (const auto& [key, value] : overlay.overrides) overrides[key] = value;
  root["overrides"] = std::move(overrides);
  const std::string text = root.dump(2) + "\n";

  return output::writeFileAtomically(path, text, "overlay");
}

}  // namespace openvcu::schedule
