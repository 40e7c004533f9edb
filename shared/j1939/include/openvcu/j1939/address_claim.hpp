#pragma once
// SAE J1939-81 address claim for one controller application (CA) on one bus (design note:
// docs/design/j1939-address-claim.md). The CA announces its NAME on an address with Address
// Claimed (PGN 60928) sent to global; a node claiming the same address with a lower NAME
// takes it, a higher NAME is answered with our claim again. A CA without an address says so
// with Cannot Claim: the same PGN from the null address 0xFE (254).
//
//   0x18EEFF21  01 00 00 00 00 80 02 B0   Address Claimed: NAME 0xB002800000000001 on 0x21
//   0x18EEFFFE  01 00 00 00 00 80 02 B0   Cannot Claim: the same NAME has no address
//   0x18EA21F3  00 EE 00                  Request for Address Claimed from 0xF3 to 0x21
//
//   start(): claim the preferred address  -> Claiming
//     250 ms without a contest            -> Claimed (J1939-81: addresses 0-127 and 248-253
//                                            may transmit at once, others after the 250 ms)
//     a lower NAME claims our address     -> if arbitrary address capable: the next free
//                                            address of the range, Claiming again;
//                                            else (or the range is full): Cannot Claim
//     a higher NAME claims our address    -> our claim again (defended)
//     every lost address                  -> ClaimSink::addressLost(address, claimant NAME)
//   Without an address (Cannot Claim) further claims only fill the table: the CA stays
//   where it is until start() runs again, however often its old address is claimed.

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "openvcu/j1939/address_table.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/name.hpp"

namespace openvcu::j1939 {

inline constexpr std::uint32_t PGN_ADDRESS_CLAIMED = 0xEE00;  ///< SAE J1939-81 PGN 60928 Address Claimed / Cannot Claim
inline constexpr std::uint32_t PGN_COMMANDED_ADDRESS =
    0xFED8;                                                ///< SAE J1939-81 PGN 65240 Commanded Address (not handled)
inline constexpr std::uint8_t ADDRESS_CLAIM_PRIORITY = 6;  ///< J1939-81 default priority of Address Claimed
/// J1939-81: a CA whose address is 128..247 waits 250 ms after its claim before other traffic.
inline constexpr std::int64_t ADDRESS_CLAIM_WAIT_NS = 250'000'000;
/// J1939-81: Cannot Claim in answer to a Request waits 0.6 ms x a pseudo-random 0..255, 0..153 ms.
inline constexpr std::int64_t CANNOT_CLAIM_DELAY_STEP_NS = 600'000;
inline constexpr std::int64_t CANNOT_CLAIM_MAX_DELAY_NS = 255 * CANNOT_CLAIM_DELAY_STEP_NS;  ///< 153 ms
inline constexpr std::uint8_t DEFAULT_CLAIM_RANGE_FIRST = 128;  ///< 0x80: J1939 self-configurable addresses
inline constexpr std::uint8_t DEFAULT_CLAIM_RANGE_LAST = 247;   ///< 0xF7

/// An Address Claimed (or Cannot Claim) frame to send: 29-bit ID and the 8 NAME bytes.
struct ClaimFrame {
  std::uint32_t canId{};
  NamePayload data{};
  friend constexpr bool operator==(const ClaimFrame&, const ClaimFrame&) = default;
};

/// CAN ID of Address Claimed from `sourceAddress` to global at priority 6.
/// 0x21 -> 0x18EEFF21; NULL_ADDRESS (Cannot Claim) -> 0x18EEFFFE.
[[nodiscard]] constexpr std::uint32_t addressClaimedCanId(std::uint8_t sourceAddress) noexcept {
  return Id::fromPgn(PGN_ADDRESS_CLAIMED, ADDRESS_CLAIM_PRIORITY, sourceAddress, GLOBAL_ADDRESS).toCanId();
}

/// Our claim of `address` for `name`.
[[nodiscard]] constexpr ClaimFrame addressClaimedFrame(std::uint8_t address, const Name& name) noexcept {
  return ClaimFrame{addressClaimedCanId(address), encodeName(name)};
}

/// Cannot Claim for `name`: Address Claimed from the null address.
[[nodiscard]] constexpr ClaimFrame cannotClaimFrame(const Name& name) noexcept {
  return addressClaimedFrame(NULL_ADDRESS, name);
}

/// A received Address Claimed: who sent it and the NAME it carries.
struct AddressClaimed {
  std::uint8_t sourceAddress{};  ///< NULL_ADDRESS for Cannot Claim
  Name name;
  friend constexpr bool operator==(const AddressClaimed&, const AddressClaimed&) = default;
};

/// The Address Claimed in a received frame; empty for a standard frame, another PGN (EDP
/// and DP included) or a payload that is not exactly 8 bytes. Any destination is accepted
/// (J1939-81 sends it to global; some nodes answer a Request to the requester).
/// 0x18EEFF21 01 00 00 00 00 80 02 B0 -> {0x21, NAME 0xB002800000000001}.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr std::optional<AddressClaimed> parseAddressClaimed(std::uint32_t canId, bool extended,
                                                                          std::span<const std::uint8_t> data) noexcept {
  if (!extended) return std::nullopt;
  const Id id = Id::fromCanId(canId);
  if (id.pgn() != PGN_ADDRESS_CLAIMED) return std::nullopt;
  const std::optional<Name> name = decodeName(data);
  if (!name) return std::nullopt;
  return AddressClaimed{id.sourceAddress, *name};
}

/// J1939-81: a CA on 0..127 or 248..253 may send other messages right after its claim.
[[nodiscard]] constexpr bool transmitsWithoutWait(std::uint8_t address) noexcept {
  return address <= 127 || (address >= 248 && address <= MAX_CLAIMABLE_ADDRESS);
}

/// The delay before a Cannot Claim answers a Request: 0.6 ms x a number 0..255 taken from
/// the NAME (FNV-1a over its 8 bytes, folded to one byte), so it is the same on every run
/// and differs between NAMEs as J1939-81's pseudo-random one is meant to.
[[nodiscard]] constexpr std::int64_t cannotClaimDelayNs(const Name& name) noexcept {
  std::uint32_t hash = 2166136261u;  // FNV-1a offset basis
  for (const std::uint8_t byte : encodeName(name)) {
    hash ^= byte;
    hash *= 16777619u;  // FNV prime
  }
  const std::uint32_t folded = (hash ^ (hash >> 8) ^ (hash >> 16) ^ (hash >> 24)) & 0xFFu;
  return static_cast<std::int64_t>(folded) * CANNOT_CLAIM_DELAY_STEP_NS;
}

enum class ClaimState : std::uint8_t {
  Idle,         ///< start() not called yet
  Claiming,     ///< our claim is out; its 250 ms contention window runs
  Claimed,      ///< 250 ms passed since the claim without a lost contest
  CannotClaim,  ///< no address: we lost and could not move; only Cannot Claim is sent
};

/// "Idle", "Claiming", "Claimed", "CannotClaim" for logs.
[[nodiscard]] std::string_view claimStateName(ClaimState state) noexcept;

/// Where the claimer puts its output; called synchronously from the claimer's methods. The
/// sink must not call back into the claimer.
/// Why virtual: one indirect call per output, no std::function and no allocation.
class ClaimSink {
 public:
  virtual ~ClaimSink() = default;
  /// An Address Claimed or Cannot Claim frame to transmit now.
  virtual void send(const ClaimFrame& frame) noexcept = 0;
  /// Our address or state changed (also Claiming -> Claimed on the same address). Comes
  /// before the frame that announces a new address: from this call on, send nothing from
  /// `oldAddress`.
  virtual void addressChanged(std::uint8_t oldAddress, std::uint8_t newAddress, ClaimState state) noexcept = 0;
  /// `claimant`, a NAME of higher priority, took `address` from us: it claimed the address
  /// we held or were claiming, or held our preferred address at start(). Comes before the
  /// addressChanged() that moves us (or leaves us without an address). A claimant that
  /// takes an address we no longer use does not call it again. Default: nothing.
  virtual void addressLost(std::uint8_t address, const Name& claimant) noexcept {
    (void)address;
    (void)claimant;
  }
};

struct AddressClaimerConfig {
  Name name;  ///< ours; its arbitraryAddressCapable bit allows moving to the range
  /// Claimed first. NULL_ADDRESS or GLOBAL_ADDRESS: none (an arbitrary address capable CA
  /// starts in the range, another one sends Cannot Claim at start).
  std::uint8_t preferredAddress{NULL_ADDRESS};
  /// Addresses tried, in order after the lost one, when arbitrary address capable. Empty
  /// when rangeFirst > rangeLast; addresses above 253 are never tried.
  std::uint8_t rangeFirst{DEFAULT_CLAIM_RANGE_FIRST};
  std::uint8_t rangeLast{DEFAULT_CLAIM_RANGE_LAST};
};

/// What happened since construction (start() does not reset them).
struct ClaimCounters {
  std::uint64_t claimsSent{};        ///< Address Claimed frames: claims, defences, answers
  std::uint64_t cannotClaimSent{};   ///< Cannot Claim frames
  std::uint64_t contestsWon{};       ///< a higher NAME claimed our address; we defended
  std::uint64_t contestsLost{};      ///< a lower NAME claimed our address; we left it
  std::uint64_t addressesSkipped{};  ///< our next address was known taken before claiming
  std::uint64_t requestsAnswered{};  ///< Requests for Address Claimed answered (or scheduled)
  std::uint64_t echoesIgnored{};     ///< claims carrying our own NAME (our own frames looped back)
  friend constexpr bool operator==(const ClaimCounters&, const ClaimCounters&) = default;
};

/// J1939-81 address claim on one bus. Time is passed in; call poll() at nextDeadlineNs()
/// (or on any timer). Each input applies passed deadlines first, so the result does not
/// depend on how often poll() runs. Other nodes' claims fill table().
///
/// Feed it every Address Claimed frame of the bus (parseAddressClaimed(), our own echoes
/// included: they are recognised by the NAME) and every Request for PGN 60928 addressed to
/// global or to us (parseRequest() with our address, pgn == PGN_ADDRESS_CLAIMED).
///
/// @note not thread-safe: one thread drives one claimer. Real-time safe after
///       construction: noexcept, no allocation; O(254) per input at most.
class AddressClaimer {
 public:
  explicit AddressClaimer(const AddressClaimerConfig& config) noexcept : m_config(config) {}

  /// Claims the preferred address (or, when none or a lower NAME is known to hold it and
  /// we are arbitrary address capable, a free one of the range). Called again, starts over
  /// (the table and the counters stay).
  void start(std::int64_t nowNs, ClaimSink& sink) noexcept;

  /// An Address Claimed seen on the bus, from `sourceAddress` (NULL_ADDRESS: Cannot Claim).
  void onAddressClaimed(std::uint8_t sourceAddress, const Name& name, std::int64_t nowNs, ClaimSink& sink) noexcept;

  /// A Request for Address Claimed to `destination`. To global or to our address it is
  /// answered with our claim at once; without an address (CannotClaim), a request to global
  /// is answered with Cannot Claim after cannotClaimDelayNs() (in poll()).
  void onRequestForAddressClaimed(std::uint8_t destination, std::int64_t nowNs, ClaimSink& sink) noexcept;

  /// Applies every deadline at or before `nowNs`: the end of the 250 ms window, a delayed
  /// Cannot Claim.
  void poll(std::int64_t nowNs, ClaimSink& sink) noexcept;

  /// The earliest pending deadline; empty when none.
  [[nodiscard]] std::optional<std::int64_t> nextDeadlineNs() const noexcept;

  [[nodiscard]] ClaimState state() const noexcept { return m_state; }
  /// Our address while Claiming or Claimed; NULL_ADDRESS otherwise.
  [[nodiscard]] std::uint8_t address() const noexcept { return m_address; }
  /// Whether other messages may be sent from address(): Claimed, or Claiming on an address
  /// that transmitsWithoutWait().
  [[nodiscard]] bool mayTransmit() const noexcept;

  [[nodiscard]] const ClaimCounters& counters() const noexcept { return m_counters; }
  /// The other nodes seen on the bus (never us).
  [[nodiscard]] const AddressTable& table() const noexcept { return m_table; }
  [[nodiscard]] const AddressClaimerConfig& config() const noexcept { return m_config; }

 private:
  void claim(std::uint8_t address, std::int64_t nowNs, ClaimSink& sink) noexcept;
  void claimNextFree(std::uint8_t lostAddress, std::int64_t nowNs, ClaimSink& sink) noexcept;
  void giveUp(ClaimSink& sink) noexcept;
  void sendClaim(ClaimSink& sink) noexcept;
  void sendCannotClaim(ClaimSink& sink) noexcept;
  void change(std::uint8_t address, ClaimState state, ClaimSink& sink) noexcept;
  [[nodiscard]] bool inRange(std::uint8_t address) const noexcept;
  [[nodiscard]] bool heldByHigherPriority(std::uint8_t address) const noexcept;

  AddressClaimerConfig m_config;
  AddressTable m_table;
  ClaimCounters m_counters;
  ClaimState m_state{ClaimState::Idle};
  std::uint8_t m_address{NULL_ADDRESS};
  std::int64_t m_windowEndNs{};                    ///< Claiming: end of the 250 ms window
  std::optional<std::int64_t> m_cannotClaimDueNs;  ///< a delayed Cannot Claim
};

static_assert(addressClaimedCanId(0x21) == 0x18EEFF21u);
static_assert(addressClaimedCanId(NULL_ADDRESS) == 0x18EEFFFEu);
static_assert(cannotClaimDelayNs(name_example::EXAMPLE) <= CANNOT_CLAIM_MAX_DELAY_NS);
static_assert(CANNOT_CLAIM_MAX_DELAY_NS == 153'000'000);

}  // namespace openvcu::j1939
