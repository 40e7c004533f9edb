#include <algorithm>
#include <cmath>

#include "bus_j1939.hpp"
#include "openvcu/j1939/address_table.hpp"
#include "openvcu/j1939/id.hpp"
#include "simulation_peer_loader.hpp"

namespace openvcu::config {
namespace {

/// A whole number in [minimum, maximum] at object[key], else an error naming its path.
std::optional<std::uint32_t> whole(JsonChecker& check, const Json& object, const std::string& path,
                                   std::string_view key, double minimum, double maximum, std::string_view reason) {
  const std::optional<double> value = check.number(object, path, key, true);
  if (!value) return std::nullopt;
  if (*value < minimum || *value > maximum || *value != std::floor(*value)) {
    check.error(JsonChecker::join(path, key), "must be a whole number " + formatNumber(minimum) + ".." +
                                                  formatNumber(maximum) + " (" + std::string(reason) + ")");
    return std::nullopt;
  }
  return static_cast<std::uint32_t>(*value);
}

constexpr std::string_view ADDRESS_REASON = "254 is the null address, 255 global";

void step(JsonChecker& check, const Json& item, const std::string& path, SimPeerConfig& peer) {
  if (!check.isObject(item, path)) return;
  check.onlyKeys(item, path, {"atMs", "claim", "request", "to", "comment"});
  SimPeerStep step;
  step.atNs =
      static_cast<std::int64_t>(whole(check, item, path, "atMs", 0, 86'400'000, "ms after the start").value_or(0)) *
      1'000'000;
  const bool claim = item.contains("claim");
  const bool request = item.contains("request");
  if (claim == request) {
    check.error(path, "needs exactly one of \"claim\" (an address) and \"request\" (a PGN)");
    return;
  }
  if (claim) {
    if (item.contains("to")) check.error(path + "/to", "only a \"request\" has a destination");
    step.kind = SimPeerStep::Kind::Claim;
    step.address = static_cast<std::uint8_t>(
        whole(check, item, path, "claim", 0, j1939::MAX_CLAIMABLE_ADDRESS, ADDRESS_REASON).value_or(0));
  } else {
    step.kind = SimPeerStep::Kind::Request;
    step.pgn = whole(check, item, path, "request", 0, j1939::PGN_MASK, "an 18-bit PGN").value_or(0);
    const Json* to = check.member(item, path, "to", false);
    if (to == nullptr) {
      step.toVcu = true;  // the default: the VCU
    } else if (to->is_string()) {
      if (to->get<std::string>() == "vcu") {
        step.toVcu = true;
      } else {
        check.error(path + "/to", "expected \"vcu\" or an address 0..255");
      }
    } else {
      step.to = static_cast<std::uint8_t>(whole(check, item, path, "to", 0, 255, "255 is global").value_or(0));
    }
    if (std::find(peer.requestedPgns.begin(), peer.requestedPgns.end(), step.pgn) == peer.requestedPgns.end()) {
      peer.requestedPgns.push_back(step.pgn);
    }
  }
  peer.script.push_back(step);
}

}  // namespace

void loadSimPeer(const Json& root, JsonChecker& check, const VehicleConfig& vehicle,
                 std::optional<SimPeerConfig>& out) {
  const Json* object = check.member(root, "", "j1939Peer", false);
  if (object == nullptr || !check.isObject(*object, "/j1939Peer")) return;
  const std::string path = "/j1939Peer";
  check.onlyKeys(*object, path, {"bus", "address", "name", "script", "comment"});
  SimPeerConfig peer;
  peer.bus = check.string(*object, path, "bus").value_or("");
  const auto bus = std::find_if(vehicle.buses.begin(), vehicle.buses.end(),
                                [&](const BusConfig& candidate) { return candidate.name == peer.bus; });
  if (bus == vehicle.buses.end()) {
    if (!peer.bus.empty()) check.error(path + "/bus", "no bus '" + peer.bus + "' in the vehicle");
  } else if (!bus->j1939) {
    check.error(path + "/bus", "bus '" + peer.bus + "' has no \"j1939\" object (the VCU's NAME there)");
  } else {
    peer.busIndex = static_cast<std::size_t>(bus - vehicle.buses.begin());
    peer.vcuName = bus->j1939->name;
  }
  peer.address = static_cast<std::uint8_t>(
      whole(check, *object, path, "address", 0, j1939::MAX_CLAIMABLE_ADDRESS, ADDRESS_REASON).value_or(0));
  if (const Json* name = check.member(*object, path, "name", true))
    loadJ1939Name(check, *name, path + "/name", peer.name);
  if (bus != vehicle.buses.end() && bus->j1939 && peer.name == peer.vcuName) {
    check.error(path + "/name", "is the VCU's own NAME on bus '" + peer.bus + "'");
  }
  if (const Json* script = check.array(*object, path, "script", false)) {
    for (std::size_t i = 0; i < script->size(); ++i)
      step(check, (*script)[i], JsonChecker::join(path + "/script", i), peer);
  }
  std::stable_sort(peer.script.begin(), peer.script.end(),
                   [](const SimPeerStep& a, const SimPeerStep& b) { return a.atNs < b.atNs; });
  out = std::move(peer);
}

}  // namespace openvcu::config
