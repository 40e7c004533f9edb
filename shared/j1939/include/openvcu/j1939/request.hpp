#pragma once
// SAE J1939-21 Request (PGN 59904): a PDU1 frame whose 3 data bytes carry the requested
// PGN, least significant byte first. The addressee answers with that PGN (or a NACK,
// acknowledgement.hpp); nobody NACKs a request sent to the global address.
//
//   0x00EA21F3  E6 FE 00  -> the VIC (SA 0xF3) asks the VCU (DA 0x21) for PGN 0xFEE6 (65254)
//   parseRequest(0x18EA21F3, true, E6 FE 00, {0x21}) -> Request{65254, 0xF3, global = false}

#include "openvcu/j1939/id.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_REQUEST = 0xEA00;         ///< SAE J1939-21 PGN 59904 Request
inline constexpr std::size_t REQUEST_LENGTH = 3;             ///< bytes carrying the requested PGN
inline constexpr std::size_t REQUEST_MAX_LENGTH = 8;         ///< some senders pad to 8 bytes
inline constexpr std::uint8_t REQUEST_DEFAULT_PRIORITY = 6;  ///< J1939-21 default for Request

using RequestPayload = std::array<std::uint8_t, REQUEST_LENGTH>;

/// The 3 Request bytes asking for `requestedPgn` (masked to 18 bits). 0xFEE6 -> E6 FE 00.
[[nodiscard]] constexpr RequestPayload encodeRequest(std::uint32_t requestedPgn) noexcept {
  const std::uint32_t pgn = requestedPgn & PGN_MASK;
  return RequestPayload{static_cast<std::uint8_t>(pgn & 0xFFu),
                        static_cast<std::uint8_t>((pgn >> 8) & 0xFFu),
                        static_cast<std::uint8_t>((pgn >> 16) & 0xFFu)};
}

/// The requested PGN; empty unless 3..8 bytes arrive and the value fits 18 bits.
/// Bytes after the third (padding) are ignored. E6 FE 00 -> 65254.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr std::optional<std::uint32_t> decodeRequest(
    std::span<const std::uint8_t> data) noexcept {
  if (data.size() < REQUEST_LENGTH || data.size() > REQUEST_MAX_LENGTH) return std::nullopt;
  const std::uint32_t pgn = static_cast<std::uint32_t>(data[0]) |
                            (static_cast<std::uint32_t>(data[1]) << 8) |
                            (static_cast<std::uint32_t>(data[2]) << 16);
  if (pgn > PGN_MASK) return std::nullopt;
  return pgn;
}

/// CAN ID of a Request from `sourceAddress` to `destination` (GLOBAL_ADDRESS asks everyone).
/// (0, 0xF3, 0x21) -> 0x00EA21F3; (6, 0x21, 0xF3) -> 0x18EAF321.
[[nodiscard]] constexpr std::uint32_t requestCanId(std::uint8_t priority,
                                                   std::uint8_t sourceAddress,
                                                   std::uint8_t destination) noexcept {
  return Id::fromPgn(PGN_REQUEST, priority, sourceAddress, destination).toCanId();
}

/// A Request as its addressee sees it (what can-rx hands can-tx).
struct Request {
  std::uint32_t pgn{};        ///< the requested PGN (18 bits)
  std::uint8_t requester{};   ///< the requester's source address
  bool global{};              ///< sent to the global address 0xFF (255): answered, never NACKed
  friend constexpr bool operator==(const Request&, const Request&) = default;
};

/// The addresses one node answers on: mine[address] is true for each of them.
using AddressSet = std::array<bool, 256>;

/// The Request in a received frame when it is one for an address in `mine` or for the
/// global address; empty for a standard frame, another PGN, a Request to another node or
/// a payload decodeRequest() refuses. The PGN check includes EDP and DP (PGN 0xEA00 exactly).
/// 0x18EA21F3 E6 FE 00 with mine[0x21] -> {65254, 0xF3, false}; 0x18EA10F3 ... -> empty.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr std::optional<Request> parseRequest(std::uint32_t canId, bool extended,
                                                            std::span<const std::uint8_t> data,
                                                            const AddressSet& mine) noexcept {
  if (!extended) return std::nullopt;
  const Id id = Id::fromCanId(canId);
  if (id.pgn() != PGN_REQUEST) return std::nullopt;
  const std::uint8_t destination = id.destination();
  const bool global = destination == GLOBAL_ADDRESS;
  if (!global && !mine[destination]) return std::nullopt;
  const std::optional<std::uint32_t> pgn = decodeRequest(data);
  if (!pgn) return std::nullopt;
  return Request{*pgn, id.sourceAddress, global};
}

/// A Request frame: its 29-bit CAN ID and its 3 data bytes.
struct RequestFrame {
  std::uint32_t canId{};
  RequestPayload payload{};
  friend constexpr bool operator==(const RequestFrame&, const RequestFrame&) = default;
};

/// The Request from `sourceAddress` to `destination` for `requestedPgn`.
/// (0xFEE6, 6, 0x21, 0xF3) -> {0x18EAF321, E6 FE 00}.
[[nodiscard]] constexpr RequestFrame buildRequest(std::uint32_t requestedPgn, std::uint8_t priority,
                                                  std::uint8_t sourceAddress, std::uint8_t destination) noexcept {
  return RequestFrame{requestCanId(priority, sourceAddress, destination), encodeRequest(requestedPgn)};
}

static_assert(requestCanId(0, 0xF3, 0x21) == 0x00EA21F3u);
static_assert(buildRequest(0xFEE6u, 6, 0x21, 0xF3) == RequestFrame{0x18EAF321u, RequestPayload{0xE6, 0xFE, 0x00}});
static_assert(encodeRequest(0xFEE6u) == RequestPayload{0xE6, 0xFE, 0x00});

}  // namespace openvcu::j1939
