#pragma once
// J1939-21 transport sessions and J1939-73 DM1/DM2 in a CAN timeline: every BAM and
// RTS/CTS session on every bus is followed passively (j1939::TpMonitor, any source and
// destination), reassembled messages are handed on (to decode them with the DBC), session
// outcomes and DTCs raised / cleared become findings, and the DTC intervals are kept for the
// report's DTC timeline. Design: docs/design/trace-analysis.md.
//
//   TransportAnalysis transport(setup);
//   while (timeline.next(frame)) transport.add(frame, sink);
//   transport.finish(lastTimeNs, sink);            // open sessions -> "incomplete" findings
//   for (const DtcInterval& dtc : transport.dtcIntervals()) draw(dtc);

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "openvcu/trace/analysis_types.hpp"
#include "openvcu/trace/timeline.hpp"

namespace openvcu::trace {

/// DTC intervals kept for the report; later ones are counted in TransportCounts::dtcIntervalsSkipped.
inline constexpr std::size_t MAX_DTC_INTERVALS = 10'000;

/// A DTC active from raisedNs until clearedNs (empty: still active at the end).
struct DtcInterval {
  std::uint16_t bus{};
  std::uint8_t source{};          ///< the ECU's source address
  bool previouslyActive{};        ///< from DM2 rather than DM1
  std::uint32_t spn{};
  std::uint8_t fmi{};
  std::uint8_t occurrenceCount{};  ///< the last one seen
  std::int64_t raisedNs{};
  std::optional<std::int64_t> clearedNs;
};

/// A message reassembled from a transport session (or a single-frame DM1/DM2), with the
/// database message its PGN matches (-1: none).
struct ReassembledMessage {
  std::uint16_t bus{};
  std::uint32_t pgn{};
  std::uint8_t source{};
  std::uint8_t destination{};   ///< 0xFF for BAM
  bool broadcast{};
  std::int64_t timeNs{};        ///< time of the last packet
  std::int32_t message{-1};
  std::span<const std::uint8_t> data;  ///< valid during the callback only
};

struct TransportCounts {
  std::uint64_t sessions{};      ///< started (BAM + RTS)
  std::uint64_t bam{};
  std::uint64_t rtsCts{};
  std::uint64_t completed{};
  std::uint64_t aborted{};
  std::uint64_t timedOut{};
  std::uint64_t incomplete{};    ///< still open when the log ended
  std::uint64_t replaced{};
  std::uint64_t protocolErrors{};  ///< bad/duplicate sequence, unexpected packets
  std::uint64_t refused{};         ///< announcements not followed: invalid, or the session pool was full
  std::uint64_t dm1Messages{};     ///< DM1 + DM2 decoded (single frame or reassembled)
  std::uint64_t dtcIntervalsSkipped{};
};

/// @note not thread-safe. add() allocates nothing per frame once the buses are known
///       (findings carry a std::string).
class TransportAnalysis {
 public:
  using OnMessage = std::function<void(const ReassembledMessage&)>;

  /// `onMessage` (optional) receives every reassembled message and every DM1/DM2.
  /// `setup` must outlive the analysis (its database names messages in findings).
  explicit TransportAnalysis(const AnalysisSetup& setup, OnMessage onMessage = {});
  TransportAnalysis(TransportAnalysis&&) noexcept;
  TransportAnalysis& operator=(TransportAnalysis&&) noexcept;
  ~TransportAnalysis();

  /// Feeds one frame of the timeline (any frame: non-TP frames cost a compare).
  void add(const TraceFrame& frame, FindingSink& sink);
  /// Applies the timeouts due by `endNs` and reports sessions still open as incomplete.
  void finish(std::int64_t endNs, FindingSink& sink);

  [[nodiscard]] const TransportCounts& counts() const noexcept;
  /// Raised/cleared DTC intervals in order of raising (at most MAX_DTC_INTERVALS).
  [[nodiscard]] const std::vector<DtcInterval>& dtcIntervals() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace openvcu::trace
