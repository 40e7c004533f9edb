// Wire time and bus load: exact bit counts checked against an independent oracle (the
// whole frame built as a bit vector, CRC by polynomial long division, stuffing by looking
// back at the stuffed output), the table-driven classic count against the bit-by-bit
// reference (detail::referenceWireBits) on 200,000 frames, hand-checked anchors, CAN FD
// field rules, the load meter.

#include <doctest/doctest.h>

#include <chrono>
#include <cstdint>
#include <random>
#include <vector>

#include "openvcu/can/wire_bits_reference.hpp"
#include "openvcu/can/wire_time.hpp"

using namespace openvcu::can;

namespace {

using Bits = std::vector<int>;

constexpr std::uint32_t BITRATE_500K = 500000;
constexpr std::uint32_t DATA_BITRATE_2M = 2000000;
constexpr std::int64_t NS_PER_BIT_500K = 2000;
constexpr std::int64_t NS_PER_BIT_2M = 500;
/// CRC delimiter, ACK slot, ACK delimiter, EOF (7), intermission (3).
constexpr std::size_t TRAILER_BITS = 13;

// ---- the oracle ------------------------------------------------------------------------

void appendBits(Bits& bits, std::uint32_t value, int width) {
  for (int i = width - 1; i >= 0; --i) bits.push_back(static_cast<int>((value >> i) & 1u));
}

/// Remainder of message * x^15 divided by the CAN generator
/// x^15+x^14+x^10+x^8+x^7+x^4+x^3+1 (0xC599 with its top term), by long division.
std::uint16_t crc15ByDivision(const Bits& message) {
  Bits work = message;
  work.resize(message.size() + 15, 0);
  Bits generator;
  appendBits(generator, 0xC599, 16);
  for (std::size_t i = 0; i < message.size(); ++i) {
    if (work[i] == 0) continue;
    for (std::size_t j = 0; j < generator.size(); ++j) work[i + j] ^= generator[j];
  }
  std::uint16_t crc = 0;
  for (std::size_t i = message.size(); i < work.size(); ++i) crc = static_cast<std::uint16_t>((crc << 1) | work[i]);
  return crc;
}

/// The bits as sent: a complement follows whenever the last five bits sent are equal.
/// `lastIsStuff` tells whether the final bit is such a stuff bit; `markIndex` (an index
/// into `bits`) is mapped to its index in the output.
Bits stuffed(const Bits& bits, bool& lastIsStuff, std::size_t markIndex, std::size_t& markOut) {
  Bits out;
  lastIsStuff = false;
  for (std::size_t i = 0; i < bits.size(); ++i) {
    out.push_back(bits[i]);
    if (i == markIndex) markOut = out.size() - 1;
    lastIsStuff = false;
    const std::size_t n = out.size();
    if (n >= 5 && out[n - 1] == out[n - 2] && out[n - 2] == out[n - 3] && out[n - 3] == out[n - 4] &&
        out[n - 4] == out[n - 5]) {
      out.push_back(1 - out[n - 1]);
      lastIsStuff = true;
    }
  }
  return out;
}

Bits identifierBits(const Frame& frame) {
  Bits bits{0};  // SOF
  if (frame.extended()) {
    appendBits(bits, frame.id >> 18, 11);
    bits.push_back(1);  // SRR
    bits.push_back(1);  // IDE
    appendBits(bits, frame.id & 0x3FFFF, 18);
  } else {
    appendBits(bits, frame.id, 11);
  }
  return bits;
}

struct OracleResult {
  std::size_t nominal{};
  std::size_t data{};
  std::size_t stuff{};
  std::uint16_t crc{};
};

OracleResult classicOracle(const Frame& frame) {
  const bool remote = (frame.flags & FLAG_RTR) != 0;
  Bits bits = identifierBits(frame);
  bits.push_back(remote ? 1 : 0);  // RTR
  bits.push_back(0);               // IDE or r1
  bits.push_back(0);               // r0
  appendBits(bits, frame.length, 4);
  if (!remote) {
    for (std::size_t i = 0; i < frame.length; ++i) appendBits(bits, frame.data[i], 8);
  }
  OracleResult result;
  result.crc = crc15ByDivision(bits);
  appendBits(bits, result.crc, 15);
  bool lastIsStuff = false;
  std::size_t unused = 0;
  const Bits sent = stuffed(bits, lastIsStuff, bits.size(), unused);
  result.stuff = sent.size() - bits.size();
  result.nominal = sent.size() + TRAILER_BITS;
  return result;
}

OracleResult fdOracle(const Frame& frame) {
  const bool brs = (frame.flags & FLAG_BRS) != 0;
  std::uint8_t dlc = 0;
  while (dlcToLength(dlc) < frame.length) ++dlc;
  Bits bits = identifierBits(frame);
  bits.push_back(0);                         // RRS
  if (!frame.extended()) bits.push_back(0);  // IDE
  bits.push_back(1);                         // FDF
  bits.push_back(0);                         // res
  bits.push_back(brs ? 1 : 0);
  const std::size_t brsIndex = bits.size() - 1;
  bits.push_back((frame.flags & FLAG_ESI) != 0 ? 1 : 0);
  appendBits(bits, dlc, 4);
  for (std::size_t i = 0; i < dlcToLength(dlc); ++i) appendBits(bits, i < frame.length ? frame.data[i] : 0, 8);
  bool lastIsStuff = false;
  std::size_t brsOut = 0;
  Bits sent = stuffed(bits, lastIsStuff, brsIndex, brsOut);
  if (lastIsStuff) sent.pop_back();  // the first fixed stuff bit takes its place
  // Stuff count (4) and CRC (17 up to 16 bytes, else 21), a fixed stuff bit before every
  // 4th of them starting with the first.
  const std::size_t fieldBits = 4 + (dlcToLength(dlc) <= 16 ? 17 : 21);
  std::size_t fixedStuff = 0;
  for (std::size_t i = 0; i < fieldBits; ++i) {
    if (i % 4 == 0) ++fixedStuff;
  }
  OracleResult result;
  result.stuff = sent.size() - bits.size() + fixedStuff;
  const std::size_t total = sent.size() + fieldBits + fixedStuff + TRAILER_BITS;
  if (brs) {
    result.nominal = brsOut + 1 + TRAILER_BITS;
    result.data = total - result.nominal;
  } else {
    result.nominal = total;
  }
  return result;
}

OracleResult oracle(const Frame& frame) {
  return frame.fd() ? fdOracle(frame) : classicOracle(frame);
}

// ---- frames ----------------------------------------------------------------------------

Frame makeFrame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes, std::uint8_t flags = 0) {
  Frame frame;
  frame.id = id;
  frame.flags = flags;
  for (const std::uint8_t byte : bytes) frame.data[frame.length++] = byte;
  return frame;
}

Frame repeated(std::uint32_t id, std::uint8_t byte, std::uint8_t length, std::uint8_t flags = 0) {
  Frame frame;
  frame.id = id;
  frame.flags = flags;
  frame.length = length;
  for (std::size_t i = 0; i < length; ++i) frame.data[i] = byte;
  return frame;
}

/// Random frames that stuff a lot: bytes are often 0x00 or 0xFF.
Frame randomFrame(std::mt19937& random, bool fd) {
  std::uniform_int_distribution<std::uint32_t> any(0, 0xFFFFFFFFu);
  Frame frame;
  const std::uint32_t choice = any(random);
  if ((choice & 1u) != 0) {
    frame.flags |= FLAG_EXTENDED;
    frame.id = any(random) & EXTENDED_ID_MASK;
  } else {
    frame.id = any(random) & STANDARD_ID_MASK;
  }
  if ((choice & 0x30u) == 0) frame.id = 0;  // all-dominant identifiers too
  if (fd) {
    frame.flags |= FLAG_FD;
    if ((choice & 2u) != 0) frame.flags |= FLAG_BRS;
    if ((choice & 4u) != 0) frame.flags |= FLAG_ESI;
    frame.length = dlcToLength(static_cast<std::uint8_t>(any(random) % 16));
  } else {
    frame.length = static_cast<std::uint8_t>(any(random) % 9);
    if ((choice & 8u) != 0) frame.flags |= FLAG_RTR;
  }
  for (std::size_t i = 0; i < frame.length; ++i) {
    const std::uint32_t kind = any(random) % 3;
    frame.data[i] = kind == 0 ? 0x00 : kind == 1 ? 0xFF : static_cast<std::uint8_t>(any(random));
  }
  return frame;
}

}  // namespace

TEST_CASE("the oracle's CRC-15 matches the published CRC-15/CAN check value") {
  // CRC RevEng catalogue, CRC-15/CAN (width 15, poly 0x4599, init 0, no reflection, no
  // xorout): the CRC of the ASCII bytes "123456789", most significant bit first, is 0x059E.
  constexpr std::uint16_t PUBLISHED_CHECK = 0x059E;
  Bits message;
  for (const char c : std::string("123456789")) appendBits(message, static_cast<std::uint8_t>(c), 8);

  CHECK(crc15ByDivision(message) == PUBLISHED_CHECK);
}

TEST_CASE("classic frame bit counts and CRCs equal the independent oracle's on random frames") {
  constexpr int FRAME_COUNT = 20000;
  std::mt19937 random(20240301);
  int mismatches = 0;
  for (int i = 0; i < FRAME_COUNT; ++i) {
    const Frame frame = randomFrame(random, false);
    const OracleResult expected = oracle(frame);
    const WireBits sut = wireBits(frame);
    const WireBits reference = detail::referenceWireBits(frame);
    if (sut.nominalBits != expected.nominal || sut.dataBits != 0 || sut.stuffBits != expected.stuff ||
        classicCrc15(frame) != expected.crc || frameBits(frame) != expected.nominal ||
        reference.nominalBits != expected.nominal || reference.stuffBits != expected.stuff ||
        detail::referenceClassicCrc15(frame) != expected.crc) {
      ++mismatches;
      INFO("id " << frame.id << " flags " << int(frame.flags) << " length " << int(frame.length));
      CHECK(sut.nominalBits == expected.nominal);
      CHECK(sut.stuffBits == expected.stuff);
      CHECK(classicCrc15(frame) == expected.crc);
    }
    if (mismatches > 5) break;
  }
  CHECK(mismatches == 0);
}

TEST_CASE("the table-driven count equals the bit-by-bit reference on random and stuffing-heavy frames") {
  std::mt19937 random(21);  // fixed seed: the same frames every run
  constexpr int FRAMES = 200'000;
  constexpr int ERROR_FRAME_EVERY = 50;
  int mismatches = 0;
  int crcMismatches = 0;
  for (int i = 0; i < FRAMES; ++i) {
    Frame frame;
    const std::uint32_t kind = random() % 8;
    frame.flags = (kind & 1u) != 0 ? FLAG_EXTENDED : 0;
    if (kind == 2) frame.flags |= FLAG_RTR;
    if (kind == 4) frame.flags |= FLAG_FD | FLAG_BRS;
    if (kind == 6 && i % ERROR_FRAME_EVERY == 0) frame.flags = FLAG_ERROR;
    frame.id = static_cast<std::uint32_t>(random()) & (frame.extended() ? EXTENDED_ID_MASK : STANDARD_ID_MASK);
    // Classic lengths up to 11: past 8 both count 8 bytes.
    frame.length = static_cast<std::uint8_t>(random() % ((frame.flags & FLAG_FD) != 0 ? 65 : 12));
    const std::uint32_t pattern = random() % 4;  // random bytes, all 0, all 1, runs
    for (std::size_t b = 0; b < MAX_DATA_LENGTH; ++b) {
      frame.data[b] = pattern == 0 ? static_cast<std::uint8_t>(random())
                      : pattern == 1 ? 0x00
                      : pattern == 2 ? 0xFF
                                     : static_cast<std::uint8_t>((b / 2) % 2 != 0 ? 0xF8 : 0x07);
    }
    if (pattern != 0) frame.id = (frame.extended() ? EXTENDED_ID_MASK : STANDARD_ID_MASK) & (pattern == 2 ? ~0u : 0u);
    if (!(wireBits(frame) == detail::referenceWireBits(frame))) {
      ++mismatches;
      if (mismatches <= 5) {
        INFO("id " << frame.id << " flags " << int(frame.flags) << " length " << int(frame.length));
        CHECK(wireBits(frame).nominalBits == detail::referenceWireBits(frame).nominalBits);
        CHECK(wireBits(frame).stuffBits == detail::referenceWireBits(frame).stuffBits);
      }
    }
    if (classicCrc15(frame) != detail::referenceClassicCrc15(frame)) ++crcMismatches;
  }
  CHECK(mismatches == 0);
  CHECK(crcMismatches == 0);
  const Frame known = repeated(0x555, 0xA5, 8);
  CHECK(detail::referenceWireBits(known) == WireBits{111, 0, 0});
  CHECK(wireBits(known) == WireBits{111, 0, 0});
}

TEST_CASE("CAN FD bit counts per phase equal the independent oracle's on random frames") {
  constexpr int FRAME_COUNT = 5000;
  std::mt19937 random(20240302);
  int mismatches = 0;
  for (int i = 0; i < FRAME_COUNT; ++i) {
    const Frame frame = randomFrame(random, true);
    const OracleResult expected = oracle(frame);
    const WireBits sut = wireBits(frame);
    if (sut.nominalBits != expected.nominal || sut.dataBits != expected.data || sut.stuffBits != expected.stuff) {
      ++mismatches;
      INFO("id " << frame.id << " flags " << int(frame.flags) << " length " << int(frame.length));
      CHECK(sut.nominalBits == expected.nominal);
      CHECK(sut.dataBits == expected.data);
      CHECK(sut.stuffBits == expected.stuff);
    }
    if (mismatches > 5) break;
  }
  CHECK(mismatches == 0);
}

TEST_CASE("a standard data frame without data has 47 bits plus at least one unavoidable stuff bit") {
  // 44 frame bits (SOF 1, ID 11, RTR 1, IDE 1, r0 1, DLC 4, CRC 15, CRC delimiter 1, ACK 2,
  // EOF 7) + 3 intermission = 47. RTR, IDE, r0 and DLC 0000 are 7 dominant bits in a row,
  // so every such frame has at least one stuff bit.
  constexpr std::uint32_t UNSTUFFED_BITS = 47;
  for (std::uint32_t id = 0; id <= STANDARD_ID_MASK; ++id) {
    const WireBits sut = wireBits(makeFrame(id, {}));
    REQUIRE(sut.nominalBits - sut.stuffBits == UNSTUFFED_BITS);
    REQUIRE(sut.stuffBits >= 1);
  }
  // ID 0x084: SOF+000 (4 dominant), 1, 0000, 1, 00 + RTR IDE r0 = 5 dominant -> stuff bit,
  // DLC 0000; CRC 0x51D0 = 101 0001 1101 0000 has no run of 5 with what precedes it.
  const Frame frame = makeFrame(0x084, {});
  CHECK(classicCrc15(frame) == 0x51D0);
  CHECK(frameBits(frame) == 48);
  CHECK(wireBits(frame).stuffBits == 1);
}

TEST_CASE("a standard frame with 8 data bytes and no stuff bits has 111 bits") {
  // 44 + 64 data bits = 108 frame bits + 3 intermission. 0x555 and A5 bytes alternate;
  // DLC 1000 after RTR IDE r0 gives at most 4 equal bits; the CRC does not stuff either.
  const Frame frame = repeated(0x555, 0xA5, 8);

  CHECK(oracle(frame).stuff == 0);
  CHECK(frameBits(frame) == 111);
  CHECK(wireBits(frame) == WireBits{111, 0, 0});
}

TEST_CASE("an all-zero standard frame with ID 0 and 8 bytes has 16 stuff bits, 127 bits in all") {
  // Bits before the CRC: 15 dominant (SOF, ID 0x000, RTR, IDE, r0) -> stuff bits after the
  // 5th, 10th and 15th (3); DLC 1000: the 1 joins the last stuff bit, then 000 + 64 data
  // zeros = 67 dominant -> 13 stuff bits (after every 5th), 2 left over. CRC 0x145B =
  // 001 0100 0101 1011: 2 + 2 leading zeros = 4, no further run of 5. 3 + 13 = 16.
  const Frame frame = repeated(0x000, 0x00, 8);

  CHECK(classicCrc15(frame) == 0x145B);
  CHECK(oracle(frame).crc == 0x145B);
  CHECK(wireBits(frame).stuffBits == 16);
  CHECK(frameBits(frame) == 111 + 16);
}

TEST_CASE("an extended frame with 8 data bytes has 131 bits without stuffing") {
  // 128 frame bits (SOF 1, ID 11, SRR 1, IDE 1, ID ext 18, RTR 1, r1 1, r0 1, DLC 4,
  // data 64, CRC 15, CRC delimiter 1, ACK 2, EOF 7) + 3 intermission.
  const Frame unstuffed = repeated(0x15555555, 0xAA, 8, FLAG_EXTENDED);
  CHECK(frameBits(unstuffed) == 131);
  CHECK(wireBits(unstuffed).stuffBits == 0);

  // A J1939 frame (PGN 65265 from SA 0x00) with 01..08: 12 stuff bits, the oracle agrees.
  const Frame j1939 = makeFrame(0x18FEF100, {1, 2, 3, 4, 5, 6, 7, 8}, FLAG_EXTENDED);
  CHECK(frameBits(j1939) == 131 + 12);
  CHECK(oracle(j1939).nominal == 131 + 12);
}

TEST_CASE("a remote frame has no data field whatever its DLC") {
  const Frame remote = repeated(0x555, 0x00, 8, FLAG_RTR);
  const WireBits sut = wireBits(remote);

  CHECK(sut.nominalBits - sut.stuffBits == 47);
  CHECK(sut.nominalBits == oracle(remote).nominal);
}

TEST_CASE("a CAN FD frame with BRS counts ESI through CRC at the data rate") {
  // 0x555, BRS, 8 bytes AA: no dynamic stuff bit. Nominal: SOF 1, ID 11, RRS 1, IDE 1,
  // FDF 1, res 1, BRS 1 = 17, + 13 trailer = 30. Data: ESI 1, DLC 4, data 64, stuff count
  // 4, CRC-17 17, 6 fixed stuff bits = 96.
  const Frame sut = repeated(0x555, 0xAA, 8, FLAG_FD | FLAG_BRS);
  CHECK(wireBits(sut) == WireBits{30, 96, 6});
  CHECK(frameBits(sut) == 126);
  CHECK(wireTimeNs(sut, BITRATE_500K, DATA_BITRATE_2M) == 30 * NS_PER_BIT_500K + 96 * NS_PER_BIT_2M);

  // 64 bytes of 0x55: CRC-21 with 7 fixed stuff bits: 1 + 4 + 512 + 4 + 21 + 7 = 549.
  const Frame longest = repeated(0x555, 0x55, 64, FLAG_FD | FLAG_BRS);
  CHECK(wireBits(longest) == WireBits{30, 549, 7});
}

TEST_CASE("a CAN FD frame without BRS sends every bit at the nominal rate") {
  const Frame sut = repeated(0x555, 0xAA, 8, FLAG_FD);

  CHECK(wireBits(sut) == WireBits{126, 0, 6});
  CHECK(wireTimeNs(sut, BITRATE_500K, DATA_BITRATE_2M) == 126 * NS_PER_BIT_500K);
}

TEST_CASE("a stuff bit owed after the last CAN FD data bit is replaced by the fixed stuff bit") {
  // ... 0x55 then 0xE0 = 1 1110 0000: five dominant bits end the data field. Classic
  // stuffing would add a bit there; CAN FD sends only the fixed stuff bit that starts the
  // CRC field, so the frame is as long as the same frame ending in 0xE1.
  const Frame owed = makeFrame(0x555, {0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0xE0}, FLAG_FD | FLAG_BRS);
  const Frame notOwed = makeFrame(0x555, {0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0x55, 0xE1}, FLAG_FD | FLAG_BRS);

  CHECK(wireBits(owed) == wireBits(notOwed));
  CHECK(wireBits(owed).stuffBits == 6);
}

TEST_CASE("a CAN FD length between DLC lengths is padded to the next one") {
  const Frame nineBytes = repeated(0x555, 0xAA, 9, FLAG_FD | FLAG_BRS);
  Frame twelveBytes = nineBytes;
  twelveBytes.length = 12;  // data[9..11] are 0 in both

  CHECK(wireBits(nineBytes) == wireBits(twelveBytes));
}

TEST_CASE("wire time is the bit count over the bit rate") {
  const Frame frame = repeated(0x555, 0xA5, 8);

  CHECK(wireTimeNs(frame, BITRATE_500K, DATA_BITRATE_2M) == 111 * NS_PER_BIT_500K);
  CHECK(wireTimeNs(frame, 1000000, 0) == 111 * 1000);
  CHECK(wireTimeNs(frame, 0, DATA_BITRATE_2M) == 0);
  CHECK(wireTimeNs(repeated(0x555, 0xAA, 8, FLAG_FD | FLAG_BRS), BITRATE_500K, 0) == 126 * NS_PER_BIT_500K);
}

TEST_CASE("an error frame counts as error flag, delimiter and intermission") {
  const Frame sut = makeFrame(0x4, {0, 4, 0, 0, 0, 0, 0, 0}, FLAG_ERROR);

  CHECK(wireBits(sut) == WireBits{ERROR_FRAME_BITS, 0, 0});
  CHECK(classicCrc15(sut) == 0);
}

TEST_CASE("4000 extended 8-byte frames per second at 500 kbit/s load the bus about 100 percent") {
  // 131 bits x 2 us = 262 us per frame, one every 250 us: 104.8 %. A real bus would
  // arbitrate (frames queue); the sim bus does not, and the meter reports the overload.
  constexpr int FRAMES = 4000;
  constexpr std::int64_t PERIOD_NS = 250'000;
  constexpr std::int64_t START_NS = 1'000'000'000;
  const Frame frame = repeated(0x15555555, 0xAA, 8, FLAG_EXTENDED);
  REQUIRE(frameBits(frame) == 131);
  BusLoadMeter sut(BITRATE_500K, DATA_BITRATE_2M);

  for (int i = 0; i < FRAMES; ++i) sut.add(frame, START_NS + i * PERIOD_NS);

  const std::int64_t nowNs = START_NS + 1'000'000'000 - 1;  // window 1.0 s .. 2.0 s - 1 ns
  const double expected = 100.0 * FRAMES * 131.0 * NS_PER_BIT_500K / (1'000'000'000.0 - 1.0);
  CHECK(sut.loadPercent(nowNs) == doctest::Approx(expected).epsilon(1e-9));
  CHECK(sut.loadPercent(nowNs) == doctest::Approx(104.8).epsilon(1e-6));
  CHECK(sut.framesPerSecond(nowNs) == doctest::Approx(4000.0).epsilon(1e-6));
  CHECK(sut.peakPercent() >= sut.loadPercent(nowNs));
  CHECK(sut.totalFrames() == FRAMES);

  // The same rate of J1939 frames (143 bits each with their 12 stuff bits): 114.4 %.
  BusLoadMeter j1939Meter(BITRATE_500K, DATA_BITRATE_2M);
  const Frame j1939 = makeFrame(0x18FEF100, {1, 2, 3, 4, 5, 6, 7, 8}, FLAG_EXTENDED);
  for (int i = 0; i < FRAMES; ++i) j1939Meter.add(j1939, START_NS + i * PERIOD_NS);
  CHECK(j1939Meter.loadPercent(nowNs) == doctest::Approx(114.4).epsilon(1e-6));
}

TEST_CASE("bus load falls to zero once the window has passed and old frames are ignored") {
  constexpr std::int64_t SECOND_NS = 1'000'000'000;
  const Frame frame = repeated(0x555, 0xA5, 8);  // 111 bits = 222 us at 500 kbit/s
  BusLoadMeter sut(BITRATE_500K, DATA_BITRATE_2M, std::chrono::milliseconds(1000));
  sut.add(frame, 5 * SECOND_NS);

  CHECK(sut.loadPercent(5 * SECOND_NS + SECOND_NS / 2) > 0.0);
  CHECK(sut.loadPercent(7 * SECOND_NS) == 0.0);
  CHECK(sut.framesPerSecond(7 * SECOND_NS) == 0.0);

  sut.add(frame, 9 * SECOND_NS);
  sut.add(frame, 8 * SECOND_NS);  // the ring slot now holds 9 s: ignored
  CHECK(sut.totalFrames() == 2);

  sut.reset();
  CHECK(sut.totalFrames() == 0);
  CHECK(sut.peakPercent() == 0.0);
  CHECK(sut.loadPercent(9 * SECOND_NS) == 0.0);
}

TEST_CASE("peak load remembers the busiest window") {
  constexpr std::int64_t SECOND_NS = 1'000'000'000;
  constexpr std::int64_t MILLISECOND_NS = 1'000'000;
  const Frame frame = repeated(0x555, 0xA5, 8);  // 222 us
  BusLoadMeter sut(BITRATE_500K, DATA_BITRATE_2M);
  for (int i = 0; i < 1000; ++i) sut.add(frame, SECOND_NS + i * MILLISECOND_NS);           // 22.2 %
  for (int i = 0; i < 100; ++i) sut.add(frame, 10 * SECOND_NS + i * 10 * MILLISECOND_NS);  // 2.22 %

  CHECK(sut.loadPercent(11 * SECOND_NS - 1) == doctest::Approx(2.22).epsilon(1e-3));
  CHECK(sut.peakPercent() == doctest::Approx(22.2).epsilon(1e-2));
}
