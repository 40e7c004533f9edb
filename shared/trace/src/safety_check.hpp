#pragma once
// The J1939-76 part of TraceChecker (private to shared/trace): SHM/SDM pairs routed to one
// j1939::SafetyPairChecker each, per bus, as a J1939-76 receiver would route them; every
// verdict but Ok / Synchronising becomes a Fault finding with its numbers, the SHM -> SDM
// delta is measured against the configured one, and silent SHM senders are found by polling
// SafetyPairChecker::headerOverdue() every SCT_POLL_NS of log time.
//
//   SafetyCheck safety(setup);
//   safety.add(frame, sink);   // every frame of the timeline
//   safety.finish(endNs, sink);
//   -> "S1_ES_PGN61427 (0x0CEFF321): CrcMismatch: SHM CRC 0x8100EFA3, SDM data CRC 0x5E3BD14C"

#include <array>
#include <bitset>
#include <cstdint>
#include <string>
#include <vector>

#include "openvcu/dbc/matcher.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/trace/check.hpp"

namespace openvcu::trace::detail {

/// @note not thread-safe. add() allocates only when a pair is first seen and for findings.
class SafetyCheck {
 public:
  explicit SafetyCheck(const AnalysisSetup& setup);

  void add(const TraceFrame& frame, FindingSink& sink);
  void finish(std::int64_t endNs, FindingSink& sink);

  [[nodiscard]] std::vector<SafetyPairStats> stats() const;
  [[nodiscard]] std::uint64_t pairsChecked() const noexcept { return m_pairsChecked; }
  [[nodiscard]] std::uint64_t faults() const noexcept { return m_faults; }
  [[nodiscard]] std::uint64_t skipped() const noexcept { return m_skipped; }

 private:
  struct Pair {
    explicit Pair(const j1939::SafetyPairConfig& config) noexcept : checker(config) {}
    j1939::SafetyPairChecker checker;
    SafetyPairStats stats;
    std::string name;              ///< "S1_ES_PGN61427 (0x0CEFF321)"
    std::int32_t configIndex{-1};  ///< into setup.safetyPairs, -1 when discovered
    // What the checker holds, mirrored to print the numbers behind a verdict.
    j1939::SafetyPayload pendingHeader{};
    std::uint8_t pendingHeaderLength{};
    std::int64_t pendingHeaderNs{};
    std::int64_t lastHeaderNs{};
    std::int64_t previousHeaderNs{};
    bool awaitingData{};
    bool headerTakenByOther{};  ///< another frame of the SDM's identity took the last SHM
    bool hasLastHeader{};
    bool hasPreviousHeader{};
    bool hasReference{};
    std::uint8_t reference{};
    bool overdueReported{};
    std::array<std::uint64_t, j1939::SAFETY_RESULT_COUNT> listed{};
    std::array<std::uint64_t, j1939::SAFETY_RESULT_COUNT> unlisted{};
    std::uint64_t deltaUnlisted{};
  };

  Pair* routeHeader(const TraceFrame& frame, FindingSink& sink);
  Pair* routeData(const TraceFrame& frame, bool& next);
  Pair* addPair(std::uint16_t bus, std::uint32_t dataCanId, std::int32_t message, std::int32_t configIndex,
                const SafetyPairSetup* configured);
  void onHeader(Pair& pair, const TraceFrame& frame);
  void onData(Pair& pair, const TraceFrame& frame, FindingSink& sink);
  void poll(std::int64_t nowNs, FindingSink& sink);

  const AnalysisSetup* m_setup;
  dbc::MessageMatcher m_matcher;
  std::vector<Pair> m_pairs;
  std::vector<std::uint8_t> m_configuredSeen;  ///< per setup.safetyPairs entry: seen on some bus
  std::bitset<256> m_sdmSources;               ///< source addresses of the SDMs known (cheap pre-filter)
  std::int64_t m_nextPollNs{};
  bool m_polling{};
  std::uint64_t m_pairsChecked{};
  std::uint64_t m_faults{};
  std::uint64_t m_skipped{};
  std::uint64_t m_contradictions{};
};

}  // namespace openvcu::trace::detail
