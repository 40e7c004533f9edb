#pragma once
// The protocol checks of a CAN timeline (`vcu trace check`, the report's findings):
// every J1939-76 safety pair (SHM before its SDM, inverted header fields, CRC-32, sequence,
// SHM -> SDM delta against the configured delta, SRVT and SCT), every J1939-21 transport
// session (TransportAnalysis), DM1/DM2 DTCs raised and cleared, and J1939-21 requests
// (PGN 59904) without an answer. Findings go to a FindingSink as they are made.
// Design: docs/design/trace-analysis.md.
//
//   TraceChecker checker(setup);
//   while (timeline.next(frame)) checker.add(frame, sink);
//   checker.finish(lastTimeNs, sink);
//   return checker.counts().faults > 0 ? 1 : 0;

#include <cstdint>
#include <cstddef>
#include <memory>
#include <vector>

#include "openvcu/trace/analysis_types.hpp"
#include "openvcu/trace/timeline.hpp"
#include "openvcu/trace/transport_analysis.hpp"

namespace openvcu::trace {

/// How long a requester waits for the answer (J1939-21 T3 / the 1.25 s response timeout).
inline constexpr std::int64_t REQUEST_TIMEOUT_NS = 1'250'000'000;

/// J1939-76 pairs found on the bus (--dbc only) are kept up to this many; SHMs naming
/// further SDMs are counted in CheckCounts::safetyPairsSkipped.
inline constexpr std::size_t MAX_DISCOVERED_SAFETY_PAIRS = 256;
/// Requests waiting for their answer; further requests are counted in CheckCounts::requestsSkipped.
inline constexpr std::size_t MAX_OPEN_REQUESTS = 1024;
/// Findings listed per safety pair and verdict (and per pair for the delta); the rest are
/// counted and summarised in one finding of the same severity at finish().
inline constexpr std::uint64_t MAX_LISTED_PER_KIND = 20;
/// SHM -> SDM delta tolerance: a measured delta further than max(DELTA_TOLERANCE_NS,
/// configured delta x DELTA_TOLERANCE_PERCENT / 100) from the configured delta is a Warning.
inline constexpr std::int64_t DELTA_TOLERANCE_NS = 200'000;
inline constexpr std::int64_t DELTA_TOLERANCE_PERCENT = 50;
/// How often (log time) silent SHM senders are looked for (SafetyPairChecker::headerOverdue()).
inline constexpr std::int64_t SCT_POLL_NS = 10'000'000;

/// One J1939-76 pair as the check saw it on one bus: verdicts and the measured SHM -> SDM delta.
struct SafetyPairStats {
  std::uint16_t bus{};
  std::int32_t message{-1};      ///< the SDM's database message, -1 when unknown
  std::uint32_t dataCanId{};     ///< the SDM identifier
  bool discovered{};             ///< found on the bus (no configured pair)
  std::int64_t deltaNs{};        ///< the configured SHM -> SDM delta (0: none)
  std::int64_t maxHeaderToDataNs{};  ///< SRVT used
  std::int64_t maxHeaderCycleNs{};   ///< SCT used
  std::uint64_t pairs{};         ///< SDMs checked
  std::uint64_t ok{};            ///< verdict Ok
  std::uint64_t faults{};        ///< verdicts other than Ok / Synchronising
  std::uint64_t deltaCount{};    ///< SDMs with a measured delta (an SHM before them)
  std::int64_t deltaMinNs{}, deltaMaxNs{}, deltaSumNs{};
  std::uint64_t deltaWarnings{};
  [[nodiscard]] double deltaMeanNs() const noexcept {
    return deltaCount == 0 ? 0.0 : static_cast<double>(deltaSumNs) / static_cast<double>(deltaCount);
  }
};

struct CheckCounts {
  std::uint64_t safetyPairs{};    ///< SDMs checked
  std::uint64_t safetyFaults{};   ///< SDMs whose pair failed (any result but Ok/Synchronising)
  std::uint64_t requests{};
  std::uint64_t unanswered{};
  std::uint64_t safetyPairsSkipped{};  ///< SHMs naming an SDM beyond MAX_DISCOVERED_SAFETY_PAIRS
  std::uint64_t requestsSkipped{};     ///< requests beyond MAX_OPEN_REQUESTS (not checked)
  std::uint64_t infos{}, warnings{}, faults{};  ///< findings by severity
};

/// @note not thread-safe.
class TraceChecker {
 public:
  explicit TraceChecker(const AnalysisSetup& setup, TransportAnalysis::OnMessage onMessage = {});
  TraceChecker(TraceChecker&&) noexcept;
  TraceChecker& operator=(TraceChecker&&) noexcept;
  ~TraceChecker();

  void add(const TraceFrame& frame, FindingSink& sink);
  void finish(std::int64_t endNs, FindingSink& sink);

  [[nodiscard]] const CheckCounts& counts() const noexcept;
  [[nodiscard]] const TransportAnalysis& transport() const noexcept;
  /// Every safety pair seen (configured ones once seen on a bus, discovered ones), in order of
  /// first sight: the report's and the docs' delta statistics.
  [[nodiscard]] std::vector<SafetyPairStats> safetyPairs() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace openvcu::trace
