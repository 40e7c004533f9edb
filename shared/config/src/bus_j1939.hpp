#pragma once
// Private to shared/config: reads a bus' "j1939" object (vehicle.cpp's bus loop calls it).

#include "openvcu/config/bus_j1939.hpp"
#include "openvcu/config/json.hpp"

#include <cstdint>
#include <optional>
#include <string>

namespace openvcu::config {

/// Reads `bus`'s "j1939" member, if any, into `out`. `busPath` is "/buses/<i>";
/// `nodeAddress` is this VCU's DBC address (the default preferredAddress), empty when the
/// node has none. Every problem is an error in `check` naming its JSON path; `out` is set
/// only when the object had none.
void loadBusJ1939(const Json& bus, const std::string& busPath, std::optional<std::uint8_t> nodeAddress,
                  JsonChecker& check, std::optional<BusJ1939>& out);

}  // namespace openvcu::config
