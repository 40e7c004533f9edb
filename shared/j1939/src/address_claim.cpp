#include "openvcu/j1939/address_claim.hpp"

namespace openvcu::j1939 {

std::string_view claimStateName(ClaimState state) noexcept {
  switch (state) {
    case ClaimState::Idle:
      return "Idle";
    case ClaimState::Claiming:
      return "Claiming";
    case ClaimState::Claimed:
      return "Claimed";
    case ClaimState::CannotClaim:
      return "CannotClaim";
  }
  return "Unknown";
}

void AddressClaimer::start(std::int64_t nowNs, ClaimSink& sink) noexcept {
  m_cannotClaimDueNs.reset();
  const std::uint8_t preferred = m_config.preferredAddress;
  if (preferred <= MAX_CLAIMABLE_ADDRESS && !heldByHigherPriority(preferred)) {
    claim(preferred, nowNs, sink);
    return;
  }
  if (preferred <= MAX_CLAIMABLE_ADDRESS) {
    ++m_counters.addressesSkipped;
    if (const std::optional<Name> holder = m_table.nameAt(preferred)) sink.addressLost(preferred, *holder);
  }
  if (m_config.name.arbitraryAddressCapable) {
    claimNextFree(preferred, nowNs, sink);
  } else {
    giveUp(sink);
  }
}

void AddressClaimer::onAddressClaimed(std::uint8_t sourceAddress, const Name& name, std::int64_t nowNs,
                                      ClaimSink& sink) noexcept {
  poll(nowNs, sink);
  if (name == m_config.name) {
    ++m_counters.echoesIgnored;
    return;
  }
  if (!m_table.onClaim(sourceAddress, name, nowNs)) return;  // from the global address
  const bool haveAddress = m_state == ClaimState::Claiming || m_state == ClaimState::Claimed;
  if (!haveAddress || sourceAddress != m_address) return;
  if (hasPriorityOver(m_config.name, name)) {
    // We keep the address: say so again; the loser moves or sends Cannot Claim.
    ++m_counters.contestsWon;
    m_table.remove(sourceAddress);
    sendClaim(sink);
    return;
  }
  ++m_counters.contestsLost;
  sink.addressLost(sourceAddress, name);
  if (m_config.name.arbitraryAddressCapable) {
    claimNextFree(sourceAddress, nowNs, sink);
  } else {
    giveUp(sink);
  }
}

void AddressClaimer::onRequestForAddressClaimed(std::uint8_t destination, std::int64_t nowNs,
                                                ClaimSink& sink) noexcept {
  poll(nowNs, sink);
  const bool global = destination == GLOBAL_ADDRESS;
  switch (m_state) {
    case ClaimState::Idle:
      return;
    case ClaimState::Claiming:
    case ClaimState::Claimed:
      if (!global && destination != m_address) return;
      ++m_counters.requestsAnswered;
      sendClaim(sink);
      return;
    case ClaimState::CannotClaim:
      if (!global) return;
      ++m_counters.requestsAnswered;
      if (!m_cannotClaimDueNs) m_cannotClaimDueNs = nowNs + cannotClaimDelayNs(m_config.name);
      poll(nowNs, sink);  // a delay of 0 answers at once
      return;
  }
}

void AddressClaimer::poll(std::int64_t nowNs, ClaimSink& sink) noexcept {
  if (m_state == ClaimState::Claiming && nowNs >= m_windowEndNs) change(m_address, ClaimState::Claimed, sink);
  if (m_cannotClaimDueNs && nowNs >= *m_cannotClaimDueNs) {
    m_cannotClaimDueNs.reset();
    if (m_state == ClaimState::CannotClaim) sendCannotClaim(sink);
  }
}

std::optional<std::int64_t> AddressClaimer::nextDeadlineNs() const noexcept {
  std::optional<std::int64_t> next = m_cannotClaimDueNs;
  if (m_state == ClaimState::Claiming && (!next || m_windowEndNs < *next)) next = m_windowEndNs;
  return next;
}

bool AddressClaimer::mayTransmit() const noexcept {
  if (m_state == ClaimState::Claimed) return true;
  return m_state == ClaimState::Claiming && transmitsWithoutWait(m_address);
}

void AddressClaimer::claim(std::uint8_t address, std::int64_t nowNs, ClaimSink& sink) noexcept {
  m_windowEndNs = nowNs + ADDRESS_CLAIM_WAIT_NS;
  change(address, ClaimState::Claiming, sink);
  sendClaim(sink);
}

void AddressClaimer::claimNextFree(std::uint8_t lostAddress, std::int64_t nowNs, ClaimSink& sink) noexcept {
  const std::uint8_t last = m_config.rangeLast > MAX_CLAIMABLE_ADDRESS ? MAX_CLAIMABLE_ADDRESS : m_config.rangeLast;
  const std::uint8_t first = m_config.rangeFirst;
  if (first > last) {
    giveUp(sink);
    return;
  }
  // The address after the lost one when it lies in the range, else the range's first;
  // once round the range, wrapping at its end. The lost address is in the table (its
  // winner), so it is skipped like every address known taken.
  const unsigned count = static_cast<unsigned>(last - first) + 1;
  const unsigned startOffset = inRange(lostAddress) ? static_cast<unsigned>(lostAddress - first) + 1 : 0;
  for (unsigned step = 0; step < count; ++step) {
    const auto candidate = static_cast<std::uint8_t>(first + (startOffset + step) % count);
    if (m_table.taken(candidate)) {
      ++m_counters.addressesSkipped;
      continue;
    }
    claim(candidate, nowNs, sink);
    return;
  }
  giveUp(sink);
}

void AddressClaimer::giveUp(ClaimSink& sink) noexcept {
  change(NULL_ADDRESS, ClaimState::CannotClaim, sink);
  sendCannotClaim(sink);
}

void AddressClaimer::sendClaim(ClaimSink& sink) noexcept {
  ++m_counters.claimsSent;
  sink.send(addressClaimedFrame(m_address, m_config.name));
}

void AddressClaimer::sendCannotClaim(ClaimSink& sink) noexcept {
  ++m_counters.cannotClaimSent;
  sink.send(cannotClaimFrame(m_config.name));
}

void AddressClaimer::change(std::uint8_t address, ClaimState state, ClaimSink& sink) noexcept {
  const std::uint8_t old = m_address;
  const ClaimState oldState = m_state;
  m_address = address;
  m_state = state;
  if (old != address || oldState != state) sink.addressChanged(old, address, state);
}

bool AddressClaimer::inRange(std::uint8_t address) const noexcept {
  return address >= m_config.rangeFirst && address <= m_config.rangeLast && address <= MAX_CLAIMABLE_ADDRESS;
}

bool AddressClaimer::heldByHigherPriority(std::uint8_t address) const noexcept {
  const std::optional<Name> holder = m_table.nameAt(address);
  return holder && hasPriorityOver(*holder, m_config.name);
}

}  // namespace openvcu::j1939
