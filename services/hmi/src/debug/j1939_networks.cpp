#include "debug/j1939_networks.hpp"

#include <algorithm>
#include <cstdio>

#include "openvcu/config/catalog.hpp"
#include "openvcu/j1939/dm1.hpp"

namespace openvcu::hmi {

DbcNodeNames dbcNodesByAddress(const dbc::Database& database) {
  DbcNodeNames names;
  for (const dbc::Node& node : database.nodes) {
    const auto address = config::nodeAddress(database, node);
    // 254 (0xFE, null: the DBC's default) and 255 (global) name no node
    if (address && *address < 0xFE && names[*address].empty()) names[*address] = node.name;
  }
  return names;
}

std::string j1939AddressText(std::uint8_t address) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "0x%02X (%u)", static_cast<unsigned>(address),
                static_cast<unsigned>(address));
  return text.data();
}

std::string j1939NameText(std::uint64_t name) {
  std::array<char, 24> text{};
  std::snprintf(text.data(), text.size(), "0x%016llX", static_cast<unsigned long long>(name));
  return text.data();
}

std::string j1939LampsText(std::uint8_t lamps) {
  const auto status = [lamps](int shift) {
    return std::string(j1939::lampStatusName(static_cast<j1939::LampStatus>((lamps >> shift) & 0x3u)));
  };
  return "protect " + status(0) + ", amber warning " + status(2) + ", red stop " + status(4) + ", malfunction " +
         status(6);
}

J1939Networks::J1939Networks(std::vector<std::string> expected, DbcNodeNames dbcNodes, std::int64_t staleAfterNs)
    : m_dbcNodes(std::move(dbcNodes)), m_staleAfterNs(staleAfterNs) {
  for (std::string& name : expected) {
    Bus bus;
    bus.name = std::move(name);
    m_buses.push_back(std::move(bus));
  }
}

void J1939Networks::onNetwork(const ipc::J1939Network& network, std::int64_t receivedMonoNs) {
  auto it = std::find_if(m_buses.begin(), m_buses.end(), [&](const Bus& bus) { return bus.name == network.bus; });
  if (it == m_buses.end()) {
    Bus bus;
    bus.name = network.bus;
    m_buses.push_back(std::move(bus));
    it = m_buses.end() - 1;
  }
  it->latest = network;
  it->receivedMonoNs = receivedMonoNs;
}

ValueStatus J1939Networks::statusOf(std::size_t index, std::int64_t nowNs) const noexcept {
  const Bus& bus = m_buses[index];
  if (bus.receivedMonoNs < 0) return ValueStatus::NotConnected;
  return nowNs - bus.receivedMonoNs > m_staleAfterNs ? ValueStatus::Stale : ValueStatus::Ready;
}

ValueStatus J1939Networks::overall(std::int64_t nowNs) const noexcept {
  std::size_t ready = 0;
  std::size_t heard = 0;
  for (std::size_t i = 0; i < m_buses.size(); ++i) {
    const ValueStatus status = statusOf(i, nowNs);
    if (status != ValueStatus::NotConnected) ++heard;
    if (status == ValueStatus::Ready) ++ready;
  }
  if (heard == 0) return ValueStatus::NotConnected;
  return ready == m_buses.size() ? ValueStatus::Ready : ValueStatus::Stale;
}

std::vector<J1939Row> J1939Networks::rows(std::int64_t nowNs) const {
  std::vector<J1939Row> rows;
  for (std::size_t i = 0; i < m_buses.size(); ++i) appendRows(rows, m_buses[i], statusOf(i, nowNs));
  return rows;
}

void J1939Networks::appendRows(std::vector<J1939Row>& rows, const Bus& bus, ValueStatus status) const {
  const auto row = [&](J1939Row::Kind kind) -> J1939Row& {
    J1939Row& added = rows.emplace_back();
    added.kind = kind;
    added.bus = bus.name;
    added.busStatus = status;
    return added;
  };
  const auto note = [&](std::string text) { row(J1939Row::Kind::Note).label = std::move(text); };
  const ipc::J1939Network& view = bus.latest;
  J1939Row& claim = row(J1939Row::Kind::Claim);
  if (bus.receivedMonoNs < 0) {
    claim.label = "not heard from vcu-can-tx yet";
    return;
  }
  claim.label = std::string(ipc::claimStateName(view.claimState));
  claim.alert = view.claimState == ipc::ClaimState::CannotClaim;
  if (view.claimState == ipc::ClaimState::Off) {
    claim.label += " (no address claim configured)";
  } else {
    claim.address = j1939AddressText(view.address);
    claim.name = j1939NameText(view.name);
  }
  if (view.nodes.empty()) {
    note("other nodes: none claimed an address");
  } else {
    note("other nodes (" + std::to_string(view.nodes.size()) + "): address, NAME, DBC node");
    for (const ipc::J1939Node& node : view.nodes) {
      J1939Row& added = row(J1939Row::Kind::Node);
      added.address = j1939AddressText(node.address);
      added.name = j1939NameText(node.name);
      added.label = m_dbcNodes[node.address];
    }
  }
  if (view.dtcs.empty()) {
    note("DTCs: none");
  } else {
    note("DTCs (" + std::to_string(view.dtcs.size()) + "): name, SPN, FMI, occurrences");
    for (const bool active : {true, false}) {
      for (const ipc::J1939Dtc& dtc : view.dtcs) {
        if (dtc.active != active) continue;
        J1939Row& added = row(J1939Row::Kind::Dtc);
        added.name = dtc.name;
        added.spn = dtc.spn;
        added.fmi = dtc.fmi;
        added.occurrences = dtc.occurrences;
        added.active = dtc.active;
        added.alert = dtc.active;
        added.label = dtc.active ? "active" : "previously active";
      }
    }
  }
  J1939Row& lamps = row(J1939Row::Kind::Lamps);
  lamps.label = "DM1 lamps: " + j1939LampsText(view.lamps);
  for (const int shift : {0, 2, 4, 6}) {
    if (static_cast<j1939::LampStatus>((view.lamps >> shift) & 0x3u) == j1939::LampStatus::On) lamps.alert = true;
  }
}

}  // namespace openvcu::hmi
