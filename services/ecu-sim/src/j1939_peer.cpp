#include "j1939_peer.hpp"

#include <algorithm>
#include <string>

#include "openvcu/j1939/acknowledgement.hpp"
#include "openvcu/j1939/address_claim.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/dm_encode.hpp"
#include "openvcu/j1939/request.hpp"

namespace openvcu::ecusim {
namespace {

j1939::TpReceiverConfig receiverConfig(std::uint8_t address) {
  j1939::TpReceiverConfig config;
  config.ownAddress = address;
  config.maxSessions = 2;
  config.maxHeldSessions = 1;
  return config;
}

std::string hex(std::uint32_t value) {
  static constexpr char DIGITS[] = "0123456789ABCDEF";
  std::string text;
  do {
    text.insert(text.begin(), DIGITS[value & 0xFu]);
    value >>= 4;
  } while (value != 0);
  return "0x" + text;
}

/// Printable ASCII of an identification answer; '*' field delimiters stay.
std::string text(std::span<const std::uint8_t> data) {
  std::string out;
  for (const std::uint8_t byte : data) out += (byte >= 0x20 && byte < 0x7F) ? static_cast<char>(byte) : '.';
  return out;
}

}  // namespace

J1939Peer::J1939Peer(const config::SimPeerConfig& config, service::Logger& log)
    : m_config(config),
      m_log(&log),
      m_tp(receiverConfig(config.address)),
      m_answers(new std::atomic<std::int64_t>[config.requestedPgns.size()] {}),
      m_outstanding(new Outstanding[config.requestedPgns.size()]{}),
      m_address(config.address) {}

void J1939Peer::start(std::int64_t nowNs) noexcept {
  m_startNs = nowNs;
  m_nowNs = nowNs;
  setOwn(m_config.address);
  queueClaim(m_address);
  // J1939-81: a node that joins asks everyone for their claims (a global Request for
  // Address Claimed), so the table also holds the nodes that claimed before it started.
  const j1939::RequestFrame request = j1939::buildRequest(j1939::PGN_ADDRESS_CLAIMED, j1939::REQUEST_DEFAULT_PRIORITY,
                                                          m_address, j1939::GLOBAL_ADDRESS);
  queue(request.canId, request.payload);
}

std::int64_t J1939Peer::nextDueNs() const noexcept {
  std::int64_t due = NEVER;
  if (m_queued > 0) due = m_nowNs;
  if (m_startNs >= 0 && m_next < m_config.script.size()) due = std::min(due, m_startNs + m_config.script[m_next].atNs);
  if (const auto tp = m_tp.nextDeadlineNs()) due = std::min(due, *tp);
  return due;
}

void J1939Peer::receive(std::size_t busIndex, const can::Frame& frame, std::int64_t atNs) noexcept {
  if (busIndex != m_config.busIndex || !frame.extended() || m_startNs < 0) return;
  m_nowNs = atNs;
  const std::span<const std::uint8_t> data = frame.payload();
  if (const auto claim = j1939::parseAddressClaimed(frame.id, true, data)) {
    onClaim(claim->sourceAddress, claim->name, atNs);
    return;
  }
  j1939::AddressSet mine{};
  if (m_address != j1939::NULL_ADDRESS) mine[m_address] = true;
  if (const auto request = j1939::parseRequest(frame.id, true, data, mine)) {
    // J1939-81: a Request for Address Claimed is answered with our claim (Cannot Claim
    // when we have no address).
    if (request->pgn == j1939::PGN_ADDRESS_CLAIMED) queueClaim(m_address);
    return;
  }
  const j1939::Id id = j1939::Id::fromCanId(frame.id);
  const std::uint32_t pgn = id.pgn();
  if (pgn == j1939::PGN_TP_CM || pgn == j1939::PGN_TP_DT) {
    m_tp.onFrame(frame.id, data, atNs, *this);
    return;
  }
  if (id.sourceAddress == m_address) return;
  const std::uint8_t destination = id.destination();
  if (destination != j1939::GLOBAL_ADDRESS && destination != m_address) return;
  if (pgn == j1939::PGN_ACKNOWLEDGEMENT && destination == m_address) {
    nacks.fetch_add(1, std::memory_order_relaxed);
    m_log->warning("j1939 peer: Acknowledgement from " + hex(id.sourceAddress) + " control " +
                   std::to_string(data.empty() ? 0 : data[0]) + " for PGN " +
                   std::to_string(data.size() >= 8 ? (data[5] | (data[6] << 8) | (data[7] << 16)) : 0));
    return;
  }
  onMessage(pgn, id.sourceAddress, data);
}

void J1939Peer::onClaim(std::uint8_t source, const j1939::Name& name, std::int64_t atNs) noexcept {
  if (name == m_config.name) return;  // our own claim (a bus may echo it)
  claimsSeen.fetch_add(1, std::memory_order_relaxed);
  m_table.onClaim(source, name, atNs);
  if (name == m_config.vcuName) {
    const std::int64_t address = source == j1939::NULL_ADDRESS ? -1 : source;
    if (vcuAddress.exchange(address, std::memory_order_relaxed) != address) {
      m_log->info("j1939 peer: the VCU claimed " +
                  (address < 0 ? std::string("no address (Cannot Claim)") : hex(static_cast<std::uint32_t>(address))));
    }
  }
  if (source != m_address || m_address == j1939::NULL_ADDRESS) return;
  // J1939-81 contest for our address: the lower NAME keeps it.
  if (j1939::hasPriorityOver(m_config.name, name)) {
    queueClaim(m_address);
  } else {
    m_log->warning("j1939 peer: lost " + hex(m_address) + " to NAME " +
                   hex(static_cast<std::uint32_t>(name.toValue() >> 32)) + "...; Cannot Claim");
    setOwn(j1939::NULL_ADDRESS);
    queueClaim(j1939::NULL_ADDRESS);
  }
}

void J1939Peer::onMessage(std::uint32_t pgn, std::uint8_t source, std::span<const std::uint8_t> data) noexcept {
  const auto& pgns = m_config.requestedPgns;
  const auto found = std::find(pgns.begin(), pgns.end(), pgn);
  if (found == pgns.end()) return;
  const auto index = static_cast<std::size_t>(found - pgns.begin());
  Outstanding& outstanding = m_outstanding[index];
  if (!outstanding.waiting || (outstanding.from != j1939::GLOBAL_ADDRESS && outstanding.from != source)) return;
  outstanding.waiting = false;
  m_answers[index].fetch_add(1, std::memory_order_relaxed);
  std::string line = "j1939 peer: answer PGN " + std::to_string(pgn) + " from " + hex(source) + ", " +
                     std::to_string(data.size()) + " bytes";
  if (pgn == j1939::PGN_DM1 || pgn == j1939::PGN_DM2) {
    if (const std::optional<j1939::Dm1> dm = j1939::decodeDm1(data)) {
      if (pgn == j1939::PGN_DM1 && vcuAddress.load(std::memory_order_relaxed) == source) {
        dm1Dtcs.store(static_cast<std::int64_t>(dm->dtcCount), std::memory_order_relaxed);
      }
      line += ", " + std::to_string(dm->dtcCount) + " DTC(s)";
      for (const j1939::Dtc& dtc : dm->activeDtcs()) {
        line += " SPN " + std::to_string(dtc.spn) + " FMI " + std::to_string(dtc.fmi) + " OC " +
                std::to_string(dtc.occurrenceCount);
      }
    } else {
      line += ", not a valid DM1/DM2 layout";
    }
  } else if (pgn == j1939::PGN_SOFTWARE_IDENTIFICATION || pgn == j1939::PGN_ECU_IDENTIFICATION ||
             pgn == j1939::PGN_COMPONENT_IDENTIFICATION) {
    line += ": \"" + text(pgn == j1939::PGN_SOFTWARE_IDENTIFICATION && !data.empty() ? data.subspan(1) : data) + "\"";
  }
  m_log->info(line);
}

void J1939Peer::runStep(const config::SimPeerStep& step) noexcept {
  if (step.kind == config::SimPeerStep::Kind::Claim) {
    m_log->info("j1939 peer: claims " + hex(step.address));
    setOwn(step.address);
    queueClaim(step.address);
    return;
  }
  std::uint8_t to = step.to;
  if (step.toVcu) {
    const std::int64_t vcu = vcuAddress.load(std::memory_order_relaxed);
    if (vcu < 0) {
      m_log->warning("j1939 peer: no claim of the VCU seen; Request for PGN " + std::to_string(step.pgn) + " not sent");
      return;
    }
    to = static_cast<std::uint8_t>(vcu);
  }
  const std::uint8_t from = m_address;  // NULL_ADDRESS: J1939-81 allows Requests from it
  const j1939::RequestFrame request = j1939::buildRequest(step.pgn, j1939::REQUEST_DEFAULT_PRIORITY, from, to);
  queue(request.canId, request.payload);
  const auto& pgns = m_config.requestedPgns;
  const auto index = static_cast<std::size_t>(std::find(pgns.begin(), pgns.end(), step.pgn) - pgns.begin());
  m_outstanding[index] = Outstanding{true, to};
  requestsSent.fetch_add(1, std::memory_order_relaxed);
  m_log->info("j1939 peer: requests PGN " + std::to_string(step.pgn) + " from " + hex(to));
}

void J1939Peer::setOwn(std::uint8_t address) noexcept {
  m_address = address;
  ownAddress.store(address == j1939::NULL_ADDRESS ? -1 : address, std::memory_order_relaxed);
  m_tp.setOwnAddress(address);
}

void J1939Peer::queueClaim(std::uint8_t address) noexcept {
  const j1939::ClaimFrame claim = j1939::addressClaimedFrame(address, m_config.name);
  queue(claim.canId, claim.data);
}

void J1939Peer::queue(std::uint32_t canId, std::span<const std::uint8_t> data) noexcept {
  if (m_queued == QUEUE) return;  // more than a step's worth: the oldest stay, this one is dropped
  can::Frame& frame = m_queue[m_queued++];
  frame = can::Frame{};
  frame.id = canId;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = static_cast<std::uint8_t>(std::min(data.size(), frame.data.size()));
  std::copy_n(data.begin(), frame.length, frame.data.begin());
}

void J1939Peer::send(const j1939::TpFrame& frame) noexcept {
  queue(frame.canId, {frame.data.data(), frame.length});
}

void J1939Peer::completed(const j1939::TpMessage& message) noexcept {
  tpCompleted.fetch_add(1, std::memory_order_relaxed);
  onMessage(message.pgn, message.source, message.data);
}

void J1939Peer::event(const j1939::TpEvent& event) noexcept {
  if (event.kind == j1939::TpEventKind::Completed || event.kind == j1939::TpEventKind::Ignored) return;
  m_log->warning("j1939 peer: TP session from " + hex(event.source) + " PGN " + std::to_string(event.pgn) + ": " +
                 std::string(j1939::tpEventKindName(event.kind)));
}

}  // namespace openvcu::ecusim
