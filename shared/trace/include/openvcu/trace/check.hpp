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
#include <memory>

#include "openvcu/trace/analysis_types.hpp"
#include "openvcu/trace/timeline.hpp"
#include "openvcu/trace/transport_analysis.hpp"

namespace openvcu::trace {

/// How long a requester waits for the answer (J1939-21 T3 / the 1.25 s response timeout).
inline constexpr std::int64_t REQUEST_TIMEOUT_NS = 1'250'000'000;

struct CheckCounts {
  std::uint64_t safetyPairs{};    ///< SDMs checked
  std::uint64_t safetyFaults{};   ///< SDMs whose pair failed (any result but Ok/Synchronising)
  std::uint64_t requests{};
  std::uint64_t unanswered{};
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

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace openvcu::trace
