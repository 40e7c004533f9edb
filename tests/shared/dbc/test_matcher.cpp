// MessageMatcher: exact ID first, then the J1939 PGN rule (docs/design/j1939-matching.md).

#include "dbc_test_support.hpp"
#include "openvcu/dbc/matcher.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <string>
#include <vector>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {

constexpr bool EXTENDED = true;
constexpr bool STANDARD = false;

// DBC messages (IDs as written, flag bit 31 set).
constexpr std::uint32_t EEC1_FE = 0x18FEF1FEu;      // PDU2 PGN 0xFEF1 from SA 0xFE
constexpr std::uint32_t EEC1_00 = 0x18FEF100u;      // same PGN from SA 0x00, defined later
constexpr std::uint32_t PROPA_TO_21 = 0x18EF21FEu;  // PDU1 PGN 0xEF00 to DA 0x21
constexpr std::uint32_t PROPA_GLOBAL = 0x18EFFFFEu; // PDU1 PGN 0xEF00 to the global address
constexpr std::uint32_t TP_TO_21 = 0x1CEC21FEu;     // PDU1 PGN 0xEC00 to DA 0x21 only

std::string flagged(std::uint32_t id) { return std::to_string(id | 0x80000000u); }

/// The matching database, in this file order.
std::string matchingDbc() {
  return "BO_ 1809 Heartbeat: 8 Vcu\n"
         "BO_ " + flagged(EEC1_FE) + " EEC1: 8 Vcu\n"
         "BO_ " + flagged(PROPA_TO_21) + " PropA_To21: 8 Vcu\n"
         "BO_ " + flagged(PROPA_GLOBAL) + " PropA_Global: 8 Vcu\n"
         "BO_ " + flagged(EEC1_00) + " EEC1_Second: 8 Vcu\n"
         "BO_ " + flagged(TP_TO_21) + " Tp_To21: 8 Vcu\n"
         "BO_ 3221225472 VECTOR__INDEPENDENT_SIG_MSG: 0 Vector__XXX\n"
         " SG_ Orphan : 0|8@1+ (1,0) [0|255] \"\" Vector__XXX\n";
}

std::int32_t indexOf(const Database& db, std::string_view name) {
  const Message* message = db.findMessage(name);
  REQUIRE(message != nullptr);
  return static_cast<std::int32_t>(message - db.messages.data());
}

ParseOutput matchingDatabase() {
  ParseOutput parsed = parseText(matchingDbc());
  INFO(describe(parsed));
  REQUIRE_FALSE(parsed.hasErrors());
  return parsed;
}

}  // namespace

TEST_CASE("matcher finds a standard frame by its exact ID") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  CHECK(sut.match(1809, STANDARD) == indexOf(parsed.database, "Heartbeat"));
  CHECK(sut.match(1809, EXTENDED) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(1810, STANDARD) == MessageMatcher::NO_MATCH);
}

TEST_CASE("matcher prefers the exact ID over an earlier message with the same PGN") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  CHECK(sut.match(EEC1_00, EXTENDED) == indexOf(parsed.database, "EEC1_Second"));
  CHECK(sut.match(EEC1_FE, EXTENDED) == indexOf(parsed.database, "EEC1"));
}

TEST_CASE("matcher matches by PGN ignoring priority and source address") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);
  constexpr std::uint32_t OTHER_SOURCE = 0x18FEF117u;
  constexpr std::uint32_t OTHER_PRIORITY = 0x0CFEF1FEu;

  CHECK(sut.match(OTHER_SOURCE, EXTENDED) == indexOf(parsed.database, "EEC1"));
  CHECK(sut.match(OTHER_PRIORITY, EXTENDED) == indexOf(parsed.database, "EEC1"));
}

TEST_CASE("matcher takes the first message in file order among equal PGN candidates") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  CHECK(sut.match(0x18FEF1AAu, EXTENDED) == indexOf(parsed.database, "EEC1"));
}

TEST_CASE("matcher honours the PDU1 destination and falls back to the global definition") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  CHECK(sut.match(0x0CEF2133u, EXTENDED) == indexOf(parsed.database, "PropA_To21"));
  CHECK(sut.match(0x0CEF2233u, EXTENDED) == indexOf(parsed.database, "PropA_Global"));
  CHECK(sut.match(0x0CEFFF33u, EXTENDED) == indexOf(parsed.database, "PropA_Global"));
}

TEST_CASE("matcher never matches a PDU1 message defined for another destination") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  CHECK(sut.match(0x1CEC21F3u, EXTENDED) == indexOf(parsed.database, "Tp_To21"));
  CHECK(sut.match(0x1CEC22F3u, EXTENDED) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(0x1CECFFF3u, EXTENDED) == MessageMatcher::NO_MATCH);
}

TEST_CASE("matcher distinguishes PGNs that differ only in the data page") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);
  constexpr std::uint32_t DATA_PAGE_BIT = 1u << 24;

  CHECK(sut.match(EEC1_FE | DATA_PAGE_BIT, EXTENDED) == MessageMatcher::NO_MATCH);
}

TEST_CASE("matcher never PGN-matches a standard frame") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  CHECK(sut.match(EEC1_FE & 0x7FFu, STANDARD) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(0x0F1u, STANDARD) == MessageMatcher::NO_MATCH);
}

TEST_CASE("matcher never matches a pseudo message") {
  const ParseOutput parsed = parseText(matchingDbc() + "BO_ 1073741824 NotAFrame: 8 Vcu\n");
  const MessageMatcher exact(parsed.database, MatchMode::Exact);
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  for (const std::uint32_t id : {0u, 0x40000000u, 0xC0000000u}) {
    CAPTURE(id);
    CHECK(sut.match(id & 0x1FFFFFFFu, EXTENDED) == MessageMatcher::NO_MATCH);
    CHECK(sut.match(id & 0x7FFu, STANDARD) == MessageMatcher::NO_MATCH);
    CHECK(exact.match(id & 0x1FFFFFFFu, EXTENDED) == MessageMatcher::NO_MATCH);
  }
}

TEST_CASE("matcher in exact mode never matches by PGN") {
  const ParseOutput parsed = matchingDatabase();
  const MessageMatcher sut(parsed.database, MatchMode::Exact);

  CHECK(sut.match(EEC1_FE, EXTENDED) == indexOf(parsed.database, "EEC1"));
  CHECK(sut.match(0x18FEF117u, EXTENDED) == MessageMatcher::NO_MATCH);
}

TEST_CASE("matcher in J1939Tagged mode only PGN-matches messages whose VFrameFormat is J1939PG") {
  const ParseOutput parsed = parseText(matchingDbc() +
                                       "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\";\n"
                                       "BA_DEF_DEF_ \"VFrameFormat\" \"ExtendedCAN\";\n"
                                       "BA_ \"VFrameFormat\" BO_ " + flagged(EEC1_00) + " 3;\n");
  REQUIRE_FALSE(parsed.hasErrors());
  const MessageMatcher sut(parsed.database, MatchMode::J1939Tagged);

  // EEC1 (untagged) comes first in the file, but only EEC1_Second is a J1939 candidate.
  CHECK(sut.match(0x18FEF117u, EXTENDED) == indexOf(parsed.database, "EEC1_Second"));
  CHECK(sut.match(0x0CEF2133u, EXTENDED) == MessageMatcher::NO_MATCH);
  // Exact IDs still match whatever the tag.
  CHECK(sut.match(PROPA_TO_21, EXTENDED) == indexOf(parsed.database, "PropA_To21"));
}

TEST_CASE("matcher PGN-matches a message written with a 29-bit ID without the extended flag") {
  const ParseOutput parsed = parseText("BO_ " + std::to_string(0x18FEF1FEu) + " NoFlag: 8 Vcu\n");
  REQUIRE_FALSE(parsed.hasErrors());
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  CHECK(sut.match(0x18FEF100u, EXTENDED) == 0);
}

TEST_CASE("matcher matches the J1939 fixture's PropA_C3 to the VCU from any priority") {
  const ParseOutput parsed = parse(readFixture("j1939_hhea_vcu.dbc"), "j1939_hhea_vcu.dbc");
  REQUIRE_FALSE(parsed.hasErrors());
  const MessageMatcher sut(parsed.database, MatchMode::J1939Tagged);

  CHECK(sut.match(0x18EF21F3u, EXTENDED) == indexOf(parsed.database, "PropA_C3_PGN61184"));
  CHECK(sut.match(0x0CEF21F3u, EXTENDED) == indexOf(parsed.database, "PropA_C3_PGN61184"));
  CHECK(sut.match(0x0CEF22F3u, EXTENDED) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(1809, STANDARD) == indexOf(parsed.database, "VcuHeartbeat"));
}

TEST_CASE("a default-constructed matcher matches nothing") {
  const MessageMatcher sut;

  CHECK(sut.match(1809, STANDARD) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(EEC1_FE, EXTENDED) == MessageMatcher::NO_MATCH);
}

TEST_CASE("matcher finds each of hundreds of messages by exact ID and by PGN, and no unknown PGN (issue 27)") {
  // 256 PDU2 PGNs 0xFF00..0xFFFF and 64 PDU1 PGNs to the global address, all from SA 0xFE,
  // plus 64 standard IDs: enough keys for collisions and probe chains in the flat tables.
  constexpr std::uint32_t PDU2_COUNT = 256;
  constexpr std::uint32_t PDU1_COUNT = 64;
  constexpr std::uint32_t STANDARD_COUNT = 64;
  constexpr std::uint32_t OTHER_SOURCE = 0x17;
  std::string text;
  std::vector<std::uint32_t> extendedIds;
  for (std::uint32_t ps = 0; ps < PDU2_COUNT; ++ps) extendedIds.push_back(0x18FF00FEu | (ps << 8));
  for (std::uint32_t pf = 0; pf < PDU1_COUNT; ++pf) extendedIds.push_back(0x1800FFFEu | (pf << 16));
  for (std::size_t i = 0; i < extendedIds.size(); ++i) {
    text += "BO_ " + flagged(extendedIds[i]) + " Ext" + std::to_string(i) + ": 8 Vcu\n";
  }
  for (std::uint32_t id = 0; id < STANDARD_COUNT; ++id) {
    text += "BO_ " + std::to_string(0x100 + id) + " Std" + std::to_string(id) + ": 8 Vcu\n";
  }
  const ParseOutput parsed = parseText(text);
  INFO(describe(parsed));
  REQUIRE_FALSE(parsed.hasErrors());
  const MessageMatcher sut(parsed.database, MatchMode::J1939);

  for (std::size_t i = 0; i < extendedIds.size(); ++i) {
    CAPTURE(i);
    const auto expected = indexOf(parsed.database, "Ext" + std::to_string(i));
    CHECK(sut.match(extendedIds[i], EXTENDED) == expected);
    CHECK(sut.match((extendedIds[i] & ~0xFFu) | OTHER_SOURCE, EXTENDED) == expected);
  }
  for (std::uint32_t id = 0; id < STANDARD_COUNT; ++id) {
    CHECK(sut.match(0x100 + id, STANDARD) == indexOf(parsed.database, "Std" + std::to_string(id)));
  }
  // PDU1 to a specific destination falls back to the global definition.
  CHECK(sut.match(0x18052133u, EXTENDED) == indexOf(parsed.database, "Ext" + std::to_string(PDU2_COUNT + 5)));
  // PGNs not in the file: PF 0xFE (PDU2), PF 0x40 (PDU1), the other data page.
  CHECK(sut.match(0x18FE0017u, EXTENDED) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(0x1840FF17u, EXTENDED) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(0x19FF0017u, EXTENDED) == MessageMatcher::NO_MATCH);
  CHECK(sut.match(0x100 + STANDARD_COUNT, STANDARD) == MessageMatcher::NO_MATCH);
}
