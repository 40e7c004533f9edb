#pragma once
// Private to shared/config: reads a bus' "j1939" object (vehicle.cpp's bus loop calls it).

#include <cstdint>
#include <optional>
#include <string>

#include "openvcu/config/bus_j1939.hpp"
#include "openvcu/config/json.hpp"

namespace openvcu::config {

/// Reads `bus`'s "j1939" member, if any, into `out`. `busPath` is "/buses/<i>";
/// `nodeAddress` is this VCU's DBC address (the default preferredAddress), empty when the
/// node has none. Every problem is an error in `check` naming its JSON path; `out` is set
/// only when the object had none.
void loadBusJ1939(const Json& bus, const std::string& busPath, std::optional<std::uint8_t> nodeAddress,
                  JsonChecker& check, std::optional<BusJ1939>& out);

/// The fields of a J1939 "name" object at `path` into `name` (fields in error stay 0); also
/// read by simulation.json's "j1939Peer" (simulation_peer.cpp).
void loadJ1939Name(JsonChecker& check, const Json& object, const std::string& path, j1939::Name& name);

}  // namespace openvcu::config
