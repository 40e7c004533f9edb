#include "openvcu/j1939/acknowledgement.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cstdint>

using namespace openvcu::j1939;

namespace {

constexpr std::uint32_t PGN_UNKNOWN = 0xFECA;  // 65226, a PGN the VCU does not send
constexpr std::uint8_t VCU_ADDRESS = 0x21;
constexpr std::uint8_t VIC_ADDRESS = 0xF3;
constexpr AcknowledgementPayload NACK_FOR_VIC{0x01, 0xFF, 0xFF, 0xFF, 0xF3, 0xCA, 0xFE, 0x00};

}  // namespace

TEST_CASE("acknowledgement: a NACK names the requester and the PGN, least significant byte first") {
  const AcknowledgementPayload sut =
      encodeAcknowledgement(Acknowledgement{AckControl::Negative, GROUP_FUNCTION_NOT_APPLICABLE, VIC_ADDRESS, PGN_UNKNOWN});

  CHECK(sut == NACK_FOR_VIC);
}

TEST_CASE("acknowledgement: a positive ACK has control byte 0 and masks the PGN to 18 bits") {
  const AcknowledgementPayload sut =
      encodeAcknowledgement(Acknowledgement{AckControl::Positive, 0x05, VIC_ADDRESS, 0xFFFC5Eu});

  CHECK(sut == AcknowledgementPayload{0x00, 0x05, 0xFF, 0xFF, 0xF3, 0x5E, 0xFC, 0x03});
}

TEST_CASE("acknowledgement: decode reads back what encode wrote") {
  const std::optional<Acknowledgement> maybeSut = decodeAcknowledgement(NACK_FOR_VIC);

  REQUIRE(maybeSut);
  CHECK(maybeSut->control == AckControl::Negative);
  CHECK(maybeSut->groupFunction == GROUP_FUNCTION_NOT_APPLICABLE);
  CHECK(maybeSut->address == VIC_ADDRESS);
  CHECK(maybeSut->pgn == PGN_UNKNOWN);
  for (const AckControl control :
       {AckControl::Positive, AckControl::Negative, AckControl::AccessDenied, AckControl::CannotRespond}) {
    const Acknowledgement ack{control, 0x00, VCU_ADDRESS, 0x1FEE6};
    CHECK(decodeAcknowledgement(encodeAcknowledgement(ack)) == ack);
  }
}

TEST_CASE("acknowledgement: decode refuses another length, an unknown control byte or a PGN wider than 18 bits") {
  const std::span<const std::uint8_t> sevenBytes{NACK_FOR_VIC.data(), 7};
  AcknowledgementPayload unknownControl = NACK_FOR_VIC;
  unknownControl[0] = 4;
  AcknowledgementPayload tooWide = NACK_FOR_VIC;
  tooWide[7] = 0x04;

  CHECK_FALSE(decodeAcknowledgement(sevenBytes));
  CHECK_FALSE(decodeAcknowledgement(unknownControl));
  CHECK_FALSE(decodeAcknowledgement(tooWide));
}

TEST_CASE("acknowledgement identifier of the VCU to global is 0x18E8FF21") {
  const std::uint32_t sut = acknowledgementCanId(ACKNOWLEDGEMENT_DEFAULT_PRIORITY, VCU_ADDRESS);

  CHECK(sut == 0x18E8FF21u);
  CHECK(pgnOf(sut) == PGN_ACKNOWLEDGEMENT);
}
