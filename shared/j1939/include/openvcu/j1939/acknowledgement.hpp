#pragma once
// SAE J1939-21 Acknowledgement (PGN 59392, 0xE800): the answer to a Request that is not
// the requested data. 8 bytes:
//
//   byte 0     control byte: 0 ACK, 1 NACK, 2 access denied, 3 cannot respond
//   byte 1     group function value (0xFF (255) when not applicable)
//   bytes 2-3  reserved, 0xFF
//   byte 4     the address being acknowledged (the requester)
//   bytes 5-7  the PGN acknowledged, least significant byte first
//
//   NACK of PGN 0xFECA (65226) for SA 0xF3, sent by 0x21 to global:
//   0x18E8FF21  01 FF FF FF F3 CA FE 00

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "openvcu/j1939/id.hpp"

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_ACKNOWLEDGEMENT = 0xE800;        ///< SAE J1939-21 PGN 59392 Acknowledgement
inline constexpr std::size_t ACKNOWLEDGEMENT_LENGTH = 8;             ///< always 8 bytes
inline constexpr std::uint8_t ACKNOWLEDGEMENT_DEFAULT_PRIORITY = 6;  ///< J1939-21 default priority
inline constexpr std::uint8_t GROUP_FUNCTION_NOT_APPLICABLE = 0xFF;  ///< byte 1 when unused, 0xff (255)

/// The control byte (byte 0).
enum class AckControl : std::uint8_t {
  Positive = 0,       ///< ACK
  Negative = 1,       ///< NACK: the PGN is not supported
  AccessDenied = 2,   ///< PGN supported, security denied access
  CannotRespond = 3,  ///< PGN supported, cannot respond now (busy)
};

struct Acknowledgement {
  AckControl control{AckControl::Negative};
  std::uint8_t groupFunction{GROUP_FUNCTION_NOT_APPLICABLE};
  std::uint8_t address{GLOBAL_ADDRESS};  ///< the requester being answered
  std::uint32_t pgn{};                   ///< the PGN acknowledged (18 bits)
  friend constexpr bool operator==(const Acknowledgement&, const Acknowledgement&) = default;
};

using AcknowledgementPayload = std::array<std::uint8_t, ACKNOWLEDGEMENT_LENGTH>;

/// The 8 bytes of `ack` (the PGN masked to 18 bits).
/// NACK of 0xFECA for 0xF3 -> 01 FF FF FF F3 CA FE 00.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr AcknowledgementPayload encodeAcknowledgement(const Acknowledgement& ack) noexcept {
  const std::uint32_t pgn = ack.pgn & PGN_MASK;
  return AcknowledgementPayload{static_cast<std::uint8_t>(ack.control),
                                ack.groupFunction,
                                0xFF,
                                0xFF,
                                ack.address,
                                static_cast<std::uint8_t>(pgn & 0xFFu),
                                static_cast<std::uint8_t>((pgn >> 8) & 0xFFu),
                                static_cast<std::uint8_t>((pgn >> 16) & 0xFFu)};
}

/// The Acknowledgement in `data`; empty unless exactly 8 bytes arrive, the control byte
/// is 0..3 and the PGN fits 18 bits. The reserved bytes are not checked.
/// 01 FF FF FF F3 CA FE 00 -> {Negative, 0xFF, 0xF3, 65226}.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr std::optional<Acknowledgement> decodeAcknowledgement(
    std::span<const std::uint8_t> data) noexcept {
  if (data.size() != ACKNOWLEDGEMENT_LENGTH) return std::nullopt;
  if (data[0] > static_cast<std::uint8_t>(AckControl::CannotRespond)) return std::nullopt;
  const std::uint32_t pgn = static_cast<std::uint32_t>(data[5]) | (static_cast<std::uint32_t>(data[6]) << 8) |
                            (static_cast<std::uint32_t>(data[7]) << 16);
  if (pgn > PGN_MASK) return std::nullopt;
  return Acknowledgement{static_cast<AckControl>(data[0]), data[1], data[4], pgn};
}

/// CAN ID of an Acknowledgement from `sourceAddress` to `destination` (J1939-21 sends a
/// NACK to the global address). (6, 0x21, 0xFF) -> 0x18E8FF21.
[[nodiscard]] constexpr std::uint32_t acknowledgementCanId(std::uint8_t priority, std::uint8_t sourceAddress,
                                                           std::uint8_t destination = GLOBAL_ADDRESS) noexcept {
  return Id::fromPgn(PGN_ACKNOWLEDGEMENT, priority, sourceAddress, destination).toCanId();
}

static_assert(acknowledgementCanId(ACKNOWLEDGEMENT_DEFAULT_PRIORITY, 0x21) == 0x18E8FF21u);
static_assert(encodeAcknowledgement(Acknowledgement{AckControl::Negative, 0xFF, 0xF3, 0xFECA}) ==
              AcknowledgementPayload{0x01, 0xFF, 0xFF, 0xFF, 0xF3, 0xCA, 0xFE, 0x00});

}  // namespace openvcu::j1939
