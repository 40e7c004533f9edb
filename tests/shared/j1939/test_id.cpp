#include "openvcu/j1939/id.hpp"

#include <doctest/doctest.h>

#include <cstdint>

using openvcu::j1939::GLOBAL_ADDRESS;
using openvcu::j1939::Id;
using openvcu::j1939::pgnOf;

namespace {

constexpr std::uint32_t S1_ES_ID = 0x0CEFF321;  // VCU -> VIC, PDU1, PGN 0xEF00
constexpr std::uint32_t CCVS1_ID = 0x18FEF121;  // VCU broadcast, PDU2, PGN 0xFEF1 (65265)
constexpr std::uint32_t VIC_REQUEST_ID = 0x00EA21F3;
constexpr std::uint8_t VCU_ADDRESS = 0x21;
constexpr std::uint8_t VIC_ADDRESS = 0xF3;

}  // namespace

TEST_CASE("a PDU1 identifier splits into priority, PF, destination and source") {
  const Id sut = Id::fromCanId(S1_ES_ID);

  CHECK(sut.priority == 3);
  CHECK_FALSE(sut.extendedDataPage);
  CHECK_FALSE(sut.dataPage);
  CHECK(sut.pduFormat == 0xEF);
  CHECK(sut.pduSpecific == VIC_ADDRESS);
  CHECK(sut.sourceAddress == VCU_ADDRESS);
  CHECK(sut.isPdu1());
  CHECK(sut.pgn() == 0xEF00u);
  CHECK(sut.destination() == VIC_ADDRESS);
  CHECK(sut.toCanId() == S1_ES_ID);
}

TEST_CASE("a PDU2 identifier keeps the group extension in its PGN and goes to everyone") {
  const Id sut = Id::fromCanId(CCVS1_ID);

  CHECK(sut.priority == 6);
  CHECK_FALSE(sut.isPdu1());
  CHECK(sut.pgn() == 65265u);
  CHECK(sut.destination() == GLOBAL_ADDRESS);
  CHECK(sut.toCanId() == CCVS1_ID);
}

TEST_CASE("extended data page and data page are the top two PGN bits") {
  constexpr std::uint32_t PDU1_BOTH_PAGES_ID = 0x0F123456;  // 3 << 26 | EDP | DP | 12 34 56
  constexpr std::uint32_t PDU2_DATA_PAGE_ID = 0x19FECA21;   // 6 << 26 | DP | FE CA 21

  const Id pdu1 = Id::fromCanId(PDU1_BOTH_PAGES_ID);
  const Id pdu2 = Id::fromCanId(PDU2_DATA_PAGE_ID);

  CHECK(pdu1.extendedDataPage);
  CHECK(pdu1.dataPage);
  CHECK(pdu1.pgn() == 0x31200u);  // EDP 0x20000 | DP 0x10000 | PF 0x12 << 8, PS is the DA
  CHECK(pdu1.destination() == 0x34);
  CHECK_FALSE(pdu2.extendedDataPage);
  CHECK(pdu2.dataPage);
  CHECK(pdu2.pgn() == 0x1FECAu);
  CHECK(Id::fromPgn(0x31200u, 3, 0x56, 0x34).toCanId() == PDU1_BOTH_PAGES_ID);
  CHECK(Id::fromPgn(0x1FECAu, 6, 0x21).toCanId() == PDU2_DATA_PAGE_ID);
}

TEST_CASE("composing from a PDU2 PGN ignores the destination") {
  const Id sut = Id::fromPgn(65265u, 6, VCU_ADDRESS, VIC_ADDRESS);

  CHECK(sut.toCanId() == CCVS1_ID);
  CHECK(sut.destination() == GLOBAL_ADDRESS);
}

TEST_CASE("the VIC's request decomposes into PGN 0xEA00 from the VIC to the VCU at priority 0") {
  const Id sut = Id::fromCanId(VIC_REQUEST_ID);

  CHECK(sut.priority == 0);
  CHECK(sut.pgn() == 0xEA00u);
  CHECK(sut.destination() == VCU_ADDRESS);
  CHECK(sut.sourceAddress == VIC_ADDRESS);
  CHECK(pgnOf(VIC_REQUEST_ID) == 0xEA00u);
}

TEST_CASE("every 29-bit identifier survives decomposition and composition") {
  constexpr std::uint32_t EXTENDED_ID_MASK = 0x1FFFFFFF;
  constexpr int SAMPLES = 100'000;
  std::uint32_t state = 0x12345678;  // linear congruential generator, fixed seed
  int mismatches = 0;

  for (int i = 0; i < SAMPLES; ++i) {
    state = state * 1'664'525u + 1'013'904'223u;
    const std::uint32_t canId = state & EXTENDED_ID_MASK;
    const Id sut = Id::fromCanId(canId);
    const Id recomposed = Id::fromPgn(sut.pgn(), sut.priority, sut.sourceAddress, sut.pduSpecific);
    if (sut.toCanId() != canId || recomposed != sut) ++mismatches;
  }

  CHECK(mismatches == 0);
}
