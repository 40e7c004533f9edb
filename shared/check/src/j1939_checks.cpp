// The whole-vehicle J1939-81 checks (j1939_checks.hpp).
#include "j1939_checks.hpp"

#include <cstdio>
#include <string>

#include "openvcu/config/json.hpp"

namespace openvcu::check {
namespace {

std::string addressText(std::uint8_t address) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%02X (%u)", static_cast<unsigned>(address), static_cast<unsigned>(address));
  return text;
}

}  // namespace

void checkSafetyAddressPolicy(const config::VehicleConfig& vehicle, const VehicleFiles& files,
                              std::vector<Error>& out) {
  if (!files.schedule) return;
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    const config::BusConfig& bus = vehicle.buses[b];
    if (!bus.j1939 || !bus.j1939->claim || !bus.j1939->name.arbitraryAddressCapable) continue;
    std::vector<std::string> pairs;
    for (const schedule::ScheduledMessage& entry : files.schedule->messages) {
      if (entry.bus == b && entry.safetyDeltaNs) pairs.push_back(vehicle.database.messages[entry.message].name);
    }
    if (pairs.empty()) continue;
    const std::string address = addressText(bus.j1939->preferredAddress);
    out.push_back(Error{
        "bus '" + bus.name + "': the VCU sends J1939-76 safety pairs here (" + listNames(pairs) + ") from " + address +
            " but its NAME is arbitrary address capable: a NAME of higher priority claiming " + address +
            " makes it move, and the pairs' receivers expect them from " + address +
            " (vcu-can-tx then holds them and raises j1939_address_lost." + bus.name +
            "). Give the bus a fixed address: \"arbitraryAddressCapable\": false (losing " + address +
            " is then Cannot Claim and silence on the bus, J1939-81)",
        Location::json(vehicle.path, config::JsonChecker::join("/buses", b) + "/j1939/name/arbitraryAddressCapable"),
        Severity::Warning});
  }
}

}  // namespace openvcu::check
