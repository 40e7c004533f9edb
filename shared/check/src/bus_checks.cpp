// The whole-vehicle bus checks (vehicle_check.hpp): expected bus load, address and
// identifier collisions.
#include <algorithm>
#include <map>
#include <set>

#include "openvcu/can/frame.hpp"
#include "openvcu/check/vehicle_check.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/j1939/transport.hpp"
#include "vehicle_files.hpp"

namespace openvcu::check {
namespace {

constexpr std::int64_t NS_PER_MS = 1'000'000;
/// J1939-21 transport: a BAM carries 7 data bytes per TP.DT frame after one TP.CM.
constexpr std::size_t TP_BYTES_PER_PACKET = 7;
/// Source addresses that name no node: 254 null (cannot claim), 255 global.
constexpr std::uint32_t FIRST_NON_NODE_ADDRESS = 0xFE;

/// The cyclic frames of one message on one bus and their share of the bus.
struct MessageLoad {
  std::string name;
  std::string sender;
  std::int64_t cycleNs{};
  double load{};
};

/// The frames another node's cyclic DBC message takes: one, or for a J1939 message longer
/// than the bus' frames a broadcast transport session (TP.CM + one TP.DT per 7 bytes).
std::vector<config::CyclicFrame> framesOf(const dbc::Message& message, const config::BusConfig& bus,
                                          std::int64_t cycleNs) {
  const std::size_t frameBytes = bus.fd ? can::MAX_DATA_LENGTH : can::CLASSIC_DATA_LENGTH;
  if (message.length <= frameBytes) {
    return {config::CyclicFrame{message.id, message.extended, static_cast<std::uint8_t>(message.length), cycleNs}};
  }
  const std::uint8_t source = j1939::Id::fromCanId(message.id).sourceAddress;
  const auto tpId = [&](std::uint32_t pgn) {
    return j1939::Id::fromPgn(pgn, j1939::TP_CM_PRIORITY, source, j1939::GLOBAL_ADDRESS).toCanId();
  };
  std::vector<config::CyclicFrame> frames;
  frames.push_back(config::CyclicFrame{tpId(j1939::PGN_TP_CM), true, can::CLASSIC_DATA_LENGTH, cycleNs});
  const std::size_t packets = (message.length + TP_BYTES_PER_PACKET - 1) / TP_BYTES_PER_PACKET;
  for (std::size_t p = 0; p < packets; ++p) {
    frames.push_back(config::CyclicFrame{tpId(j1939::PGN_TP_DT), true, can::CLASSIC_DATA_LENGTH, cycleNs});
  }
  return frames;
}

std::string cycleText(std::int64_t cycleNs) {
  return config::formatNumber(static_cast<double>(cycleNs) / static_cast<double>(NS_PER_MS)) + " ms";
}

}  // namespace

void checkBusLoads(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::vector<Error>& out) {
  if (!files.schedule) return;  // the VCU's share is unknown
  const auto& messages = vehicle.database.messages;
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    const config::BusConfig& bus = vehicle.buses[b];
    std::vector<MessageLoad> loads;
    double vcuLoad = 0;
    for (const schedule::ScheduledMessage& entry : files.schedule->messages) {
      if (entry.bus != b || entry.cycleNs <= 0) continue;
      const dbc::Message& message = messages[entry.message];
      std::vector<config::CyclicFrame> frames = {config::CyclicFrame{
          entry.canId, entry.extended,
          static_cast<std::uint8_t>(std::min<std::size_t>(message.length, can::MAX_DATA_LENGTH)), entry.cycleNs}};
      if (entry.safetyDeltaNs) {  // the SHM before every SDM
        frames.push_back(config::CyclicFrame{j1939::safetyHeaderCanId(entry.canId), true,
                                             static_cast<std::uint8_t>(j1939::SAFETY_MESSAGE_LENGTH), entry.cycleNs});
      }
      const double load = config::cyclicBusLoad(frames, bus);
      vcuLoad += load;
      loads.push_back(MessageLoad{message.name, vehicle.node, entry.cycleNs, load});
    }
    for (const std::size_t m : bus.messages) {
      const dbc::Message& message = messages[m];
      if (message.pseudo || !message.cycleTimeMs || config::sentBy(message, vehicle.node)) continue;
      const std::int64_t cycleNs = static_cast<std::int64_t>(*message.cycleTimeMs) * NS_PER_MS;
      std::vector<config::CyclicFrame> frames = framesOf(message, bus, cycleNs);
      if (files.receive) {  // a J1939-76 SDM another node sends comes after its SHM
        for (const config::SafetyGroup& group : files.receive->safety) {
          if (group.dataMessage != m) continue;
          frames.push_back(config::CyclicFrame{j1939::safetyHeaderCanId(message.id), true,
                                               static_cast<std::uint8_t>(j1939::SAFETY_MESSAGE_LENGTH), cycleNs});
        }
      }
      const std::string sender = message.transmitter == dbc::NO_NODE ? "no node named" : message.transmitter;
      loads.push_back(MessageLoad{message.name, sender, cycleNs, config::cyclicBusLoad(frames, bus)});
    }
    double total = 0;
    for (const MessageLoad& load : loads) total += load.load;
    if (total <= BUS_LOAD_WARNING) continue;
    std::sort(loads.begin(), loads.end(), [](const MessageLoad& a, const MessageLoad& c) { return a.load > c.load; });
    std::vector<std::string> heaviest;
    for (std::size_t i = 0; i < std::min<std::size_t>(3, loads.size()); ++i) {
      heaviest.push_back(loads[i].name + " (" + loads[i].sender + ") every " + cycleText(loads[i].cycleNs) + ": " +
                         percent(loads[i].load));
    }
    const bool error = total > BUS_LOAD_ERROR;
    std::string text = "bus '" + bus.name + "': the cyclic frames expected on it take " + percent(total) + " of its " +
                       std::to_string(bus.bitrate) + " bit/s (" + vehicle.node + "'s schedule " + percent(vcuLoad) +
                       ", the other nodes' DBC cycles " + percent(total - vcuLoad) + "), more than " +
                       percent(error ? BUS_LOAD_ERROR : BUS_LOAD_WARNING) +
                       (error ? ": they cannot all be sent" : ", the most a J1939 bus should carry") +
                       "; heaviest: " + heaviest.front();
    for (std::size_t i = 1; i < heaviest.size(); ++i) text += ", " + heaviest[i];
    text += "; lengthen cycles or raise the bit rate";
    out.push_back(Error{std::move(text), Location::json(vehicle.path, config::JsonChecker::join("/buses", b)),
                        error ? Severity::Error : Severity::Warning});
  }
}

namespace {

/// One use of a source address by a node on a bus.
struct AddressUse {
  std::string node;
  std::string how;  ///< "NmStationAddress", "message X (0x18FEF1F3)"
  Location where;
  bool station{};  ///< the node's NmStationAddress
};

std::string hexByte(std::uint32_t value) {
  std::string text = hexId(value, false);  // "0x0F3"
  return "0x" + text.substr(3) + " (" + std::to_string(value) + ")";
}

/// Where a node's attributes are defined: the DBC file when the vehicle has one (the model
/// keeps no line for BA_), else vehicle.json's /dbc.
Location nodeLocation(const config::VehicleConfig& vehicle) {
  if (vehicle.dbcFiles.size() == 1) return Location{vehicle.dbcFiles.front(), 0, 0, {}};
  return Location::json(vehicle.path, "/dbc");
}

/// The explicit NmStationAddress of a node (a default would give every node the same one).
std::optional<std::uint32_t> explicitAddress(const dbc::Node& node) {
  const auto it = node.attributes.find("NmStationAddress");
  if (it == node.attributes.end() || it->second.kind != dbc::AttributeValue::Kind::Number) return std::nullopt;
  const double value = it->second.number;
  if (value < 0 || value >= FIRST_NON_NODE_ADDRESS) return std::nullopt;
  return static_cast<std::uint32_t>(value);
}

/// Nodes on bus `b` sharing a J1939 source address: the VCU's from its scheduled IDs, the
/// others' from the J1939 messages they send, and every such node's NmStationAddress.
/// Two nodes declaring one NmStationAddress: an error (J1939-81 lets one node hold an
/// address; can-rx gives each addressed node its own DM1 slots). A node sending with an
/// address another node holds, by other PGNs: a warning (exact-ID receivers still tell
/// the frames apart; a DM1, request or acknowledgement from that address does not).
void checkSourceAddresses(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::size_t b,
                          std::vector<Error>& out) {
  const config::BusConfig& bus = vehicle.buses[b];
  const auto& messages = vehicle.database.messages;
  std::map<std::uint32_t, std::vector<AddressUse>> uses;
  std::set<std::string> nodesOnBus;
  const auto use = [&](std::uint32_t address, AddressUse entry) {
    if (address >= FIRST_NON_NODE_ADDRESS) return;
    nodesOnBus.insert(entry.node);
    uses[address].push_back(std::move(entry));
  };
  const std::string scheduleFile = vehicle.scheduleFile.empty() ? vehicle.path : vehicle.scheduleFile;
  for (const std::size_t m : bus.messages) {
    const dbc::Message& message = messages[m];
    if (!message.isJ1939() || message.transmitter == dbc::NO_NODE || message.transmitter.empty()) continue;
    if (config::sentBy(message, vehicle.node)) {
      const schedule::ScheduledMessage* entry = files.schedule ? files.schedule->find(m) : nullptr;
      if (entry == nullptr) continue;  // not sent
      use(entry->canId & 0xFFu,
          AddressUse{vehicle.node, "message " + message.name + " " + hexId(entry->canId, true),
                     Location::json(scheduleFile, config::JsonChecker::join("/messages", message.name))});
      continue;
    }
    use(message.id & 0xFFu, AddressUse{message.transmitter, "message " + message.name + " " + hexId(message.id, true),
                                       messageLocation(vehicle, message)});
  }
  for (const dbc::Node& node : vehicle.database.nodes) {
    if (!nodesOnBus.contains(node.name)) continue;
    if (const auto address = explicitAddress(node)) {
      use(*address, AddressUse{node.name, "NmStationAddress", nodeLocation(vehicle), true});
    }
  }
  for (const auto& [address, list] : uses) {
    // the nodes in first-use order, each with what it uses the address for
    std::vector<std::string> nodes;
    std::map<std::string, std::vector<const AddressUse*>> byNode;
    std::size_t stations = 0;
    for (const AddressUse& entry : list) {
      if (!byNode.contains(entry.node)) nodes.push_back(entry.node);
      byNode[entry.node].push_back(&entry);
      stations += entry.station ? 1 : 0;
    }
    if (nodes.size() < 2) continue;
    const bool error = stations >= 2;
    std::string text = "bus '" + bus.name + "': J1939 source address " + hexByte(address) + " is used by " +
                       std::to_string(nodes.size()) + " nodes: ";
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      const auto& entries = byNode[nodes[i]];
      text += (i == 0 ? "" : "; ") + nodes[i] + " (" + entries.front()->how;
      if (entries.size() > 1) text += " and " + std::to_string(entries.size() - 1) + " more";
      text += ")";
    }
    text += error ? ". Two nodes declare it as their NmStationAddress: J1939-81 lets one node hold an address, and "
                    "can-rx keeps one DM1 per address"
                  : ". J1939-81 lets one node hold an address: exact identifiers still tell these frames apart, a "
                    "DM1, request or acknowledgement from the address does not";
    const AddressUse& second = *byNode[nodes[1]].front();
    out.push_back(Error{std::move(text), second.where, error ? Severity::Error : Severity::Warning});
  }
}

/// Identifiers that collide on bus `b`: two DBC messages with one ID (error); a scheduled ID
/// (after the schedule's source and destination) equal to another DBC message's (error); J1939 messages with one PGN,
/// destination and source from two nodes (error) or from one node, differing only by
/// priority (warning; the VCU's own pairs are left to can-tx's safety-identity warnings).
void checkIdentifiers(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::size_t b,
                      std::vector<Error>& out) {
  const config::BusConfig& bus = vehicle.buses[b];
  const auto& messages = vehicle.database.messages;
  // Exact identifiers of the bus' DBC messages: the DBC only warns about a repeated ID (it
  // may belong to another bus); on one bus every frame decodes as the first message.
  std::map<std::pair<bool, std::uint32_t>, std::size_t> byId;
  for (const std::size_t m : bus.messages) {
    const dbc::Message& message = messages[m];
    const auto [it, inserted] = byId.emplace(std::pair{message.extended, message.id}, m);
    if (inserted) continue;
    out.push_back(Error{"bus '" + bus.name + "': " + message.name + " (" + message.transmitter +
                            ") has the identifier " + hexId(message.id, message.extended) + " of " +
                            messages[it->second].name + " (" + messages[it->second].transmitter +
                            "): every such frame decodes as " + messages[it->second].name +
                            "; put them on different buses or correct the ID",
                        messageLocation(vehicle, message)});
  }
  if (files.schedule) {
    for (const schedule::ScheduledMessage& entry : files.schedule->messages) {
      if (entry.bus != b) continue;
      const auto it = byId.find(std::pair{entry.extended, entry.canId});
      if (it == byId.end() || it->second == entry.message) continue;
      const dbc::Message& other = messages[it->second];
      out.push_back(Error{"bus '" + bus.name + "': " + messages[entry.message].name + " goes out as " +
                              hexId(entry.canId, entry.extended) + ", the identifier of " + other.name + " (sent by " +
                              other.transmitter + "): receivers would decode one as the other",
                          Location::json(vehicle.scheduleFile.empty() ? vehicle.path : vehicle.scheduleFile,
                                         config::JsonChecker::join("/messages", messages[entry.message].name))});
    }
  }
  // J1939 messages equal but for the priority: PGN, destination and source.
  std::map<std::uint64_t, std::size_t> byIdentity;
  for (const std::size_t m : bus.messages) {
    const dbc::Message& message = messages[m];
    if (!message.isJ1939()) continue;
    const j1939::Id id = j1939::Id::fromCanId(message.id);
    const std::uint64_t identity = (static_cast<std::uint64_t>(id.pgn()) << 16) |
                                   (static_cast<std::uint64_t>(id.destination()) << 8) | id.sourceAddress;
    const auto [it, inserted] = byIdentity.emplace(identity, m);
    if (inserted) continue;
    const dbc::Message& first = messages[it->second];
    if (first.id == message.id) continue;  // the same identifier: reported above
    const bool sameNode = first.transmitter == message.transmitter;
    // The VCU's own pairs are can-tx's (schedule::safetyIdentityWarnings, logged at its start).
    if (sameNode && config::sentBy(message, vehicle.node)) continue;
    std::string text = "bus '" + bus.name + "': " + first.name + " (" + hexId(first.id, true) + ", " +
                       first.transmitter + ") and " + message.name + " (" + hexId(message.id, true) + ", " +
                       message.transmitter + ") have the same PGN, destination and source address";
    text += sameNode ? " and differ only by priority: a J1939 receiver that matches by PGN takes one for the other"
                     : ": two nodes send frames no receiver can tell apart by their address";
    out.push_back(
        Error{std::move(text), messageLocation(vehicle, message), sameNode ? Severity::Warning : Severity::Error});
  }
}

}  // namespace

void checkAddresses(const config::VehicleConfig& vehicle, const VehicleFiles& files, std::vector<Error>& out) {
  for (std::size_t b = 0; b < vehicle.buses.size(); ++b) {
    checkSourceAddresses(vehicle, files, b, out);
    checkIdentifiers(vehicle, files, b, out);
  }
}

}  // namespace openvcu::check
