#pragma once
// The other nodes of one J1939 bus as their Address Claimed messages (J1939-81) show them:
// address <-> NAME, one NAME per address and one address per NAME.
//
//   onClaim(0x80, A)   -> 0x80: A
//   onClaim(0x81, A)   -> 0x81: A          (A moved; 0x80 is free again)
//   onClaim(0x81, B)   -> 0x81: B          (B took the address; A is gone from the table)
//   onClaim(0xFE, B)   -> empty            (B sent Cannot Claim: it has no address)

#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/name.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace openvcu::j1939 {

inline constexpr std::size_t ADDRESS_COUNT = 256;  ///< 0..255, of which 0..253 can be claimed
inline constexpr std::uint8_t MAX_CLAIMABLE_ADDRESS = 0xFD;  ///< 253: 254 is null, 255 global

/// One known node.
struct AddressEntry {
  std::uint8_t address{NULL_ADDRESS};
  Name name;
  std::int64_t claimedNs{};  ///< when its latest claim was seen
};

/// A fixed map of 256 addresses; nothing is allocated.
/// @note not thread-safe: one thread owns a table. Real-time safe: noexcept; onClaim() and
///       addressOf() are O(254) (a scan for the NAME), nameAt() is O(1).
class AddressTable {
  struct Slot {
    bool known{};
    Name name;
    std::int64_t claimedNs{};  ///< when its latest claim was seen
  };

 public:
  /// What an Address Claimed frame from `address` with `name` says: the NAME now holds
  /// `address` (leaving the address it held before, and taking the address from whoever held
  /// it). From NULL_ADDRESS (Cannot Claim) the NAME is removed. Returns false, changing
  /// nothing, for the global address 0xFF (255), which nobody can claim.
  bool onClaim(std::uint8_t address, const Name& name, std::int64_t nowNs) noexcept {
    if (address == GLOBAL_ADDRESS) return false;
    if (const std::optional<std::uint8_t> previous = addressOf(name)) remove(*previous);
    if (address == NULL_ADDRESS) return true;
    Slot& slot = m_slots[address];
    if (!slot.known) ++m_size;
    slot = Slot{true, name, nowNs};
    return true;
  }

  /// Forgets the node at `address` (nothing when none is known there).
  void remove(std::uint8_t address) noexcept {
    Slot& slot = m_slots[address];
    if (!slot.known) return;
    slot = Slot{};
    --m_size;
  }

  void clear() noexcept {
    m_slots = {};
    m_size = 0;
  }

  /// The NAME claimed at `address`, or empty.
  [[nodiscard]] std::optional<Name> nameAt(std::uint8_t address) const noexcept {
    const Slot& slot = m_slots[address];
    if (!slot.known) return std::nullopt;
    return slot.name;
  }

  /// The address `name` holds, or empty.
  [[nodiscard]] std::optional<std::uint8_t> addressOf(const Name& name) const noexcept {
    if (m_size == 0) return std::nullopt;
    for (std::size_t address = 0; address <= MAX_CLAIMABLE_ADDRESS; ++address) {
      const Slot& slot = m_slots[address];
      if (slot.known && slot.name == name) return static_cast<std::uint8_t>(address);
    }
    return std::nullopt;
  }

  [[nodiscard]] bool taken(std::uint8_t address) const noexcept { return m_slots[address].known; }
  /// Nodes known.
  [[nodiscard]] std::size_t size() const noexcept { return m_size; }
  [[nodiscard]] bool empty() const noexcept { return m_size == 0; }

  /// Iterates over the known entries in address order; skips free addresses.
  class Iterator {
   public:
    AddressEntry operator*() const noexcept {
      const Slot& slot = (*m_slots)[m_index];
      return AddressEntry{static_cast<std::uint8_t>(m_index), slot.name, slot.claimedNs};
    }
    Iterator& operator++() noexcept {
      ++m_index;
      skipFree();
      return *this;
    }
    friend bool operator==(const Iterator& a, const Iterator& b) noexcept { return a.m_index == b.m_index; }

   private:
    friend class AddressTable;
    Iterator(const std::array<Slot, ADDRESS_COUNT>* slots, std::size_t index) noexcept
        : m_slots(slots), m_index(index) {
      skipFree();
    }
    void skipFree() noexcept {
      while (m_index < ADDRESS_COUNT && !(*m_slots)[m_index].known) ++m_index;
    }
    const std::array<Slot, ADDRESS_COUNT>* m_slots;
    std::size_t m_index;
  };

  [[nodiscard]] Iterator begin() const noexcept { return Iterator(&m_slots, 0); }
  [[nodiscard]] Iterator end() const noexcept { return Iterator(&m_slots, ADDRESS_COUNT); }

 private:
  std::array<Slot, ADDRESS_COUNT> m_slots{};
  std::size_t m_size{};
};

}  // namespace openvcu::j1939
