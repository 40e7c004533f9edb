#include "openvcu/dbc/matcher.hpp"

#include "openvcu/j1939/id.hpp"

namespace openvcu::dbc {

namespace {
std::uint32_t pgnKey(std::uint32_t pgn, std::uint8_t destination) { return (pgn << 8) | destination; }
}  // namespace

MessageMatcher::MessageMatcher(const Database& database, MatchMode mode) : m_mode(mode) {
  for (std::size_t i = 0; i < database.messages.size(); ++i) {
    const Message& msg = database.messages[i];
    if (msg.pseudo) continue;
    const auto index = static_cast<std::int32_t>(i);
    m_exact.emplace((static_cast<std::uint64_t>(msg.extended) << 32) | msg.id, index);
    const bool candidate = msg.extended && (mode == MatchMode::J1939 || (mode == MatchMode::J1939Tagged && msg.isJ1939()));
    if (!candidate) continue;
    const auto id = j1939::Id::fromCanId(msg.id);
    m_byPgn.emplace(pgnKey(id.pgn(), id.destination()), index);  // first in file order wins
  }
}

std::int32_t MessageMatcher::match(std::uint32_t id, bool extended) const noexcept {
  if (const auto it = m_exact.find((static_cast<std::uint64_t>(extended) << 32) | id); it != m_exact.end()) {
    return it->second;
  }
  if (m_mode == MatchMode::Exact || !extended) return NO_MATCH;
  const auto fields = j1939::Id::fromCanId(id);
  const std::uint32_t pgn = fields.pgn();
  if (const auto it = m_byPgn.find(pgnKey(pgn, fields.destination())); it != m_byPgn.end()) return it->second;
  if (fields.isPdu1() && fields.destination() != j1939::GLOBAL_ADDRESS) {
    if (const auto it = m_byPgn.find(pgnKey(pgn, j1939::GLOBAL_ADDRESS)); it != m_byPgn.end()) return it->second;
  }
  return NO_MATCH;
}

}  // namespace openvcu::dbc
