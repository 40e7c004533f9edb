#include "policy.hpp"

#include "openvcu/safety/safety_case.hpp"
#include "openvcu/service/heartbeat.hpp"

namespace openvcu::watchdog {
namespace {

/// Each service needs its heartbeat slot; `where` names the list in errors.
Status checkSlots(const WatchedPolicy& policy, const signals::Catalog& catalog, const std::string& where) {
  if (policy.services.empty()) return Error{where + ": no service to watch"};
  for (std::size_t i = 0; i < policy.services.size(); ++i) {
    const std::string key = service::heartbeatKey(policy.services[i]);
    if (!catalog.indexOf(key)) {
      return Error{where + "/" + std::to_string(i) + ": '" + policy.services[i] + "' has no heartbeat slot '" + key +
                   "' in the catalog (not a service of the stack)"};
    }
  }
  return {};
}

WatchedPolicy defaults(std::string origin) {
  WatchedPolicy policy;
  for (const std::string_view name : DEFAULT_SERVICES) policy.services.emplace_back(name);
  policy.origin = std::move(origin);
  return policy;
}

}  // namespace

Result<WatchedPolicy> policyOf(const config::VehicleConfig& vehicle, const signals::Catalog& catalog) {
  if (vehicle.safetyFile.empty()) {
    WatchedPolicy policy = defaults("defaults: " + vehicle.path + " names no safety case");
    if (Status checked = checkSlots(policy, catalog, "default services"); !checked) return checked.error();
    return policy;
  }
  auto safetyResult = safety::loadSafety(vehicle.safetyFile);
  if (!safetyResult) return safetyResult.error();
  if (!safetyResult->watchdog) {
    WatchedPolicy policy = defaults("defaults: " + vehicle.safetyFile + " has no \"watchdog\"");
    if (Status checked = checkSlots(policy, catalog, "default services"); !checked) return checked.error();
    return policy;
  }
  const safety::WatchdogPolicy& section = *safetyResult->watchdog;
  WatchedPolicy policy{section.services, section.silentAfterMs, section.restart, section.device,
                       vehicle.safetyFile + " /watchdog"};
  if (Status checked = checkSlots(policy, catalog, vehicle.safetyFile + ": /watchdog/services"); !checked) {
    return checked.error();
  }
  return policy;
}

}  // namespace openvcu::watchdog
