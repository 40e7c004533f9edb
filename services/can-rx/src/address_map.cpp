#include "address_map.hpp"

namespace openvcu::canrx {

namespace {
/// The 8-byte NAME of an Address Claimed payload, least significant byte first (J1939-81).
std::uint64_t nameOf(std::span<const std::uint8_t> payload) noexcept {
  std::uint64_t name = 0;
  for (std::size_t i = 0; i < 8; ++i) name |= static_cast<std::uint64_t>(payload[i]) << (8 * i);
  return name;
}
}  // namespace

AddressMap::AddressMap(std::optional<std::uint64_t> ownName, std::uint8_t ownAddress) noexcept
    : m_ownName(ownName), m_ownConfigured(ownAddress), m_ownAddress(ownAddress) {
  for (std::size_t i = 0; i < m_home.size(); ++i) m_home[i] = static_cast<std::uint8_t>(i);
}

AddressMap::Entry* AddressMap::find(std::uint64_t name) noexcept {
  for (std::size_t i = 0; i < m_count; ++i) {
    if (m_entries[i].name == name) return &m_entries[i];
  }
  return nullptr;
}

void AddressMap::release(Entry& entry) noexcept {
  if (entry.current == NONE) return;
  m_home[entry.current] = entry.current;
  entry.current = NONE;
}

bool AddressMap::onAddressClaimed(std::uint8_t source, std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() < 8) return false;
  const std::uint64_t name = nameOf(payload);
  const bool own = m_ownName && *m_ownName == name;
  const std::uint8_t ownBefore = m_ownAddress;
  Entry* entry = find(name);
  if (source >= NONE) {  // Cannot Claim (0xFE); 0xFF is no valid source either
    if (entry != nullptr) release(*entry);
    if (own) m_ownAddress = NONE;
    return m_ownAddress != ownBefore;
  }
  if (entry == nullptr) {
    if (m_count == m_entries.size()) return false;  // 254 NAMEs: every address is taken
    entry = &m_entries[m_count++];
    entry->name = name;
    entry->home = own ? m_ownConfigured : source;
  }
  // The NAME that held `source` before has lost it (J1939-81: it must move or stop).
  for (std::size_t i = 0; i < m_count; ++i) {
    if (&m_entries[i] != entry && m_entries[i].current == source) m_entries[i].current = NONE;
  }
  if (entry->current != source) release(*entry);
  entry->current = source;
  m_home[source] = entry->home;
  if (own) m_ownAddress = source;
  return m_ownAddress != ownBefore;
}

}  // namespace openvcu::canrx
