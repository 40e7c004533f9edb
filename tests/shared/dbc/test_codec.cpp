// MessageCodec against known values: byte orders (incl. the Motorola "sawtooth" start
// bit), sign extension, wide fields, floats, scaling, multiplexing, short frames,
// encoding and the initial payload (J1939 "not available" fill, GenSigStartValue).

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <array>
#include <climits>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

// ------------------------------------------------------------------ byte orders

TEST_CASE("codec decodes unsigned fields in both byte orders") {
  struct Row {
    const char* name;
    const char* signal;
    const char* payload;
    std::uint64_t expected;
  };
  const Row rows[] = {
      {"an Intel field LSB first", " SG_ A : 8|16@1+ (1,0) [0|0] \"\" Vcu\n", "00 34 12 00 00 00 00 00", 0x1234u},
      {"Motorola start 7 size 16 as bytes 0..1 big-endian", " SG_ A : 7|16@0+ (1,0) [0|0] \"\" Vcu\n",
       "12 34 FF FF FF FF FF FF", 0x1234u},
      // MSB is byte 1 bit 4: byte 1 bits 4..0 then byte 2 bits 7..1; the other bits are noise.
      {"Motorola start 12 size 12 across the sawtooth byte boundary", " SG_ A : 12|12@0+ (1,0) [0|0] \"\" Vcu\n",
       "FF F5 79 FF 00 00 00 00", 0xABCu},
      {"Intel start 12 size 12 from the high nibble up", " SG_ A : 12|12@1+ (1,0) [0|0] \"\" Vcu\n",
       "FF CF AB FF 00 00 00 00", 0xABCu},
      {"a Motorola signal ending in the last bit of the frame", " SG_ A : 51|12@0+ (1,0) [0|0] \"\" Vcu\n",
       "00 00 00 00 00 00 0A BC", 0xABCu},
  };
  for (const Row& row : rows) {
    SUBCASE(row.name) {
      const ParseOutput parsed = oneMessage(row.signal);
      const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

      CHECK(decodeOne(sut, hexBytes(row.payload), 0).rawUnsigned == row.expected);
    }
  }
}

// ------------------------------------------------------------------ signs and widths

TEST_CASE("codec sign-extends a big-endian 8-bit 0xFF to -1") {
  // Regression of the original program, which decoded this as -1793.
  const ParseOutput parsed = oneMessage(" SG_ A : 7|8@0- (1,0) [0|0] \"\" Vcu\n SG_ B : 15|12@0- (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  const auto visited = decodeAll(sut, hexBytes("FF FF F0 00 00 00 00 00"));

  const Visited* a = findVisited(visited, 0);
  const Visited* b = findVisited(visited, 1);
  REQUIRE(a != nullptr);
  REQUIRE(b != nullptr);
  CHECK(a->value.kind == RawKind::Signed);
  CHECK(a->value.rawSigned == -1);
  CHECK(a->value.physical == -1.0);
  CHECK(b->value.rawSigned == -1);
}

TEST_CASE("codec sign-extends the most negative value of a field") {
  const ParseOutput parsed = oneMessage(" SG_ A : 7|16@0- (1,0) [0|0] \"\" Vcu\n SG_ B : 16|4@1- (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  const auto visited = decodeAll(sut, hexBytes("80 00 08 00 00 00 00 00"));

  CHECK(visitedValue(visited, 0).rawSigned == -32768);
  CHECK(visitedValue(visited, 1).rawSigned == -8);
}

TEST_CASE("codec decodes 32-bit fields without 32-bit overflow") {
  const ParseOutput parsed =
      oneMessage(" SG_ U : 0|32@1+ (1,0) [0|0] \"\" Vcu\n SG_ S : 32|32@1- (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  const auto visited = decodeAll(sut, hexBytes("FF FF FF FF 00 00 00 80"));

  CHECK(visitedValue(visited, 0).rawUnsigned == 0xFFFFFFFFu);
  CHECK(visitedValue(visited, 0).physical == 4294967295.0);
  CHECK(visitedValue(visited, 1).rawSigned == -2147483648LL);
}

TEST_CASE("codec decodes 64-bit fields in both byte orders") {
  const ParseOutput parsed = oneMessage(
      " SG_ Intel : 0|64@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Motorola : 7|64@0+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Signed : 0|64@1- (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  const auto ordered = decodeAll(sut, hexBytes("01 02 03 04 05 06 07 08"));
  const auto ones = decodeAll(sut, hexBytes("FF FF FF FF FF FF FF FF"));

  REQUIRE(ordered.size() == 3);
  REQUIRE(ones.size() == 3);
  CHECK(visitedValue(ordered, 0).rawUnsigned == 0x0807060504030201ull);
  CHECK(visitedValue(ordered, 1).rawUnsigned == 0x0102030405060708ull);
  CHECK(visitedValue(ones, 0).rawUnsigned == 0xFFFFFFFFFFFFFFFFull);
  CHECK(visitedValue(ones, 0).physical == 18446744073709551615.0);
  CHECK(visitedValue(ones, 2).rawSigned == -1);
}

TEST_CASE("codec decodes an unaligned 64-bit field that spans nine bytes") {
  const ParseOutput parsed = oneMessage(
      " SG_ Intel : 4|64@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Motorola : 3|64@0+ (1,0) [0|0] \"\" Vcu\n", 9);
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  // Value 0x123456789ABCDEF0 placed 4 bits up (Intel) and 4 bits in (Motorola).
  const auto intel = decodeAll(sut, hexBytes("00 EF CD AB 89 67 45 23 01"));
  const auto motorola = decodeAll(sut, hexBytes("01 23 45 67 89 AB CD EF 00"));

  CHECK(visitedValue(intel, 0).rawUnsigned == 0x123456789ABCDEF0ull);
  CHECK(visitedValue(motorola, 1).rawUnsigned == 0x123456789ABCDEF0ull);
}

// ------------------------------------------------------------------ floats and scaling

TEST_CASE("codec decodes float32 and float64 signals") {
  const ParseOutput parsed = oneMessage(
      " SG_ F32 : 0|32@1+ (2,1) [0|0] \"\" Vcu\n"
      " SG_ F64 : 32|64@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ F32Be : 103|32@0+ (1,0) [0|0] \"\" Vcu\n",
      16, "SIG_VALTYPE_ 1 F32 : 1;\nSIG_VALTYPE_ 1 F64 : 2;\nSIG_VALTYPE_ 1 F32Be : 1;\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  const auto visited = decodeAll(sut, hexBytes("00 00 C0 3F 00 00 00 00 00 00 02 40 3F C0 00 00"));

  REQUIRE(visited.size() == 3);
  CHECK(visitedValue(visited, 0).kind == RawKind::Float32);
  CHECK(visitedValue(visited, 0).rawFloat == 1.5);
  CHECK(visitedValue(visited, 0).physical == 4.0);
  CHECK(visitedValue(visited, 1).kind == RawKind::Float64);
  CHECK(visitedValue(visited, 1).rawFloat == 2.25);
  CHECK(visitedValue(visited, 2).rawFloat == 1.5);
}

TEST_CASE("codec computes physical = raw * factor + offset in double without truncation") {
  const ParseOutput parsed = oneMessage(" SG_ T : 0|16@1+ (0.1,-40) [-40|6513.5] \"degC\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  constexpr std::uint64_t RAW = 123;

  const DecodedValue value = decodeOne(sut, hexBytes("7B 00 00 00 00 00 00 00"), 0);

  CHECK(value.rawUnsigned == RAW);
  CHECK(value.physical == static_cast<double>(RAW) * 0.1 + -40.0);
  CHECK(value.physical == doctest::Approx(-27.7));
}

// ------------------------------------------------------------------ multiplexing and short frames

TEST_CASE("codec visits only the active multiplexed signals, multiplexor first") {
  const ParseOutput parsed = parse(readFixture("multiplexing.dbc"), "multiplexing.dbc");
  REQUIRE_FALSE(parsed.hasErrors());
  const Message* muxed = parsed.database.findMessage("Muxed");
  REQUIRE(muxed != nullptr);
  const MessageCodec sut = MessageCodec::compile(parsed.database, *muxed);

  // Selector 2 -> SubSelector (m2M) = 5 -> SubValueB (4-6, 9-9); Always is always there.
  const auto visited = decodeAll(sut, hexBytes("02 05 77 00 00 00 00 99"));

  std::vector<std::string> names;
  for (const Visited& v : visited) names.push_back(muxed->signals[v.index].name);
  CHECK(names == std::vector<std::string>{"Selector", "Always", "SubSelector", "SubValueB"});
  const Visited* subValue = findVisited(visited, signalIndex(*muxed, "SubValueB"));
  REQUIRE(subValue != nullptr);
  CHECK(subValue->value.rawUnsigned == 0x77u);
}

TEST_CASE("codec selects m1 and skips the other pages") {
  const ParseOutput parsed = parse(readFixture("multiplexing.dbc"), "multiplexing.dbc");
  const Message* muxed = parsed.database.findMessage("Muxed");
  REQUIRE(muxed != nullptr);
  const MessageCodec sut = MessageCodec::compile(parsed.database, *muxed);

  const auto visited = decodeAll(sut, hexBytes("01 FF FF 00 00 00 00 00"));

  CHECK(visited.size() == 3);
  const Visited* value1 = findVisited(visited, signalIndex(*muxed, "Value1"));
  REQUIRE(value1 != nullptr);
  CHECK(value1->value.rawSigned == -1);
  CHECK(value1->value.physical == -0.5);
  CHECK(findVisited(visited, signalIndex(*muxed, "Value0")) == nullptr);
}

TEST_CASE("codec ignores a nested multiplexor whose own page is not selected") {
  const ParseOutput parsed = parse(readFixture("multiplexing.dbc"), "multiplexing.dbc");
  const Message* muxed = parsed.database.findMessage("Muxed");
  REQUIRE(muxed != nullptr);
  const MessageCodec sut = MessageCodec::compile(parsed.database, *muxed);

  // Selector 0 selects Value0; the bits SubSelector would read hold 3, but it is inactive.
  const auto visited = decodeAll(sut, hexBytes("00 03 44 00 00 00 00 00"));

  CHECK(findVisited(visited, signalIndex(*muxed, "Value0")) != nullptr);
  CHECK(findVisited(visited, signalIndex(*muxed, "SubSelector")) == nullptr);
  CHECK(findVisited(visited, signalIndex(*muxed, "SubValueA")) == nullptr);
  CHECK(visited.size() == 3);
}

TEST_CASE("codec lets a signed multiplexor reading -128 select m128") {
  const ParseOutput parsed = parse(readFixture("multiplexing.dbc"), "multiplexing.dbc");
  const Message* signedMux = parsed.database.findMessage("SignedMux");
  REQUIRE(signedMux != nullptr);
  const MessageCodec sut = MessageCodec::compile(parsed.database, *signedMux);

  const auto visited = decodeAll(sut, hexBytes("80 2A 00 00 00 00 00 00"));

  REQUIRE(findVisited(visited, signalIndex(*signedMux, "Mode")) != nullptr);
  CHECK(findVisited(visited, signalIndex(*signedMux, "Mode"))->value.rawSigned == -128);
  const Visited* high = findVisited(visited, signalIndex(*signedMux, "HighPage"));
  REQUIRE(high != nullptr);
  CHECK(high->value.rawUnsigned == 0x2Au);
  CHECK(findVisited(visited, signalIndex(*signedMux, "LowPage")) == nullptr);
}

TEST_CASE("codec follows two independent multiplexors with several ranges") {
  const ParseOutput parsed = parse(readFixture("multiplexing.dbc"), "multiplexing.dbc");
  const Message* twoMux = parsed.database.findMessage("TwoMultiplexors");
  REQUIRE(twoMux != nullptr);
  const MessageCodec sut = MessageCodec::compile(parsed.database, *twoMux);
  const std::uint32_t valueA = signalIndex(*twoMux, "ValueA");
  const std::uint32_t valueB = signalIndex(*twoMux, "ValueB");

  const auto bothActive = decodeAll(sut, hexBytes("C1 11 22 00 00 00 00 00"));  // MuxA 1, MuxB 12 (8-15)
  const auto onlyB = decodeAll(sut, hexBytes("52 11 22 00 00 00 00 00"));       // MuxA 2, MuxB 5
  const auto neither = decodeAll(sut, hexBytes("42 11 22 00 00 00 00 00"));     // MuxA 2, MuxB 4

  CHECK(findVisited(bothActive, valueA) != nullptr);
  CHECK(findVisited(bothActive, valueB) != nullptr);
  CHECK(findVisited(onlyB, valueA) == nullptr);
  CHECK(findVisited(onlyB, valueB) != nullptr);
  CHECK(findVisited(neither, valueA) == nullptr);
  CHECK(findVisited(neither, valueB) == nullptr);
}

TEST_CASE("codec decodes what fits in a frame shorter than the DBC length and counts the rest as missing") {
  const ParseOutput parsed = oneMessage(
      " SG_ A : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ B : 16|16@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ C : 56|8@1+ (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  DecodeSummary summary;

  const auto visited = decodeAll(sut, hexBytes("11 22 33"), &summary);

  CHECK(summary.decoded == 1);
  CHECK(summary.missing == 2);
  REQUIRE(visited.size() == 1);
  CHECK(visited[0].value.rawUnsigned == 0x11u);
}

TEST_CASE("codec counts every signal as missing for an empty payload") {
  const ParseOutput parsed = oneMessage(" SG_ A : 0|8@1+ (1,0) [0|0] \"\" Vcu\n SG_ B : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  DecodeSummary summary;

  const auto visited = decodeAll(sut, std::span<const std::uint8_t>{}, &summary);

  CHECK(visited.empty());
  CHECK(summary.missing == 2);
}

TEST_CASE("codec decodes transport-protocol payloads longer than 64 bytes") {
  constexpr std::uint32_t TP_LENGTH = 100;
  const ParseOutput parsed = oneMessage(" SG_ Late : 760|16@1+ (1,0) [0|0] \"\" Vcu\n SG_ Last : 799|8@0+ (1,0) [0|0] \"\" Vcu\n",
                                        TP_LENGTH);
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  std::vector<std::uint8_t> payload(TP_LENGTH, 0);
  payload[95] = 0x34;
  payload[96] = 0x12;
  payload[99] = 0xA5;

  const auto visited = decodeAll(sut, payload);

  REQUIRE(visited.size() == 2);
  CHECK(visitedValue(visited, 0).rawUnsigned == 0x1234u);
  CHECK(visitedValue(visited, 1).rawUnsigned == 0xA5u);
}

TEST_CASE("codec never reads outside the frame for a start bit near 2^32") {
  const ParseOutput parsed = oneMessage(" SG_ Far : 4294967290|8@1+ (1,0) [0|0] \"\" Vcu\n SG_ FarBe : 4294967288|8@0+ (1,0) [0|0] \"\" Vcu\n");
  const Message& message = onlyMessage(parsed);
  const MessageCodec sut = MessageCodec::compile(parsed.database, message);
  DecodeSummary summary;

  const auto visited = decodeAll(sut, hexBytes("FF FF FF FF FF FF FF FF"), &summary);

  CHECK(visited.empty());
  CHECK(summary.missing == 2);
  std::array<std::uint8_t, CLASSIC_LENGTH> buffer{};
  CHECK(sut.encode(0, 1.0, buffer) == EncodeStatus::BufferTooShort);
}

TEST_CASE("codec leaves signals over 64 bits and mismatched floats out of the compiled layout") {
  const ParseOutput parsed = oneMessage(" SG_ Text : 0|72@1+ (1,0) [0|0] \"\" Vcu\n SG_ BadFloat : 0|16@1+ (1,0) [0|0] \"\" Vcu\n"
                                        " SG_ Ok : 0|8@1+ (1,0) [0|0] \"\" Vcu\n",
                                        16, "SIG_VALTYPE_ 1 BadFloat : 1;\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  std::array<std::uint8_t, 16> buffer{};

  CHECK(sut.skippedSignals() == std::vector<std::uint32_t>{0, 1});
  CHECK(sut.find(0) == nullptr);
  REQUIRE(sut.find(2) != nullptr);
  CHECK(sut.signals().size() == 1);
  CHECK(sut.encode(0, 1.0, buffer) == EncodeStatus::NotEncodable);
}

// ------------------------------------------------------------------ plain-message word path (issue 27)

namespace {

/// Intel and Motorola, signed and unsigned, byte-aligned and not, all inside bytes 0..7.
const std::string PLAIN_SIGNALS =
    " SG_ IntelU12 : 4|12@1+ (0.5,-10) [0|0] \"\" Vcu\n"
    " SG_ IntelS7 : 17|7@1- (1,0) [0|0] \"\" Vcu\n"
    " SG_ MotorolaU16 : 31|16@0+ (0.1,0) [0|0] \"\" Vcu\n"
    " SG_ MotorolaS12 : 43|12@0- (0.25,1) [0|0] \"\" Vcu\n"
    " SG_ IntelS7End : 57|7@1- (1,0) [0|0] \"\" Vcu\n";

/// The same bytes through the plain word path (8 bytes) and the padded path (the 8 bytes
/// plus one more, which no signal covers): every visited signal must agree bit for bit.
void checkWordPathEqualsPaddedPath(const MessageCodec& sut, const std::vector<std::uint8_t>& classic) {
  std::vector<std::uint8_t> longer = classic;
  longer.push_back(0xA5);
  DecodeSummary wordSummary;
  DecodeSummary paddedSummary;

  const auto word = decodeAll(sut, classic, &wordSummary);
  const auto padded = decodeAll(sut, longer, &paddedSummary);

  REQUIRE(word.size() == padded.size());
  CHECK(wordSummary.decoded == paddedSummary.decoded);
  CHECK(wordSummary.missing == paddedSummary.missing);
  for (std::size_t i = 0; i < word.size(); ++i) {
    CAPTURE(i);
    CHECK(word[i].index == padded[i].index);
    CHECK(word[i].value.kind == padded[i].value.kind);
    CHECK(word[i].value.rawUnsigned == padded[i].value.rawUnsigned);
    CHECK(word[i].value.physical == padded[i].value.physical);
  }
}

}  // namespace

TEST_CASE("codec marks a message without multiplexing and with integer signals plain") {
  const ParseOutput parsed = oneMessage(PLAIN_SIGNALS);
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  CHECK(sut.isPlain());
  CHECK(sut.wordSignals().size() == sut.signals().size());
}

TEST_CASE("codec does not mark multiplexed, float, 64-bit unsigned or long-frame messages plain") {
  const ParseOutput mux = oneMessage(" SG_ Sel M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n SG_ A m1 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n");
  const ParseOutput floats = oneMessage(" SG_ F : 0|32@1+ (1,0) [0|0] \"\" Vcu\n", CLASSIC_LENGTH, "SIG_VALTYPE_ 1 F : 1;\n");
  const ParseOutput wideUnsigned = oneMessage(" SG_ U64 : 0|64@1+ (1,0) [0|0] \"\" Vcu\n");
  const ParseOutput pastByte7 = oneMessage(" SG_ A : 0|8@1+ (1,0) [0|0] \"\" Vcu\n SG_ B : 64|8@1+ (1,0) [0|0] \"\" Vcu\n", 16);

  CHECK_FALSE(MessageCodec::compile(mux.database, onlyMessage(mux)).isPlain());
  CHECK_FALSE(MessageCodec::compile(floats.database, onlyMessage(floats)).isPlain());
  CHECK_FALSE(MessageCodec::compile(wideUnsigned.database, onlyMessage(wideUnsigned)).isPlain());
  CHECK_FALSE(MessageCodec::compile(pastByte7.database, onlyMessage(pastByte7)).isPlain());
}

TEST_CASE("codec word path decodes signed and Motorola signals as the padded path does") {
  const ParseOutput parsed = oneMessage(PLAIN_SIGNALS);
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  REQUIRE(sut.isPlain());
  std::mt19937_64 random(27);

  for (const char* fixed : {"00 00 00 00 00 00 00 00", "FF FF FF FF FF FF FF FF", "80 00 80 00 80 00 80 00"}) {
    CAPTURE(fixed);
    checkWordPathEqualsPaddedPath(sut, hexBytes(fixed));
  }
  constexpr int RANDOM_PAYLOADS = 200;
  for (int round = 0; round < RANDOM_PAYLOADS; ++round) {
    const std::uint64_t bits = random();
    std::vector<std::uint8_t> payload(CLASSIC_LENGTH);
    std::memcpy(payload.data(), &bits, payload.size());
    checkWordPathEqualsPaddedPath(sut, payload);
  }
}

TEST_CASE("codec word path gives known values for signed Intel and Motorola signals") {
  const ParseOutput parsed = oneMessage(PLAIN_SIGNALS);
  const Message& message = onlyMessage(parsed);
  const MessageCodec sut = MessageCodec::compile(parsed.database, message);
  REQUIRE(sut.isPlain());
  // IntelU12 = 0xABC (bits 4..15), IntelS7 = -1 (bits 17..23), MotorolaU16 = 0x1234 (bytes 3..4),
  // MotorolaS12 = -2048 (byte 5 bits 3..0 = 0x8, byte 6 = 0x00), IntelS7End = -64 (byte 7 bits 1..7).
  const auto visited = decodeAll(sut, hexBytes("C0 AB FE 12 34 08 00 80"));

  REQUIRE(visited.size() == 5);
  CHECK(visitedValue(visited, signalIndex(message, "IntelU12")).rawUnsigned == 0xABCu);
  CHECK(visitedValue(visited, signalIndex(message, "IntelU12")).physical == 0xABC * 0.5 - 10);
  CHECK(visitedValue(visited, signalIndex(message, "IntelS7")).rawSigned == -1);
  CHECK(visitedValue(visited, signalIndex(message, "MotorolaU16")).rawUnsigned == 0x1234u);
  CHECK(visitedValue(visited, signalIndex(message, "MotorolaS12")).rawSigned == -2048);
  CHECK(visitedValue(visited, signalIndex(message, "MotorolaS12")).physical == -2048 * 0.25 + 1);
  CHECK(visitedValue(visited, signalIndex(message, "IntelS7End")).rawSigned == -64);
}

TEST_CASE("codec word path decodes a signed 64-bit signal and a 63-bit unsigned maximum") {
  const ParseOutput signed64 = oneMessage(" SG_ S : 7|64@0- (1,0) [0|0] \"\" Vcu\n");
  const ParseOutput unsigned63 = oneMessage(" SG_ U : 0|63@1+ (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec signedCodec = MessageCodec::compile(signed64.database, onlyMessage(signed64));
  const MessageCodec unsignedCodec = MessageCodec::compile(unsigned63.database, onlyMessage(unsigned63));
  REQUIRE(signedCodec.isPlain());
  REQUIRE(unsignedCodec.isPlain());
  const std::vector<std::uint8_t> ones = hexBytes("FF FF FF FF FF FF FF FF");

  CHECK(decodeOne(signedCodec, hexBytes("80 00 00 00 00 00 00 00"), 0).rawSigned == INT64_MIN);
  CHECK(decodeOne(signedCodec, ones, 0).rawSigned == -1);
  CHECK(decodeOne(unsignedCodec, ones, 0).rawUnsigned == 0x7FFFFFFFFFFFFFFFull);
  CHECK(decodeOne(unsignedCodec, ones, 0).physical == 9223372036854775807.0);
}

TEST_CASE("codec decodes a 64-bit unsigned maximum outside the word path without losing the top bit") {
  const ParseOutput parsed = oneMessage(" SG_ U64 : 0|64@1+ (2,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  REQUIRE_FALSE(sut.isPlain());

  const DecodedValue value = decodeOne(sut, hexBytes("FF FF FF FF FF FF FF FF"), 0);

  CHECK(value.rawUnsigned == 0xFFFFFFFFFFFFFFFFull);
  CHECK(value.physical == 2.0 * 18446744073709551615.0);
}

TEST_CASE("codec decodes a plain message from a short frame signal by signal and counts the rest as missing") {
  const ParseOutput parsed = oneMessage(PLAIN_SIGNALS);
  const Message& message = onlyMessage(parsed);
  const MessageCodec sut = MessageCodec::compile(parsed.database, message);
  REQUIRE(sut.isPlain());
  constexpr std::size_t SIGNALS_IN_FIVE_BYTES = 3;  // IntelU12, IntelS7, MotorolaU16 (bytes 3..4)
  DecodeSummary summary;

  const auto visited = decodeAll(sut, hexBytes("C0 AB FE 12 34"), &summary);

  CHECK(summary.decoded == SIGNALS_IN_FIVE_BYTES);
  CHECK(summary.missing == sut.signals().size() - SIGNALS_IN_FIVE_BYTES);
  REQUIRE(visited.size() == SIGNALS_IN_FIVE_BYTES);
  CHECK(visitedValue(visited, signalIndex(message, "IntelU12")).rawUnsigned == 0xABCu);
  CHECK(visitedValue(visited, signalIndex(message, "MotorolaU16")).rawUnsigned == 0x1234u);
  for (std::size_t length = 0; length < CLASSIC_LENGTH; ++length) {
    CAPTURE(length);
    const std::vector<std::uint8_t> prefix(length, 0xFF);
    DecodeSummary partial;
    (void)decodeAll(sut, prefix, &partial);
    CHECK(partial.decoded + partial.missing == sut.signals().size());
  }
}
