#include "openvcu/j1939/request.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cstdint>

using namespace openvcu::j1939;

namespace {

constexpr std::uint32_t PGN_TIME_DATE_REQUESTED = 65254;  // 0xFEE6
constexpr std::uint32_t PGN_HVESSHIST = 64606;            // 0xFC5E, state of health
constexpr std::uint32_t VIC_REQUEST_ID = 0x00EA21F3;
constexpr std::uint8_t VCU_ADDRESS = 0x21;
constexpr std::uint8_t VIC_ADDRESS = 0xF3;
constexpr RequestPayload TIME_DATE_REQUEST{0xE6, 0xFE, 0x00};

}  // namespace

TEST_CASE("request for Time/Date encodes the PGN least significant byte first") {
  CHECK(encodeRequest(PGN_TIME_DATE_REQUESTED) == TIME_DATE_REQUEST);
  CHECK(encodeRequest(PGN_HVESSHIST) == RequestPayload{0x5E, 0xFC, 0x00});
}

TEST_CASE("request E6 FE 00 decodes to PGN 65254") {
  const std::optional<std::uint32_t> maybeSut = decodeRequest(TIME_DATE_REQUEST);

  REQUIRE(maybeSut);
  CHECK(*maybeSut == PGN_TIME_DATE_REQUESTED);
}

TEST_CASE("request padded to 8 bytes decodes like the 3-byte form") {
  constexpr std::array<std::uint8_t, 8> PADDED{0xE6, 0xFE, 0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};

  CHECK(decodeRequest(PADDED) == PGN_TIME_DATE_REQUESTED);
}

TEST_CASE("request decode refuses fewer than 3 or more than 8 bytes") {
  constexpr std::array<std::uint8_t, 9> TOO_LONG{0xE6, 0xFE, 0x00, 0, 0, 0, 0, 0, 0};
  const std::span<const std::uint8_t> tooShort{TIME_DATE_REQUEST.data(), 2};

  CHECK_FALSE(decodeRequest(tooShort));
  CHECK_FALSE(decodeRequest(TOO_LONG));
  CHECK_FALSE(decodeRequest({}));
}

TEST_CASE("request decode refuses a value wider than an 18-bit PGN") {
  constexpr RequestPayload TOO_WIDE{0xE6, 0xFE, 0x04};

  CHECK_FALSE(decodeRequest(TOO_WIDE));
  CHECK(decodeRequest(RequestPayload{0xFF, 0xFF, 0x03}) == PGN_MASK);
}

TEST_CASE("request identifier of the VIC asking the VCU is 0x00EA21F3") {
  const std::uint32_t sut = requestCanId(0, VIC_ADDRESS, VCU_ADDRESS);

  CHECK(sut == VIC_REQUEST_ID);
  CHECK(pgnOf(sut) == PGN_REQUEST);
  CHECK(Id::fromCanId(sut).destination() == VCU_ADDRESS);
}

TEST_CASE("request identifier of the VCU asking the VIC for HVESSHIST uses the default priority") {
  constexpr std::uint32_t EXPECTED_ID = 0x18EAF321;

  CHECK(requestCanId(REQUEST_DEFAULT_PRIORITY, VCU_ADDRESS, VIC_ADDRESS) == EXPECTED_ID);
}

TEST_CASE("global request identifier goes to 0xFF") {
  CHECK(requestCanId(REQUEST_DEFAULT_PRIORITY, VCU_ADDRESS, GLOBAL_ADDRESS) == 0x18EAFF21u);
}

namespace {

constexpr std::uint32_t REQUEST_TO_VCU = 0x18EA21F3;
constexpr std::uint32_t REQUEST_TO_ALL = 0x18EAFFF3;
constexpr std::uint32_t REQUEST_TO_ECU1 = 0x18EA10F3;

AddressSet vcuAddresses() {
  AddressSet mine{};
  mine[VCU_ADDRESS] = true;
  return mine;
}

}  // namespace

TEST_CASE("request parse: a request to one of my addresses names the PGN and the requester") {
  const std::optional<Request> maybeSut = parseRequest(REQUEST_TO_VCU, true, TIME_DATE_REQUEST, vcuAddresses());

  REQUIRE(maybeSut);
  CHECK(*maybeSut == Request{PGN_TIME_DATE_REQUESTED, VIC_ADDRESS, false});
}

TEST_CASE("request parse: a request to the global address is for me and marked global") {
  const std::optional<Request> maybeSut = parseRequest(REQUEST_TO_ALL, true, TIME_DATE_REQUEST, vcuAddresses());

  REQUIRE(maybeSut);
  CHECK(maybeSut->global);
  CHECK(maybeSut->requester == VIC_ADDRESS);
}

TEST_CASE("request parse: a request to another node, a standard frame or another PGN is not mine") {
  CHECK_FALSE(parseRequest(REQUEST_TO_ECU1, true, TIME_DATE_REQUEST, vcuAddresses()));
  CHECK_FALSE(parseRequest(REQUEST_TO_VCU & 0x7FFu, false, TIME_DATE_REQUEST, vcuAddresses()));
  CHECK_FALSE(parseRequest(0x18E821F3, true, TIME_DATE_REQUEST, vcuAddresses()));  // PGN 59392, not 59904
  CHECK_FALSE(parseRequest(0x19EA21F3, true, TIME_DATE_REQUEST, vcuAddresses()));  // DP set: PGN 0x1EA00
}

TEST_CASE("request parse: a request for me with a malformed payload is refused") {
  const std::span<const std::uint8_t> tooShort{TIME_DATE_REQUEST.data(), 2};

  CHECK_FALSE(parseRequest(REQUEST_TO_VCU, true, tooShort, vcuAddresses()));
  CHECK_FALSE(parseRequest(REQUEST_TO_VCU, true, RequestPayload{0xE6, 0xFE, 0x04}, vcuAddresses()));
}

TEST_CASE("request build gives the identifier and the bytes, and parses back") {
  const RequestFrame sut = buildRequest(PGN_TIME_DATE_REQUESTED, REQUEST_DEFAULT_PRIORITY, VIC_ADDRESS, VCU_ADDRESS);

  CHECK(sut.canId == REQUEST_TO_VCU);
  CHECK(sut.payload == TIME_DATE_REQUEST);
  CHECK(parseRequest(sut.canId, true, sut.payload, vcuAddresses()) ==
        Request{PGN_TIME_DATE_REQUESTED, VIC_ADDRESS, false});
}
