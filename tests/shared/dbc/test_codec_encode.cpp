// MessageCodec encoding: rounding, range checks, untouched neighbours, raw and float
// values, and the initial payload (J1939 fill, GenSigStartValue, the HHEA S1_ES example).

#include "dbc_test_support.hpp"

#include <doctest/doctest.h>

#include <array>
#include <limits>
#include <string>
#include <vector>

using namespace openvcu;
using namespace openvcu::dbc;
using namespace openvcu::dbc::test;

namespace {
constexpr std::uint8_t NOT_AVAILABLE_FILL = 0xFF;  // SAE J1939-71: all ones = not available
constexpr std::uint8_t NOISE = 0xAA;
constexpr double CONNECT_FOR_DRIVING = 3;  // Control_Es_Relay (hhea-can-interface.md)

std::vector<std::uint8_t> filled(std::uint8_t value, std::size_t length = CLASSIC_LENGTH) {
  return std::vector<std::uint8_t>(length, value);
}

std::vector<std::uint8_t> initialOf(const MessageCodec& codec) {
  return {codec.initialPayload().begin(), codec.initialPayload().end()};
}
}  // namespace

// ------------------------------------------------------------------ encode

TEST_CASE("codec encode rounds to the nearest raw step instead of truncating") {
  const ParseOutput parsed = oneMessage(
      " SG_ U : 0|16@1+ (0.1,0) [0|6553.5] \"\" Vcu\n"
      " SG_ S : 16|16@1- (0.1,0) [-3276.8|3276.7] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  auto buffer = filled(0);

  REQUIRE(sut.encode(0, 12.46, buffer) == EncodeStatus::Ok);
  REQUIRE(sut.encode(1, -12.46, buffer) == EncodeStatus::Ok);

  CHECK(decodeOne(sut, buffer, 0).rawUnsigned == 125u);
  CHECK(decodeOne(sut, buffer, 1).rawSigned == -125);
}

TEST_CASE("codec encode of a decoded physical value reproduces the raw value") {
  const ParseOutput parsed = oneMessage(" SG_ T : 4|12@0- (0.05,-20) [-122.4|82.35] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  constexpr std::int64_t LOWEST = -2048;
  constexpr std::int64_t HIGHEST = 2047;

  for (std::int64_t raw = LOWEST; raw <= HIGHEST; ++raw) {
    CAPTURE(raw);
    auto buffer = filled(0);
    REQUIRE(sut.encode(0, static_cast<double>(raw) * 0.05 - 20, buffer) == EncodeStatus::Ok);
    CHECK(decodeOne(sut, buffer, 0).rawSigned == raw);
  }
}

TEST_CASE("codec encode refuses values outside the DBC range") {
  const ParseOutput parsed = oneMessage(" SG_ Soc : 0|8@1+ (0.4,0) [0|100] \"%\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  auto buffer = filled(NOISE);

  CHECK(sut.encode(0, 100.0, buffer) == EncodeStatus::Ok);
  CHECK(sut.encode(0, 100.4, buffer) == EncodeStatus::OutOfRange);
  CHECK(sut.encode(0, -0.4, buffer) == EncodeStatus::OutOfRange);
  CHECK(decodeOne(sut, buffer, 0).physical == doctest::Approx(100.0));
}

TEST_CASE("codec encode refuses values the bit width cannot hold when the DBC gives no range") {
  const ParseOutput parsed = oneMessage(
      " SG_ U : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ S : 8|8@1- (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  auto buffer = filled(0);

  CHECK(sut.encode(0, 255.0, buffer) == EncodeStatus::Ok);
  CHECK(sut.encode(0, 256.0, buffer) == EncodeStatus::OutOfRange);
  CHECK(sut.encode(0, -1.0, buffer) == EncodeStatus::OutOfRange);
  CHECK(sut.encode(1, -128.0, buffer) == EncodeStatus::Ok);
  CHECK(sut.encode(1, 127.0, buffer) == EncodeStatus::Ok);
  CHECK(sut.encode(1, 128.0, buffer) == EncodeStatus::OutOfRange);
  CHECK(sut.encode(1, -129.0, buffer) == EncodeStatus::OutOfRange);
}

TEST_CASE("codec encode refuses non-finite values and a buffer too short for the signal") {
  const ParseOutput parsed = oneMessage(" SG_ Late : 56|8@1+ (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  auto buffer = filled(0);
  std::array<std::uint8_t, 4> shortBuffer{};

  CHECK(sut.encode(0, std::numeric_limits<double>::quiet_NaN(), buffer) == EncodeStatus::NotEncodable);
  CHECK(sut.encode(0, std::numeric_limits<double>::infinity(), buffer) == EncodeStatus::NotEncodable);
  CHECK(sut.encode(0, 1.0, shortBuffer) == EncodeStatus::BufferTooShort);
  CHECK(sut.encode(7, 1.0, buffer) == EncodeStatus::NotEncodable);
}

TEST_CASE("codec encode leaves every other bit untouched in both byte orders") {
  const ParseOutput parsed = oneMessage(
      " SG_ Intel : 10|9@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Motorola : 44|11@0+ (1,0) [0|0] \"\" Vcu\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  constexpr double ALL_ZERO = 0;

  auto intelBuffer = filled(0xFF);
  auto motorolaBuffer = filled(0xFF);
  REQUIRE(sut.encode(0, ALL_ZERO, intelBuffer) == EncodeStatus::Ok);
  REQUIRE(sut.encode(1, ALL_ZERO, motorolaBuffer) == EncodeStatus::Ok);

  // Intel bits 10..18: byte 1 bits 2..7, byte 2 bits 0..2.
  CHECK(intelBuffer == hexBytes("FF 03 F8 FF FF FF FF FF"));
  // Motorola MSB byte 5 bit 4: byte 5 bits 4..0, byte 6 bits 7..2.
  CHECK(motorolaBuffer == hexBytes("FF FF FF FF FF E0 03 FF"));
}

TEST_CASE("codec encodeRaw writes two's complement bits and float bit patterns") {
  const ParseOutput parsed = oneMessage(
      " SG_ S : 0|12@1- (1,0) [0|0] \"\" Vcu\n"
      " SG_ F : 32|32@1+ (1,0) [0|0] \"\" Vcu\n",
      CLASSIC_LENGTH, "SIG_VALTYPE_ 1 F : 1;\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  auto buffer = filled(0);
  DecodedValue minusOne;
  minusOne.kind = RawKind::Signed;
  minusOne.rawSigned = -1;
  DecodedValue oneAndAHalf;
  oneAndAHalf.kind = RawKind::Float32;
  oneAndAHalf.rawFloat = 1.5;

  REQUIRE(sut.encodeRaw(0, minusOne, buffer) == EncodeStatus::Ok);
  REQUIRE(sut.encodeRaw(1, oneAndAHalf, buffer) == EncodeStatus::Ok);

  CHECK(buffer == hexBytes("FF 0F 00 00 00 00 C0 3F"));
}

TEST_CASE("codec encode writes float64 signals exactly") {
  const ParseOutput parsed = oneMessage(" SG_ D : 0|64@1- (1,0) [0|0] \"\" Vcu\n", CLASSIC_LENGTH,
                                        "SIG_VALTYPE_ 1 D : 2;\n");
  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));
  auto buffer = filled(0);
  constexpr double VALUE = -1234.5678;

  REQUIRE(sut.encode(0, VALUE, buffer) == EncodeStatus::Ok);

  CHECK(decodeOne(sut, buffer, 0).rawFloat == VALUE);
}

// ------------------------------------------------------------------ initial payload

TEST_CASE("codec initial payload is all ones for a J1939PG message") {
  const ParseOutput parsed = oneMessage(" SG_ A : 0|8@1+ (1,0) [0|0] \"\" Vcu\n", CLASSIC_LENGTH,
                                        "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\";\n"
                                        "BA_ \"VFrameFormat\" BO_ 1 3;\n");
  const Message& message = onlyMessage(parsed);
  REQUIRE(message.isJ1939());

  const MessageCodec sut = MessageCodec::compile(parsed.database, message);

  CHECK(initialOf(sut) == filled(NOT_AVAILABLE_FILL));
}

TEST_CASE("codec initial payload is all zeros for a plain CAN message") {
  const ParseOutput parsed = oneMessage(" SG_ A : 0|8@1+ (1,0) [0|0] \"\" Vcu\n");

  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  CHECK(initialOf(sut) == filled(0));
  CHECK(sut.length() == CLASSIC_LENGTH);
}

TEST_CASE("codec initial payload applies GenSigStartValue explicit values and defaults as raw values") {
  const ParseOutput parsed = oneMessage(
      " SG_ Mode : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Level : 8|8@1- (0.5,10) [-54|73.5] \"\" Vcu\n"
      " SG_ Big : 23|16@0+ (1,0) [0|0] \"\" Vcu\n",
      CLASSIC_LENGTH,
      "BA_DEF_ SG_ \"GenSigStartValue\" INT -100000 100000;\n"
      "BA_DEF_DEF_ \"GenSigStartValue\" 7;\n"
      "BA_ \"GenSigStartValue\" SG_ 1 Level -2;\n"
      "BA_ \"GenSigStartValue\" SG_ 1 Big 4660;\n");

  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  CHECK(initialOf(sut) == hexBytes("07 FE 12 34 00 00 00 00"));
}

TEST_CASE("codec initial payload leaves multiplexed signals at the fill value") {
  const ParseOutput parsed = oneMessage(
      " SG_ Sel M : 0|8@1+ (1,0) [0|0] \"\" Vcu\n"
      " SG_ Page m1 : 8|8@1+ (1,0) [0|0] \"\" Vcu\n",
      CLASSIC_LENGTH,
      "BA_DEF_ SG_ \"GenSigStartValue\" INT 0 255;\n"
      "BA_ \"GenSigStartValue\" SG_ 1 Sel 1;\n"
      "BA_ \"GenSigStartValue\" SG_ 1 Page 9;\n");

  const MessageCodec sut = MessageCodec::compile(parsed.database, onlyMessage(parsed));

  CHECK(initialOf(sut) == hexBytes("01 00 00 00 00 00 00 00"));
}

TEST_CASE("codec encodes Control_Es_Relay = 3 on the J1939 fill as EF FF FF FF FF FF FF FF") {
  // hhea-can-interface.md: S1_ES_PGN61427, the thesis' trace (Figure 6.11).
  const ParseOutput parsed = parseText(
      "BO_ 2364535585 S1_ES_PGN61427: 8 Vehicle_Control_Unit\n"
      " SG_ ShutDown_Clearance : 0|2@1+ (1,0) [0|3] \"\" VIC\n"
      " SG_ Control_Es_Relay : 2|3@1+ (1,0) [0|7] \"\" VIC\n"
      " SG_ Reserved_1 : 5|1@1+ (1,0) [0|1] \"\" VIC\n"
      " SG_ Service_Mode_Request : 6|2@1+ (1,0) [0|3] \"\" VIC\n"
      " SG_ Reserved_2 : 8|32@1+ (1,0) [0|4294967295] \"\" VIC\n"
      " SG_ Terminal_Voltage_Actual : 40|12@1+ (0.5,0) [0|2047.5] \"V\" VIC\n"
      " SG_ Counter_PGN61427 : 52|4@1+ (1,0) [0|15] \"\" VIC\n"
      " SG_ CRC_PGN61427 : 56|8@1+ (1,0) [0|255] \"\" VIC\n"
      "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\";\n"
      "BA_ \"VFrameFormat\" BO_ 2364535585 3;\n");
  const Message& message = onlyMessage(parsed);
  const MessageCodec sut = MessageCodec::compile(parsed.database, message);
  std::vector<std::uint8_t> payload = initialOf(sut);
  REQUIRE(payload == filled(NOT_AVAILABLE_FILL));

  REQUIRE(sut.encode(signalIndex(message, "Control_Es_Relay"), CONNECT_FOR_DRIVING, payload) == EncodeStatus::Ok);

  CHECK(payload == hexBytes("EF FF FF FF FF FF FF FF"));
  // The battery mimic's reading: (byte0 & 0x1C) >> 2.
  CHECK(((payload[0] & 0x1C) >> 2) == 3);
  CHECK(decodeOne(sut, payload, signalIndex(message, "Terminal_Voltage_Actual")).physical == 2047.5);
}

TEST_CASE("codec applies the fixture's start value to S1_ES, then Control_Es_Relay = 3 gives EF FF..") {
  const ParseOutput parsed = parse(readFixture("j1939_hhea_vcu.dbc"), "j1939_hhea_vcu.dbc");
  REQUIRE_FALSE(parsed.hasErrors());
  const Message* s1 = parsed.database.findMessage(0x0CEFF321u, true);
  REQUIRE(s1 != nullptr);
  const MessageCodec sut = MessageCodec::compile(parsed.database, *s1);
  std::vector<std::uint8_t> payload = initialOf(sut);

  CHECK(payload == hexBytes("E3 FF FF FF FF FF FF FF"));  // start value 0 = disconnect
  REQUIRE(sut.encode(signalIndex(*s1, "Control_Es_Relay"), CONNECT_FOR_DRIVING, payload) == EncodeStatus::Ok);
  CHECK(payload == hexBytes("EF FF FF FF FF FF FF FF"));
}
