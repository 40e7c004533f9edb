#pragma once
// J1939-81 address claims seen on one bus, as the receive path needs them:
//   - the VCU's own address follows its own claims (Address Claimed frames carrying its
//     NAME, sent by vcu-can-tx and seen on the bus like any other node's), so requests and
//     TP sessions to a newly claimed address are answered;
//   - a node that claims a new address keeps its identity: frames from its new address are
//     matched and decoded as if they came from its home address (the address its NAME first
//     claimed; for the VCU its configured address). The DBC names nodes by address, the bus
//     by NAME: this map joins the two.
//
//   AddressMap map(ownName, 0x21);
//   map.onAddressClaimed(0x71, claimPayload);  // the HVLP inverter at home: 0x71 -> 0x71
//   map.onAddressClaimed(0x90, claimPayload);  // ... it moved: frames from 0x90 decode as 0x71
//   map.homeAddress(0x90) == 0x71
//
// Decision: a NAME's home is the first address it was seen claiming. An ECU that starts on
// an address other than its DBC one is therefore decoded by that address (the DBC carries
// no NAMEs to do better; docs/design/j1939-network.md).

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace openvcu::canrx {

/// @note restricted thread-safe: one thread. noexcept and allocation-free after construction.
class AddressMap {
 public:
  /// `ownName`: the VCU's NAME on this bus (empty: it claims no address here);
  /// `ownAddress`: its configured (preferred) address, the home of its NAME.
  AddressMap(std::optional<std::uint64_t> ownName, std::uint8_t ownAddress) noexcept;

  /// One Address Claimed frame (PGN 0xEE00) from `source` (0xFE: Cannot Claim). Payloads
  /// shorter than the 8-byte NAME are ignored. true when the VCU's own address changed.
  bool onAddressClaimed(std::uint8_t source, std::span<const std::uint8_t> payload) noexcept;

  /// The address frames from `source` are decoded as: the home of the NAME that claimed
  /// `source` last, else `source` itself.
  [[nodiscard]] std::uint8_t homeAddress(std::uint8_t source) const noexcept { return m_home[source]; }
  /// The VCU's address now: its configured one until it is seen claiming, then the last
  /// claimed one; 0xFE (null) after it sent Cannot Claim.
  [[nodiscard]] std::uint8_t ownAddress() const noexcept { return m_ownAddress; }
  /// NAMEs seen claiming on this bus.
  [[nodiscard]] std::size_t knownNames() const noexcept { return m_count; }

 private:
  static constexpr std::uint8_t NONE = 0xFE;  ///< J1939-81 null address 0xfe (254)
  struct Entry {
    std::uint64_t name{};
    std::uint8_t home{};
    std::uint8_t current{NONE};
  };
  Entry* find(std::uint64_t name) noexcept;
  void release(Entry& entry) noexcept;

  std::array<std::uint8_t, 256> m_home{};  ///< source address -> home address (identity by default)
  std::array<Entry, 254> m_entries{};      ///< one per NAME seen, in order of appearance
  std::size_t m_count{};
  std::optional<std::uint64_t> m_ownName;
  std::uint8_t m_ownConfigured{};
  std::uint8_t m_ownAddress{};
};

}  // namespace openvcu::canrx
