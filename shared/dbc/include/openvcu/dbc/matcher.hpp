#pragma once
// Matching a received frame to a DBC message.
//
// Rule (docs/design/j1939-matching.md):
//   1. exact: the frame's (ID, extended) equals a message's; pseudo messages never match.
//   2. J1939 (extended frames only, in J1939 mode): the frame's PGN equals a candidate
//      message's PGN, priority and source address ignored. For PDU1 PGNs the destination
//      counts: a message defined for the frame's destination wins, else one defined for
//      the global address 0xFF; a message defined for another destination never matches.
//      Among equal candidates the first in file order wins.
//   Candidates in J1939 mode: MatchMode::J1939 takes every extended message;
//   MatchMode::J1939Tagged only those whose VFrameFormat resolves to J1939PG.
//
//   0x18FEF100 against BO_ 2566844926 (0x18FEF1FE) -> exact miss, PGN 0xFEF1 -> match
//   0x18EF03F3 against a message 0x18EFFFFE (PDU1, DA 0xFF) -> match (global definition)
//   0x18EF03F3 against a message 0x18EF21FE (PDU1, DA 0x21) only -> no match
//
// Layout: two flat open-addressing tables built in the constructor (power-of-two capacity
// of at least 4x the entries, multiplicative hash, linear probing, keys and values in two
// arrays). The J1939 table is keyed by ID bits 8..25 (EDP, DP, PF, PS: the PGN for PDU2,
// PGN + destination for PDU1) and also remembers the one extended message with that key, so
// an extended frame costs one probe; the exact table is probed only for standard frames, in
// Exact mode, or when several extended messages share a key (same PGN, other source address).

#include "openvcu/dbc/model.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace openvcu::dbc {

enum class MatchMode : std::uint8_t { Exact, J1939, J1939Tagged };

namespace detail {

/// Insert-only open-addressing map for the matcher: `EMPTY` marks a free slot, so it is
/// never a key. Built once; find() is noexcept, allocation-free and loops at most until the
/// first free slot (the table is at most a quarter full).
template <typename Key, typename Value, Key EMPTY>
class FlatMap {
 public:
  FlatMap() = default;
  /// Room for `count` keys at a load factor of at most 1/4.
  explicit FlatMap(std::size_t count) {
    std::size_t capacity = 8;
    unsigned bits = 3;
    while (capacity < 4 * count) {
      capacity *= 2;
      ++bits;
    }
    m_keys.assign(capacity, EMPTY);
    m_values.resize(capacity);
    m_shift = 64 - bits;
  }
  /// Inserts key -> value unless the key is present; returns the stored value.
  Value& insert(Key key, const Value& value) {
    std::size_t slot = home(key);
    while (m_keys[slot] != key && m_keys[slot] != EMPTY) slot = (slot + 1) & (m_keys.size() - 1);
    if (m_keys[slot] == EMPTY) {
      m_keys[slot] = key;
      m_values[slot] = value;
    }
    return m_values[slot];
  }
  [[nodiscard]] const Value* find(Key key) const noexcept {
    if (m_keys.empty() || key == EMPTY) return nullptr;
    const std::size_t mask = m_keys.size() - 1;
    for (std::size_t slot = home(key);; slot = (slot + 1) & mask) {
      const Key stored = m_keys[slot];
      if (stored == key) return &m_values[slot];
      if (stored == EMPTY) return nullptr;
    }
  }

 private:
  /// Fibonacci hashing: the top bits of key * 2^64/phi spread consecutive IDs and PGNs.
  [[nodiscard]] std::size_t home(Key key) const noexcept {
    return static_cast<std::size_t>((static_cast<std::uint64_t>(key) * 0x9E3779B97F4A7C15ull) >> m_shift);
  }

  std::vector<Key> m_keys;
  std::vector<Value> m_values;
  unsigned m_shift{63};
};

}  // namespace detail

class MessageMatcher {
 public:
  static constexpr std::int32_t NO_MATCH = -1;

  MessageMatcher() = default;
  MessageMatcher(const Database& database, MatchMode mode);

  /// Index into Database::messages, or NO_MATCH.
  /// @note noexcept, allocation-free, const (safe to share between threads); inline because
  ///       it runs once per received frame.
  [[nodiscard]] std::int32_t match(std::uint32_t id, bool extended) const noexcept;

 private:
  static constexpr std::int32_t SEVERAL = -2;  ///< PgnEntry::exactIndex: probe the exact table

  /// What the J1939 table holds for one key (ID bits 8..25).
  struct PgnEntry {
    std::int32_t byPgn{NO_MATCH};       ///< first candidate in file order with this key
    std::int32_t exactIndex{NO_MATCH};  ///< the one extended message with this key, or SEVERAL
    std::uint32_t exactId{};            ///< its ID when exactIndex >= 0
  };

  /// (extended << 32 | id) -> message; bit 63 is never set in a key.
  detail::FlatMap<std::uint64_t, std::int32_t, ~std::uint64_t{0}> m_exact;
  /// ID bits 8..25 (< 2^18) -> PgnEntry, every extended non-pseudo message (J1939 modes).
  detail::FlatMap<std::uint32_t, PgnEntry, ~std::uint32_t{0}> m_byKey;
  MatchMode m_mode{MatchMode::Exact};
};

// ---------------------------------------------------------------- inline hot path

inline std::int32_t MessageMatcher::match(std::uint32_t id, bool extended) const noexcept {
  if (!extended || m_mode == MatchMode::Exact) {
    const std::int32_t* exact = m_exact.find((static_cast<std::uint64_t>(extended) << 32) | id);
    return exact != nullptr ? *exact : NO_MATCH;
  }
  // J1939-21: bits 25..8 are EDP, DP, PF, PS; PF < 0xF0 (240) is PDU1 with PS the destination.
  const std::uint32_t key = (id >> 8) & 0x3FFFFu;
  if (const PgnEntry* entry = m_byKey.find(key); entry != nullptr) {
    if (entry->exactIndex >= 0 && entry->exactId == id) return entry->exactIndex;
    if (entry->exactIndex == SEVERAL) {
      if (const std::int32_t* exact = m_exact.find((std::uint64_t{1} << 32) | id); exact != nullptr) return *exact;
    }
    if (entry->byPgn != NO_MATCH) return entry->byPgn;
  }
  const bool pdu1 = ((key >> 8) & 0xFFu) < 0xF0u;
  if (pdu1 && (key & 0xFFu) != 0xFFu) {  // PDU1 to a specific destination: the global definition
    if (const PgnEntry* global = m_byKey.find(key | 0xFFu); global != nullptr) return global->byPgn;
  }
  return NO_MATCH;
}

}  // namespace openvcu::dbc
