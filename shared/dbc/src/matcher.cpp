#include "openvcu/dbc/matcher.hpp"

namespace openvcu::dbc {

MessageMatcher::MessageMatcher(const Database& database, MatchMode mode)
    : m_exact(database.messages.size()), m_mode(mode) {
  const bool j1939 = mode != MatchMode::Exact;
  if (j1939) m_byKey = detail::FlatMap<std::uint32_t, PgnEntry, ~std::uint32_t{0}>(database.messages.size());
  for (std::size_t i = 0; i < database.messages.size(); ++i) {
    const Message& msg = database.messages[i];
    if (msg.pseudo) continue;
    const auto index = static_cast<std::int32_t>(i);
    m_exact.insert((static_cast<std::uint64_t>(msg.extended) << 32) | msg.id, index);  // first in file order wins
    if (!j1939 || !msg.extended) continue;
    // Same key as match(): ID bits 8..25, the PGN (PDU2) or PGN + destination (PDU1).
    PgnEntry& entry = m_byKey.insert((msg.id >> 8) & 0x3FFFFu, PgnEntry{});
    if (entry.exactIndex == NO_MATCH) {
      entry.exactIndex = index;
      entry.exactId = msg.id;
    } else if (entry.exactIndex != SEVERAL && entry.exactId != msg.id) {
      entry.exactIndex = SEVERAL;  // another source address or priority: the exact table decides
    }
    const bool candidate = mode == MatchMode::J1939 || msg.isJ1939();
    if (candidate && entry.byPgn == NO_MATCH) entry.byPgn = index;  // first in file order wins
  }
}

}  // namespace openvcu::dbc
