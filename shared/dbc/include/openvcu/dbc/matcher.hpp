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

#include "openvcu/dbc/model.hpp"

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace openvcu::dbc {

enum class MatchMode : std::uint8_t { Exact, J1939, J1939Tagged };

class MessageMatcher {
 public:
  static constexpr std::int32_t NO_MATCH = -1;

  MessageMatcher() = default;
  MessageMatcher(const Database& database, MatchMode mode);

  /// Index into Database::messages, or NO_MATCH. @note noexcept, allocation-free.
  [[nodiscard]] std::int32_t match(std::uint32_t id, bool extended) const noexcept;

 private:
  std::unordered_map<std::uint64_t, std::int32_t> m_exact;  ///< extended << 32 | id
  std::unordered_map<std::uint32_t, std::int32_t> m_byPgn;  ///< pgn << 8 | destination
  MatchMode m_mode{MatchMode::Exact};
};

}  // namespace openvcu::dbc
