#include "openvcu/j1939/safety.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <vector>

using namespace openvcu::j1939;

// Failure messages name the result ("CrcMismatch") instead of "{?}".
template <>
struct doctest::StringMaker<SafetyResult> {
  static doctest::String convert(SafetyResult result) {
    const std::string_view name = safetyResultName(result);
    return {name.data(), static_cast<doctest::String::size_type>(name.size())};
  }
};

namespace {

// Thesis Figures 6.11 and 6.13: S1_ES_PGN61427 with Control_Es_Relay = 3.
constexpr std::uint32_t THESIS_SDM_ID = 0x0CEFF321;
constexpr std::uint32_t THESIS_SHM_ID = 0x0C0EF321;
constexpr SafetyPayload THESIS_SDM_DATA{0xEF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
constexpr std::uint8_t THESIS_SEQUENCE = 15;
constexpr SafetyPayload THESIS_SHM_DATA{0x7F, 0xDE, 0x0C, 0x10, 0xA3, 0xEF, 0x00, 0x81};
constexpr std::uint32_t THESIS_CRC = 0x8100EFA3;

// The second public example (not from the thesis).
constexpr std::uint32_t PUBLIC_SDM_ID = 0x0C010305;
constexpr std::uint32_t PUBLIC_SHM_ID = 0x0C0E0305;
constexpr SafetyPayload PUBLIC_SDM_DATA{0xFF, 0xFF, 0x7D, 0xFF, 0xFF, 0x3F, 0x3F, 0xFF};
constexpr std::uint8_t PUBLIC_SEQUENCE = 1;
constexpr SafetyPayload PUBLIC_SHM_DATA{0x0F, 0xFA, 0xFC, 0xFE, 0xF2, 0xD9, 0x94, 0x97};
constexpr std::uint32_t PUBLIC_CRC = 0x9794D9F2;

constexpr std::array<std::uint8_t, 8> COUNTING_BYTES{0x00, 0x01, 0x02, 0x03,
                                                     0x04, 0x05, 0x06, 0x07};
constexpr std::uint32_t COUNTING_CRC = 0xC550537D;

constexpr std::int64_t MILLISECOND_NS = 1'000'000;
constexpr std::int64_t CYCLE_NS = 20 * MILLISECOND_NS;  // S1_ES_PGN61427 period
constexpr std::int64_t HEADER_TO_DATA_NS = 292'000;     // the original's smallest delta
constexpr std::int64_t SRVT_NS = 5 * MILLISECOND_NS;
constexpr std::int64_t SCT_NS = 2 * CYCLE_NS;
constexpr SafetyPairConfig CHECKER_CONFIG{THESIS_SDM_ID, SRVT_NS, SCT_NS};

// Bit-by-bit reference: shift each data bit into the register MSB first.
std::uint32_t naiveCrc(std::span<const std::uint8_t> data) {
  std::uint32_t reg = 0xFFFFFFFF;
  for (const std::uint8_t byte : data) {
    for (int bit = 7; bit >= 0; --bit) {
      const bool feedback = (((reg >> 31) ^ (static_cast<std::uint32_t>(byte) >> bit)) & 1u) != 0;
      reg <<= 1;
      if (feedback) reg ^= 0x6938392D;
    }
  }
  return reg;
}

// A sender running at CYCLE_NS: SHM, then the SDM HEADER_TO_DATA_NS later.
struct Sender {
  SafetyPairBuilder builder{THESIS_SDM_ID};
  std::int64_t nowNs{};

  SafetyResult sendTo(SafetyPairChecker& checker, const SafetyPayload& data = THESIS_SDM_DATA) {
    return sendHeader(checker, builder.nextHeader(data), data);
  }
  SafetyResult sendHeader(SafetyPairChecker& checker, const SafetyPayload& header,
                          const SafetyPayload& data = THESIS_SDM_DATA) {
    nowNs += CYCLE_NS;
    checker.onHeader(header, nowNs);
    return checker.onData(data, nowNs + HEADER_TO_DATA_NS);
  }
};

// A checker that has already seen two good pairs.
void synchronise(SafetyPairChecker& checker, Sender& sender) {
  REQUIRE(sender.sendTo(checker) == SafetyResult::Synchronising);
  REQUIRE(sender.sendTo(checker) == SafetyResult::Ok);
}

/// A checker with CHECKER_CONFIG and a sender whose first pair has synchronised it.
struct SynchronisedChecker {
  SafetyPairChecker sut{CHECKER_CONFIG};
  Sender sender;

  SynchronisedChecker() { synchronise(sut, sender); }
};

}  // namespace

TEST_CASE("CRC-32 of J1939-76 matches the three known answers") {
  CHECK(crc32J1939_76(THESIS_SDM_DATA) == THESIS_CRC);
  CHECK(crc32J1939_76(PUBLIC_SDM_DATA) == PUBLIC_CRC);
  CHECK(crc32J1939_76(COUNTING_BYTES) == COUNTING_CRC);
}

TEST_CASE("table-driven CRC equals the bit-by-bit reference on pseudo-random data") {
  constexpr int SAMPLES = 2'000;
  constexpr std::size_t MAX_LENGTH = 16;
  std::uint32_t state = 0xC0FFEE;
  std::vector<std::uint8_t> data;
  int mismatches = 0;

  for (int i = 0; i < SAMPLES; ++i) {
    data.resize(static_cast<std::size_t>(i) % (MAX_LENGTH + 1));
    for (auto& byte : data) {
      state = state * 1'664'525u + 1'013'904'223u;
      byte = static_cast<std::uint8_t>(state >> 24);
    }
    if (crc32J1939_76(data) != naiveCrc(data)) ++mismatches;
  }

  CHECK(mismatches == 0);
}

TEST_CASE("safety header of the thesis example matches the trace") {
  const SafetyPayload sut = buildSafetyHeader(THESIS_SDM_ID, THESIS_SDM_DATA, THESIS_SEQUENCE);

  CHECK(sut == THESIS_SHM_DATA);
  CHECK(safetyHeaderCanId(THESIS_SDM_ID) == THESIS_SHM_ID);
}

TEST_CASE("safety header of the second public example matches its reference") {
  const SafetyPayload sut = buildSafetyHeader(PUBLIC_SDM_ID, PUBLIC_SDM_DATA, PUBLIC_SEQUENCE);

  CHECK(sut == PUBLIC_SHM_DATA);
  CHECK(safetyHeaderCanId(PUBLIC_SDM_ID) == PUBLIC_SHM_ID);
}

TEST_CASE("safety header carries the inverted data page bits of the SDM") {
  constexpr std::uint32_t BOTH_PAGES_SDM_ID = 0x0F12F321;  // EDP = 1, DP = 1, PF 0x12
  constexpr std::uint8_t SEQUENCE = 2;
  constexpr std::uint8_t EXPECTED_FIRST_BYTE = (SEQUENCE << 3) | 0x04;  // both inverted bits 0

  const SafetyPayload sut = buildSafetyHeader(BOTH_PAGES_SDM_ID, THESIS_SDM_DATA, SEQUENCE);
  const std::optional<SafetyHeader> maybeParsed = parseSafetyHeader(sut);

  CHECK(sut[0] == EXPECTED_FIRST_BYTE);
  REQUIRE(maybeParsed);
  CHECK(maybeParsed->sdmExtendedDataPage);
  CHECK(maybeParsed->sdmDataPage);
  CHECK(maybeParsed->matchesData(BOTH_PAGES_SDM_ID));
  CHECK_FALSE(maybeParsed->matchesData(THESIS_SDM_ID));
}

TEST_CASE("safety header of a broadcast SDM goes to the global address") {
  constexpr std::uint32_t CCVS1_ID = 0x18FEF121;
  constexpr std::uint32_t EXPECTED_SHM_ID = 0x180EFF21;  // PGN 0x0E00 to DA 0xFF from 0x21

  CHECK(safetyHeaderCanId(CCVS1_ID) == EXPECTED_SHM_ID);
}

TEST_CASE("parsing the thesis safety header recovers the SDM identity, sequence and CRC") {
  const std::optional<SafetyHeader> maybeSut = parseSafetyHeader(THESIS_SHM_DATA);

  REQUIRE(maybeSut);
  CHECK(maybeSut->sequence == THESIS_SEQUENCE);
  CHECK_FALSE(maybeSut->sdmExtendedDataPage);
  CHECK_FALSE(maybeSut->sdmDataPage);
  CHECK(maybeSut->sdmSourceAddress == 0x21);
  CHECK(maybeSut->sdmPduSpecific == 0xF3);
  CHECK(maybeSut->sdmPduFormat == 0xEF);
  CHECK(maybeSut->sdmCrc == THESIS_CRC);
  CHECK(maybeSut->matchesData(THESIS_SDM_ID));
}

TEST_CASE("parsing a safety header that is not 8 bytes gives nothing") {
  const std::array<std::uint8_t, 7> shortHeader{0x7F, 0xDE, 0x0C, 0x10, 0xA3, 0xEF, 0x00};

  CHECK_FALSE(parseSafetyHeader(shortHeader));
  CHECK_FALSE(parseSafetyHeader({}));
}

TEST_CASE("pair builder numbers its headers and wraps from 31 to 0") {
  constexpr std::uint8_t LAST_SEQUENCE = SAFETY_SEQUENCE_MODULO - 1;
  SafetyPairBuilder sut{THESIS_SDM_ID, LAST_SEQUENCE};

  const SafetyPayload last = sut.nextHeader(THESIS_SDM_DATA);
  const SafetyPayload wrapped = sut.nextHeader(THESIS_SDM_DATA);

  CHECK((last[0] >> 3) == LAST_SEQUENCE);
  CHECK((wrapped[0] >> 3) == 0);
  CHECK(sut.sequence() == 1);
  CHECK(sut.headerCanId() == THESIS_SHM_ID);
  CHECK(sut.dataCanId() == THESIS_SDM_ID);
}

TEST_CASE("pair builder at sequence 15 reproduces the thesis trace") {
  SafetyPairBuilder sut{THESIS_SDM_ID, THESIS_SEQUENCE};

  CHECK(sut.nextHeader(THESIS_SDM_DATA) == THESIS_SHM_DATA);
  CHECK(sut.sequence() == THESIS_SEQUENCE + 1);
}

TEST_CASE("checker synchronises on the first good pair and accepts the next one") {
  SafetyPairChecker sut{CHECKER_CONFIG};
  Sender sender;

  CHECK(sut.headerCanId() == THESIS_SHM_ID);
  CHECK(sender.sendTo(sut) == SafetyResult::Synchronising);
  CHECK(sender.sendTo(sut) == SafetyResult::Ok);
  CHECK(sender.sendTo(sut) == SafetyResult::Ok);
  CHECK(sut.count(SafetyResult::Synchronising) == 1);
  CHECK(sut.count(SafetyResult::Ok) == 2);
}

TEST_CASE("checker accepts the thesis pair as a reference with any sequence number") {
  SafetyPairChecker sut{CHECKER_CONFIG};

  sut.onHeader(THESIS_SHM_DATA, 0);

  CHECK(sut.onData(THESIS_SDM_DATA, HEADER_TO_DATA_NS) == SafetyResult::Synchronising);
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reports a CRC mismatch when one data bit flips") {
  const SafetyPayload header = sender.builder.nextHeader(THESIS_SDM_DATA);
  SafetyPayload corrupted = THESIS_SDM_DATA;
  corrupted[3] ^= 0x10;

  CHECK(sender.sendHeader(sut, header, corrupted) == SafetyResult::CrcMismatch);
  CHECK(sut.count(SafetyResult::CrcMismatch) == 1);
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reports a sequence error when a pair is skipped") {
  (void)sender.builder.nextHeader(THESIS_SDM_DATA);  // this pair is lost on the bus

  CHECK(sender.sendTo(sut) == SafetyResult::SequenceError);
  CHECK(sut.count(SafetyResult::SequenceError) == 1);
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reports a repetition when the same sequence number comes twice") {
  const SafetyPayload header = sender.builder.nextHeader(THESIS_SDM_DATA);

  CHECK(sender.sendHeader(sut, header) == SafetyResult::Ok);
  CHECK(sender.sendHeader(sut, header) == SafetyResult::Repetition);
  CHECK(sut.count(SafetyResult::Repetition) == 1);
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker measures the SDM against the SRVT from its header") {
  const std::int64_t headerNs = sender.nowNs + CYCLE_NS;

  sut.onHeader(sender.builder.nextHeader(THESIS_SDM_DATA), headerNs);

  SUBCASE("checker reports a timeout when the SDM comes later than the SRVT") {
    CHECK(sut.onData(THESIS_SDM_DATA, headerNs + SRVT_NS + 1) == SafetyResult::Timeout);
    CHECK(sut.count(SafetyResult::Timeout) == 1);
  }
  SUBCASE("checker accepts an SDM exactly at the SRVT") {
    CHECK(sut.onData(THESIS_SDM_DATA, headerNs + SRVT_NS) == SafetyResult::Ok);
  }
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reports a missing header when an SDM comes without an SHM") {
  CHECK(sut.onData(THESIS_SDM_DATA, sender.nowNs + CYCLE_NS) == SafetyResult::MissingHeader);
  CHECK(sut.count(SafetyResult::MissingHeader) == 1);
}

TEST_CASE("checker reports a missing header when an SDM comes before its SHM") {
  SafetyPairChecker sut{CHECKER_CONFIG};

  CHECK(sut.onData(THESIS_SDM_DATA, 0) == SafetyResult::MissingHeader);
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reports a cycle timeout when an SHM comes later than the SCT") {
  sender.nowNs += SCT_NS;  // the next SHM comes SCT + one cycle after the previous one

  CHECK(sender.sendTo(sut) == SafetyResult::CycleTimeout);
  CHECK(sut.count(SafetyResult::CycleTimeout) == 1);
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reports a header mismatch when the inverted source address is wrong") {
  SafetyPayload header = sender.builder.nextHeader(THESIS_SDM_DATA);
  header[1] = 0xFF;  // the original's defect: FF instead of ~SA

  CHECK(sender.sendHeader(sut, header) == SafetyResult::HeaderMismatch);
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reports a header mismatch when the data page bit is wrong") {
  SafetyPayload header = sender.builder.nextHeader(THESIS_SDM_DATA);
  header[0] &= 0xFE;  // claims DP = 1

  CHECK(sender.sendHeader(sut, header) == SafetyResult::HeaderMismatch);
}

TEST_CASE("checker reports a bad length for a short SHM and for a short SDM") {
  SafetyPairChecker sut{CHECKER_CONFIG};
  const SafetyPayload header = buildSafetyHeader(THESIS_SDM_ID, THESIS_SDM_DATA, 0);
  const std::span<const std::uint8_t> shortHeader{header.data(), 7};
  const std::span<const std::uint8_t> shortData{THESIS_SDM_DATA.data(), 7};

  sut.onHeader(shortHeader, 0);
  CHECK(sut.onData(THESIS_SDM_DATA, HEADER_TO_DATA_NS) == SafetyResult::BadLength);
  sut.onHeader(header, CYCLE_NS);
  CHECK(sut.onData(shortData, CYCLE_NS + HEADER_TO_DATA_NS) == SafetyResult::BadLength);
  CHECK(sut.count(SafetyResult::BadLength) == 2);
}

TEST_CASE("checker accepts the sequence wrapping from 31 to 0") {
  SafetyPairChecker sut{CHECKER_CONFIG};
  Sender sender;
  sender.builder = SafetyPairBuilder{THESIS_SDM_ID, SAFETY_SEQUENCE_MODULO - 2};

  CHECK(sender.sendTo(sut) == SafetyResult::Synchronising);  // 30
  CHECK(sender.sendTo(sut) == SafetyResult::Ok);             // 31
  CHECK(sender.sendTo(sut) == SafetyResult::Ok);             // 0
  CHECK(sender.sendTo(sut) == SafetyResult::Ok);             // 1
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker recovers from a fault on the second consecutive good pair") {
  (void)sender.builder.nextHeader(THESIS_SDM_DATA);

  CHECK(sender.sendTo(sut) == SafetyResult::SequenceError);
  CHECK(sender.sendTo(sut) == SafetyResult::Synchronising);
  CHECK(sender.sendTo(sut) == SafetyResult::Ok);
}

TEST_CASE("checker counts an SHM replaced before its SDM came as dropped") {
  SafetyPairChecker sut{CHECKER_CONFIG};
  const SafetyPayload first = buildSafetyHeader(THESIS_SDM_ID, THESIS_SDM_DATA, 0);
  const SafetyPayload second = buildSafetyHeader(THESIS_SDM_ID, THESIS_SDM_DATA, 1);

  sut.onHeader(first, 0);
  sut.onHeader(second, CYCLE_NS);

  CHECK(sut.droppedHeaders() == 1);
  CHECK(sut.onData(THESIS_SDM_DATA, CYCLE_NS + HEADER_TO_DATA_NS) == SafetyResult::Synchronising);
}

TEST_CASE("checker says the header is overdue before the first SHM and after the SCT") {
  SafetyPairChecker sut{CHECKER_CONFIG};
  constexpr std::int64_t HEADER_NS = 1'000 * MILLISECOND_NS;

  CHECK(sut.headerOverdue(0));
  sut.onHeader(THESIS_SHM_DATA, HEADER_NS);
  CHECK_FALSE(sut.headerOverdue(HEADER_NS + SCT_NS));
  CHECK(sut.headerOverdue(HEADER_NS + SCT_NS + 1));
}

TEST_CASE_FIXTURE(SynchronisedChecker, "checker reset forgets the reference but keeps the counters") {
  sut.reset();

  CHECK(sender.sendTo(sut) == SafetyResult::Synchronising);
  CHECK(sut.count(SafetyResult::Ok) == 1);
}

TEST_CASE("every safety result has a name") {
  for (std::size_t i = 0; i < SAFETY_RESULT_COUNT; ++i) {
    CHECK(safetyResultName(static_cast<SafetyResult>(i)) != "Unknown");
  }
  CHECK(safetyResultName(SafetyResult::CrcMismatch) == "CrcMismatch");
}

TEST_CASE("sameSafetyIdentity: identifiers equal but for the priority are one SDM to a receiver (issue 18)") {
  constexpr std::uint32_t PROPA_C4 = 0x18EFF321;  // HHEA: S1_ES's PGN, SA and DA at priority 6
  CHECK(sameSafetyIdentity(THESIS_SDM_ID, PROPA_C4));
  for (std::uint32_t priority = 0; priority < 8; ++priority) {
    CHECK(sameSafetyIdentity(THESIS_SDM_ID, (THESIS_SDM_ID & SAFETY_IDENTITY_MASK) | priority << 26));
  }
  // every other identifier bit (EDP, DP, PF, PS = DA, SA) tells them apart
  for (int bit = 0; bit < 26; ++bit) {
    CHECK_FALSE(sameSafetyIdentity(THESIS_SDM_ID, THESIS_SDM_ID ^ (1u << bit)));
  }
  CHECK_FALSE(sameSafetyIdentity(THESIS_SDM_ID, THESIS_SHM_ID));
}
