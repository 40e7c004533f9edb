#pragma once
// Private to shared/config: simulation.json's "j1939Peer" (simulation_peer.cpp), called by
// loadSimConfig (simulation.cpp).

#include <optional>

#include "openvcu/config/json.hpp"
#include "openvcu/config/simulation_peer.hpp"
#include "openvcu/config/vehicle.hpp"

namespace openvcu::config {

/// Reads root's "j1939Peer" member, if any, into `out`; every problem is an error in
/// `check` naming its JSON path.
void loadSimPeer(const Json& root, JsonChecker& check, const VehicleConfig& vehicle, std::optional<SimPeerConfig>& out);

}  // namespace openvcu::config
