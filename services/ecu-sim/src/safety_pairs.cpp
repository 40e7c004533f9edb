#include "safety_pairs.hpp"

#include <algorithm>
#include <array>

namespace openvcu::ecusim {

SafetyPairs::SafetyPairs(const std::vector<config::SafetyCheckConfig>& pairs) {
  for (const config::SafetyCheckConfig& pair : pairs) {
    const j1939::SafetyPairConfig checker{pair.dataCanId, pair.srvtNs, pair.sctNs};
    m_pairs.push_back(Pair{j1939::SafetyPairChecker(checker), j1939::safetyHeaderCanId(pair.dataCanId)});
  }
}

SafetyPairs::Outcome SafetyPairs::receive(const can::Frame& frame, std::int64_t atNs, bool otherCrc) noexcept {
  // As a J1939-76 receiver: an SHM is PGN 0x0E00 from the SDM's SA to its DA (any priority)
  // naming this SDM in its bytes; the SDM is the next frame after it with the SDM's PGN, SA
  // and DA, whatever its priority (j1939::sameSafetyIdentity). HHEA's PropA_C4 (0x18EFF321)
  // shares S1_ES's (0x0CEFF321): sent between S1_ES's SHM and SDM it is taken for the SDM and
  // fails the CRC. Without an SHM waiting, only the SDM's own identifier is judged (an SDM
  // without its SHM: MissingHeader), unless another frame just took its SHM: that pair has
  // its verdict already (one per SHM, so a fault is reported as what it is, not flipping).
  // Before the first SHM since the start or reset() an SDM is not judged: a receiver that
  // comes up between a pair's SHM and SDM has not missed a header (it was not listening).
  // Other frames of its identity are ordinary frames.
  for (Pair& pair : m_pairs) {
    const std::uint32_t dataId = pair.checker.dataCanId();
    if (frame.extended() && j1939::sameSafetyIdentity(frame.id, pair.headerId)) {
      const auto header = j1939::parseSafetyHeader(frame.payload());
      if (header && !header->matchesData(dataId)) continue;  // another SDM's SHM to the same DA (HVESSC1's)
      pair.checker.onHeader(frame.payload(), atNs);
      pair.awaitingData = true;
      pair.headerTakenByOther = false;
      pair.headerSeen = true;
      return Outcome::Header;
    }
    const bool next = pair.awaitingData && frame.extended() && j1939::sameSafetyIdentity(frame.id, dataId);
    if (!next && frame.id != dataId) continue;
    if (!pair.headerSeen) return Outcome::NotUsed;
    if (!next && pair.headerTakenByOther) {
      pair.headerTakenByOther = false;  // the SDM whose SHM another frame took: not used, judged already
      return Outcome::NotUsed;
    }
    pair.headerTakenByOther = next && frame.id != dataId;
    pair.awaitingData = false;
    std::array<std::uint8_t, 8> data{};
    const std::size_t length = std::min<std::size_t>(frame.length, data.size());
    std::copy_n(frame.data.begin(), length, data.begin());
    if (otherCrc) data[7] ^= 0x01;  // a receiver that expects another CRC
    const j1939::SafetyResult result = pair.checker.onData(std::span<const std::uint8_t>(data.data(), length), atNs);
    m_stats.last = result;
    if (result == j1939::SafetyResult::Ok) {
      ++m_stats.ok;
    } else if (result != j1939::SafetyResult::Synchronising) {
      ++m_stats.refused;
      m_stats.lastRefusal = result;
    }
    if (result != j1939::SafetyResult::Synchronising && m_reported != result) {
      m_reported = result;
      m_changed = true;
    }
    return result == j1939::SafetyResult::Ok ? Outcome::Used : Outcome::NotUsed;
  }
  return Outcome::NotPaired;
}

void SafetyPairs::reset() noexcept {
  for (Pair& pair : m_pairs) {
    pair.checker.reset();
    pair.awaitingData = false;
    pair.headerTakenByOther = false;
    pair.headerSeen = false;
  }
}

std::optional<j1939::SafetyResult> SafetyPairs::takeChange() noexcept {
  if (!m_changed) return std::nullopt;
  m_changed = false;
  return m_reported;
}

}  // namespace openvcu::ecusim
