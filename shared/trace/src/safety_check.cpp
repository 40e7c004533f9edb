// J1939-76 pairs in a timeline: routing as a receiver does, verdicts with their numbers,
// the SHM -> SDM delta, silent SHM senders (design: docs/design/trace-analysis.md).
#include "safety_check.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <optional>

#include "openvcu/j1939/id.hpp"

namespace openvcu::trace::detail {
namespace {

using j1939::SafetyResult;

/// SCT of a pair found on the bus whose SDM has no known cycle: DEFAULT_SCT_CYCLES x 1 s.
constexpr std::int64_t UNKNOWN_CYCLE_NS = 1'000'000'000;

std::string hex32(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", value);
  return text;
}

std::string hex8(std::uint8_t value) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", value);
  return text;
}

/// 292000 -> "292 us"; sub-microsecond digits dropped.
std::string micros(std::int64_t ns) {
  return std::to_string(ns / 1000) + " us";
}

bool usable(const TraceFrame& frame) noexcept {
  return frame.frame.extended() && (frame.frame.flags & (can::FLAG_ERROR | can::FLAG_RTR)) == 0;
}

bool isHeader(std::uint32_t canId) noexcept {
  return j1939::pgnOf(canId) == j1939::PGN_SAFETY_HEADER;
}

/// The SDM identifier an SHM names (its own priority), when the SHM is self-consistent:
/// the SDM's SA is the SHM's SA and the SDM's destination is the SHM's DA.
std::optional<std::uint32_t> namedData(std::uint32_t headerId, const j1939::SafetyHeader& header) noexcept {
  const j1939::Id shm = j1939::Id::fromCanId(headerId);
  j1939::Id sdm;
  sdm.priority = shm.priority;
  sdm.extendedDataPage = header.sdmExtendedDataPage;
  sdm.dataPage = header.sdmDataPage;
  sdm.pduFormat = header.sdmPduFormat;
  sdm.pduSpecific = header.sdmPduSpecific;
  sdm.sourceAddress = header.sdmSourceAddress;
  if (sdm.sourceAddress != shm.sourceAddress || sdm.destination() != shm.pduSpecific) return std::nullopt;
  return sdm.toCanId();
}

std::string headerFields(const j1939::SafetyHeader& header) {
  return "EDP " + std::to_string(header.sdmExtendedDataPage ? 1 : 0) + " DP " +
         std::to_string(header.sdmDataPage ? 1 : 0) + " PF " + hex8(header.sdmPduFormat) + " PS " +
         hex8(header.sdmPduSpecific) + " SA " + hex8(header.sdmSourceAddress);
}

std::int64_t deltaTolerance(std::int64_t deltaNs) noexcept {
  return std::max(DELTA_TOLERANCE_NS, deltaNs * DELTA_TOLERANCE_PERCENT / 100);
}

}  // namespace

SafetyCheck::SafetyCheck(const AnalysisSetup& setup)
    : m_setup(&setup), m_matcher(setup.database, setup.match), m_configuredSeen(setup.safetyPairs.size(), 0) {
  for (const SafetyPairSetup& pair : setup.safetyPairs) m_sdmSources.set(pair.dataCanId & 0xFFu);
  m_pairs.reserve(setup.safetyPairs.empty() ? 16 : setup.safetyPairs.size());
}

SafetyCheck::Pair* SafetyCheck::addPair(std::uint16_t bus, std::uint32_t dataCanId, std::int32_t message,
                                        std::int32_t configIndex, const SafetyPairSetup* configured) {
  j1939::SafetyPairConfig config{dataCanId, DEFAULT_SRVT_NS, 0};
  std::int64_t deltaNs = 0;
  if (configured != nullptr) {
    config.maxHeaderToDataNs = configured->maxHeaderToDataNs > 0 ? configured->maxHeaderToDataNs : DEFAULT_SRVT_NS;
    config.maxHeaderCycleNs = configured->maxHeaderCycleNs;
    deltaNs = configured->deltaNs;
  } else {
    const bool knownCycle = message >= 0 && static_cast<std::size_t>(message) < m_setup->expectedCycleNs.size() &&
                            m_setup->expectedCycleNs[static_cast<std::size_t>(message)] > 0;
    config.maxHeaderCycleNs =
        DEFAULT_SCT_CYCLES *
        (knownCycle ? m_setup->expectedCycleNs[static_cast<std::size_t>(message)] : UNKNOWN_CYCLE_NS);
  }
  if (config.maxHeaderCycleNs <= 0) config.maxHeaderCycleNs = DEFAULT_SCT_CYCLES * UNKNOWN_CYCLE_NS;
  Pair& pair = m_pairs.emplace_back(config);
  pair.configIndex = configIndex;
  pair.stats.bus = bus;
  pair.stats.message = message;
  pair.stats.dataCanId = dataCanId;
  pair.stats.discovered = configured == nullptr;
  pair.stats.deltaNs = deltaNs;
  pair.stats.maxHeaderToDataNs = config.maxHeaderToDataNs;
  pair.stats.maxHeaderCycleNs = config.maxHeaderCycleNs;
  const bool named = message >= 0 && static_cast<std::size_t>(message) < m_setup->database.messages.size();
  pair.name =
      (named ? m_setup->database.messages[static_cast<std::size_t>(message)].name + " (" + hex32(dataCanId) + ")"
             : "SDM " + hex32(dataCanId));
  m_sdmSources.set(dataCanId & 0xFFu);
  if (configIndex >= 0) m_configuredSeen[static_cast<std::size_t>(configIndex)] = 1;
  return &pair;
}

SafetyCheck::Pair* SafetyCheck::routeHeader(const TraceFrame& frame, FindingSink& sink) {
  const std::uint32_t id = frame.frame.id;
  const std::optional<j1939::SafetyHeader> header = j1939::parseSafetyHeader(frame.frame.payload());
  // 1. a pair of this bus whose SHM identity this is and whose SDM the SHM names
  // 2. else (a corrupted SHM) the only such pair with this exact SHM identifier, or the only one
  Pair* exact = nullptr;
  Pair* only = nullptr;
  std::size_t exactCount = 0;
  std::size_t candidates = 0;
  for (Pair& pair : m_pairs) {
    if (pair.stats.bus != frame.bus || !j1939::sameSafetyIdentity(pair.checker.headerCanId(), id)) continue;
    if (header && header->matchesData(pair.stats.dataCanId)) return &pair;
    ++candidates;
    only = &pair;
    if (pair.checker.headerCanId() == id) {
      ++exactCount;
      exact = &pair;
    }
  }
  // a configured pair first seen on this bus
  for (std::size_t i = 0; i < m_setup->safetyPairs.size(); ++i) {
    const SafetyPairSetup& configured = m_setup->safetyPairs[i];
    if (!j1939::sameSafetyIdentity(j1939::safetyHeaderCanId(configured.dataCanId), id)) continue;
    if (!header || !header->matchesData(configured.dataCanId)) continue;
    const bool onThisBus = std::any_of(m_pairs.begin(), m_pairs.end(), [&](const Pair& pair) {
      return pair.stats.bus == frame.bus && pair.configIndex == static_cast<std::int32_t>(i);
    });
    if (!onThisBus)
      return addPair(frame.bus, configured.dataCanId, configured.message, static_cast<std::int32_t>(i), &configured);
  }
  if (exactCount == 1) return exact;
  if (candidates == 1) return only;
  if (!m_setup->safetyPairs.empty()) return nullptr;  // an SHM of no configured pair: not ours to judge

  // --dbc only: the SHM names its SDM
  const std::optional<std::uint32_t> data = header ? namedData(id, *header) : std::nullopt;
  if (!data) {
    if (m_contradictions++ < MAX_LISTED_PER_KIND) {
      sink.finding(Finding{frame.timeNs, frame.bus, Severity::Fault, Check::Safety,
                           "SHM " + hex32(id) +
                               (header ? ": names an SDM its own identifier contradicts (" + headerFields(*header) + ")"
                                       : ": " + std::to_string(frame.frame.length) + " bytes, an SHM has 8")});
    }
    return nullptr;
  }
  const std::size_t discovered = static_cast<std::size_t>(
      std::count_if(m_pairs.begin(), m_pairs.end(), [](const Pair& pair) { return pair.stats.discovered; }));
  if (discovered >= MAX_DISCOVERED_SAFETY_PAIRS) {
    if (m_skipped++ == 0) {
      sink.finding(Finding{frame.timeNs, frame.bus, Severity::Warning, Check::Safety,
                           "more than " + std::to_string(MAX_DISCOVERED_SAFETY_PAIRS) +
                               " J1939-76 pairs: SHMs of further SDMs are not checked (counted at the end)"});
    }
    return nullptr;
  }
  return addPair(frame.bus, *data, m_matcher.match(*data, true), -1, nullptr);
}

SafetyCheck::Pair* SafetyCheck::routeData(const TraceFrame& frame, bool& next) {
  const std::uint32_t id = frame.frame.id;
  // the next frame with the SDM's identity after its SHM is the SDM, whatever its priority
  for (Pair& pair : m_pairs) {
    if (pair.stats.bus == frame.bus && pair.awaitingData && j1939::sameSafetyIdentity(pair.stats.dataCanId, id)) {
      next = true;
      return &pair;
    }
  }
  next = false;
  for (Pair& pair : m_pairs) {
    if (pair.stats.bus == frame.bus && pair.stats.dataCanId == id) return &pair;
  }
  for (std::size_t i = 0; i < m_setup->safetyPairs.size(); ++i) {
    const SafetyPairSetup& configured = m_setup->safetyPairs[i];
    if (configured.dataCanId == id) {
      return addPair(frame.bus, configured.dataCanId, configured.message, static_cast<std::int32_t>(i), &configured);
    }
  }
  return nullptr;
}

void SafetyCheck::onHeader(Pair& pair, const TraceFrame& frame) {
  const std::span<const std::uint8_t> payload = frame.frame.payload();
  pair.checker.onHeader(payload, frame.timeNs);
  pair.pendingHeaderLength = static_cast<std::uint8_t>(payload.size());
  std::copy_n(payload.begin(), std::min(payload.size(), pair.pendingHeader.size()), pair.pendingHeader.begin());
  pair.pendingHeaderNs = frame.timeNs;
  pair.hasPreviousHeader = pair.hasLastHeader;
  pair.previousHeaderNs = pair.lastHeaderNs;
  pair.hasLastHeader = true;
  pair.lastHeaderNs = frame.timeNs;
  pair.awaitingData = true;
  pair.headerTakenByOther = false;
  pair.overdueReported = false;
}

void SafetyCheck::onData(Pair& pair, const TraceFrame& frame, FindingSink& sink) {
  const bool hadHeader = pair.awaitingData && frame.timeNs >= pair.pendingHeaderNs;
  pair.awaitingData = false;
  const std::span<const std::uint8_t> data = frame.frame.payload();
  const SafetyResult result = pair.checker.onData(data, frame.timeNs);
  ++m_pairsChecked;
  ++pair.stats.pairs;
  const std::optional<j1939::SafetyHeader> header =
      hadHeader
          ? j1939::parseSafetyHeader(std::span<const std::uint8_t>(pair.pendingHeader.data(), pair.pendingHeaderLength))
          : std::nullopt;
  const std::int64_t delayNs = frame.timeNs - pair.pendingHeaderNs;

  if (result == SafetyResult::Ok || result == SafetyResult::Synchronising) {
    if (result == SafetyResult::Ok) ++pair.stats.ok;
    pair.hasReference = true;
    pair.reference = header ? header->sequence : 0;
  } else {
    ++pair.stats.faults;
    ++m_faults;
    std::string text = pair.name + ": " + std::string(j1939::safetyResultName(result)) + ": ";
    switch (result) {
      case SafetyResult::MissingHeader:
        text += "SDM without an SHM before it";
        break;
      case SafetyResult::BadLength:
        text += "SHM " + std::to_string(pair.pendingHeaderLength) + " bytes, SDM " + std::to_string(data.size()) +
                " bytes (8 each)";
        break;
      case SafetyResult::Timeout:
        text += "SDM " + micros(delayNs) + " after its SHM (SRVT " + micros(pair.stats.maxHeaderToDataNs) + ")";
        break;
      case SafetyResult::CycleTimeout:
        text += "SHM " + micros(pair.lastHeaderNs - pair.previousHeaderNs) + " after the previous SHM (SCT " +
                micros(pair.stats.maxHeaderCycleNs) + ")";
        break;
      case SafetyResult::HeaderMismatch:
        text += header ? "SHM names " + headerFields(*header) + ", the SDM is " + hex32(frame.frame.id)
                       : std::string("SHM unreadable");
        break;
      case SafetyResult::CrcMismatch:
        text += "SHM CRC " + hex32(header ? header->sdmCrc : 0) + ", SDM data CRC " + hex32(j1939::crc32J1939_76(data));
        break;
      case SafetyResult::Repetition:
        text += "sequence " + std::to_string(header ? header->sequence : 0) + " repeated";
        break;
      case SafetyResult::SequenceError: {
        const unsigned expected = (pair.reference + 1u) % j1939::SAFETY_SEQUENCE_MODULO;
        text += "sequence " + std::to_string(header ? header->sequence : 0) + ", expected " + std::to_string(expected) +
                " after " + std::to_string(pair.reference);
        break;
      }
      default:
        break;
    }
    if (frame.frame.id != pair.stats.dataCanId) text += " (taken for the SDM: " + hex32(frame.frame.id) + ")";
    pair.hasReference = false;
    const auto index = static_cast<std::size_t>(result);
    if (pair.listed[index] < MAX_LISTED_PER_KIND) {
      ++pair.listed[index];
      sink.finding(Finding{frame.timeNs, frame.bus, Severity::Fault, Check::Safety, std::move(text)});
    } else {
      ++pair.unlisted[index];
    }
  }

  if (!hadHeader || result == SafetyResult::MissingHeader || result == SafetyResult::BadLength) return;
  SafetyPairStats& stats = pair.stats;
  stats.deltaMinNs = stats.deltaCount == 0 ? delayNs : std::min(stats.deltaMinNs, delayNs);
  stats.deltaMaxNs = stats.deltaCount == 0 ? delayNs : std::max(stats.deltaMaxNs, delayNs);
  stats.deltaSumNs += delayNs;
  ++stats.deltaCount;
  if (stats.deltaNs <= 0 || result == SafetyResult::Timeout) return;
  const std::int64_t tolerance = deltaTolerance(stats.deltaNs);
  if (std::llabs(delayNs - stats.deltaNs) <= tolerance) return;
  ++stats.deltaWarnings;
  if (stats.deltaWarnings > MAX_LISTED_PER_KIND) {
    ++pair.deltaUnlisted;
    return;
  }
  sink.finding(Finding{frame.timeNs, frame.bus, Severity::Warning, Check::Safety,
                       pair.name + ": SHM -> SDM delta " + micros(delayNs) + ", configured " + micros(stats.deltaNs) +
                           " (tolerance " + micros(tolerance) + ")"});
}

namespace {
const std::string NO_GROUP;
}  // namespace

void SafetyCheck::poll(std::int64_t nowNs, FindingSink& sink) {
  for (Pair& pair : m_pairs) {
    if (!pair.hasLastHeader || pair.overdueReported || !pair.checker.headerOverdue(nowNs)) continue;
    pair.overdueReported = true;
    const std::string& switchedBy =
        pair.configIndex >= 0 ? m_setup->safetyPairs[static_cast<std::size_t>(pair.configIndex)].switchedBy : NO_GROUP;
    std::string text = pair.name + ": no SHM for " + micros(nowNs - pair.lastHeaderNs) + " (SCT " +
                       micros(pair.stats.maxHeaderCycleNs) + "): ";
    // A pair of a send group stops when the group is switched off (the FSM's Stop): expected,
    // but worth a line; any other pair that falls silent is a fault for its receivers.
    text += switchedBy.empty() ? "the sender stopped or its SHMs are lost"
                               : "stopped; it is in send group " + switchedBy + ", which switches it off";
    sink.finding(Finding{nowNs, pair.stats.bus, switchedBy.empty() ? Severity::Fault : Severity::Warning, Check::Safety,
                         std::move(text)});
  }
}

void SafetyCheck::add(const TraceFrame& frame, FindingSink& sink) {
  if (!m_polling || frame.timeNs >= m_nextPollNs) {
    if (m_polling) poll(frame.timeNs, sink);
    m_polling = true;
    m_nextPollNs = frame.timeNs + SCT_POLL_NS;
  }
  if (!usable(frame)) return;
  const std::uint32_t id = frame.frame.id;
  if (isHeader(id)) {
    if (Pair* pair = routeHeader(frame, sink)) onHeader(*pair, frame);
    return;
  }
  if (!m_sdmSources.test(id & 0xFFu)) return;  // no SDM from this source address
  bool next = false;
  Pair* pair = routeData(frame, next);
  if (pair == nullptr) return;
  if (!next && pair->headerTakenByOther) {
    pair->headerTakenByOther = false;  // its SHM went to the frame before it: judged already
    return;
  }
  if (!next && pair->stats.dataCanId != id) return;
  pair->headerTakenByOther = next && id != pair->stats.dataCanId;
  onData(*pair, frame, sink);
}

void SafetyCheck::finish(std::int64_t endNs, FindingSink& sink) {
  if (m_polling) poll(endNs, sink);
  for (const Pair& pair : m_pairs) {
    for (std::size_t i = 0; i < j1939::SAFETY_RESULT_COUNT; ++i) {
      if (pair.unlisted[i] == 0) continue;
      sink.finding(Finding{endNs, pair.stats.bus, Severity::Fault, Check::Safety,
                           pair.name + ": " + std::to_string(pair.unlisted[i]) + " more " +
                               std::string(j1939::safetyResultName(static_cast<SafetyResult>(i))) + " not listed"});
    }
    if (pair.deltaUnlisted > 0) {
      sink.finding(Finding{endNs, pair.stats.bus, Severity::Warning, Check::Safety,
                           pair.name + ": " + std::to_string(pair.deltaUnlisted) + " more delta warnings not listed"});
    }
    if (pair.stats.discovered && pair.stats.pairs == 0) {
      sink.finding(Finding{endNs, pair.stats.bus, Severity::Warning, Check::Safety,
                           pair.name + ": SHMs name it but no frame with its identity followed"});
    }
  }
  for (std::size_t i = 0; i < m_setup->safetyPairs.size(); ++i) {
    if (m_configuredSeen[i] != 0) continue;
    const SafetyPairSetup& configured = m_setup->safetyPairs[i];
    const bool named =
        configured.message >= 0 && static_cast<std::size_t>(configured.message) < m_setup->database.messages.size();
    sink.finding(Finding{endNs, 0, Severity::Info, Check::Safety,
                         (named ? m_setup->database.messages[static_cast<std::size_t>(configured.message)].name + " (" +
                                      hex32(configured.dataCanId) + ")"
                                : "SDM " + hex32(configured.dataCanId)) +
                             ": configured J1939-76 pair not in this log"});
  }
  if (m_skipped > 0) {
    sink.finding(Finding{endNs, 0, Severity::Warning, Check::Safety,
                         std::to_string(m_skipped) + " SHMs of pairs beyond the first " +
                             std::to_string(MAX_DISCOVERED_SAFETY_PAIRS) + " not checked"});
  }
  if (m_contradictions > MAX_LISTED_PER_KIND) {
    sink.finding(
        Finding{endNs, 0, Severity::Fault, Check::Safety,
                std::to_string(m_contradictions - MAX_LISTED_PER_KIND) + " more self-contradicting SHMs not listed"});
  }
}

std::vector<SafetyPairStats> SafetyCheck::stats() const {
  std::vector<SafetyPairStats> all;
  all.reserve(m_pairs.size());
  for (const Pair& pair : m_pairs) all.push_back(pair.stats);
  return all;
}

}  // namespace openvcu::trace::detail
