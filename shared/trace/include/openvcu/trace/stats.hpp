#pragma once
// Traffic statistics of a CAN timeline (`vcu trace stats`, the HMI's Statistics page, the
// HTML report's figures; the thesis' Figures 7.1-7.3): per bus the bus load (exact wire
// bits, can::frameBits, as can-rx counts them) over a sliding window, mean and peak; per
// node (J1939 source address) frames, bit/s and share of the bus load; per message the
// count, expected cycle, measured period (mean, p50, p99, max), deviation, gaps (intervals
// over 1.5 expected cycles) and missing cycles. Memory is bounded whatever the log size:
// periods go into a fixed histogram per message (resolution stated at PERIOD_BIN_NS),
// the bus load over time into a fixed number of buckets that merge pairwise when full.
//
//   TraceStats stats(setup);
//   while (timeline.next(frame)) stats.add(frame);
//   StatsReport report = stats.finish(timeline.buses());
//   appendStatsText(out, report);   // aligned tables
//   appendStatsJson(out, report);   // {"buses":[...],"nodes":[...],"messages":[...]}

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "openvcu/trace/analysis_types.hpp"
#include "openvcu/trace/timeline.hpp"

namespace openvcu::trace {

/// Width of a period histogram bin: percentiles are exact to this (and the max is exact).
inline constexpr std::int64_t PERIOD_BIN_NS = 100'000;  // 0.1 ms
/// Sliding window of the bus load (mean and peak are over windows of this length).
inline constexpr std::int64_t LOAD_WINDOW_NS = 1'000'000'000;  // 1 s
/// Distinct (bus, identifier) streams tracked; frames of further ones are counted as skipped.
inline constexpr std::size_t MAX_STREAMS = 4096;
/// Points of the bus-load-over-time series per bus (buckets merge pairwise when full).
inline constexpr std::size_t LOAD_SERIES_POINTS = 1024;

struct BusStats {
  std::string bus;              ///< name
  std::uint32_t bitrate{};
  std::uint64_t frames{};
  std::uint64_t errorFrames{};
  double durationS{};           ///< first to last frame on this bus
  double loadMeanPct{};         ///< all wire bits / (duration x bitrate)
  double loadMaxPct{};          ///< the highest load of any LOAD_WINDOW_NS window
  /// Load over time: (seconds from the timeline's start, % in that bucket), bucket width
  /// loadBucketS; at most LOAD_SERIES_POINTS points.
  std::vector<std::pair<double, double>> loadSeries;
  double loadBucketS{};
};

struct NodeStats {
  std::string bus;
  std::uint8_t sa{};            ///< J1939 source address (29-bit frames); 11-bit frames: see `standard`
  bool standard{};              ///< the "node" of all 11-bit frames (no source address)
  std::string name;             ///< from the DBC where known, else empty
  std::uint64_t frames{};
  double bitsPerS{};            ///< wire bits / bus duration
  double sharePct{};            ///< of all wire bits on the bus
};

struct MessageStats {
  std::string bus;
  std::uint32_t id{};           ///< CAN identifier (29-bit with `extended`)
  bool extended{};
  std::string name;             ///< DBC name, empty when unknown
  std::uint8_t sa{};            ///< source address (extended ids)
  std::uint64_t count{};
  double expectedMs{};          ///< 0: no expectation
  CycleSource cycleSource{CycleSource::None};
  double meanMs{}, p50Ms{}, p99Ms{}, maxMs{}, minMs{};  ///< measured periods (0 below 2 frames)
  double deviationMs{};         ///< meanMs - expectedMs (0 without an expectation)
  std::uint64_t gaps{};         ///< periods > 1.5 x expected
  std::uint64_t missing{};      ///< cycles missed inside those gaps: sum of round(period/expected) - 1
};

struct StatsReport {
  double startS{};              ///< the timeline's first frame, log time in s
  double durationS{};
  std::uint64_t frames{};
  std::uint64_t skippedFrames{};   ///< frames of streams beyond MAX_STREAMS
  std::uint64_t backwardSteps{};   ///< periods not measured because time went backwards
  std::vector<BusStats> buses;
  std::vector<NodeStats> nodes;        ///< by bus, then bits/s descending
  std::vector<MessageStats> messages;  ///< by bus, then identifier
};

/// Accumulates the statistics of a timeline frame by frame.
/// @note not thread-safe. add() allocates only when a new stream or bus appears.
class TraceStats {
 public:
  explicit TraceStats(const AnalysisSetup& setup);
  TraceStats(TraceStats&&) noexcept;
  TraceStats& operator=(TraceStats&&) noexcept;
  ~TraceStats();

  void add(const TraceFrame& frame);
  /// The figures so far; `buses` names TraceFrame::bus (LogTimeline::buses()). May be
  /// called again after more add()s.
  [[nodiscard]] StatsReport finish(const std::vector<std::string>& buses) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// Aligned text tables: buses, nodes, messages (with units).
void appendStatsText(std::string& out, const StatsReport& report);
/// One JSON object: {"start_s","duration_s","frames","skipped_frames","buses":[{bus,bitrate,
/// frames,error_frames,load_mean_pct,load_max_pct}],"nodes":[{bus,sa,name,frames,bits_per_s,
/// share_pct}],"messages":[{bus,id,name,count,expected_ms,cycle_source,mean_ms,p50_ms,p99_ms,
/// max_ms,deviation_ms,gaps,missing}]}; "id" is "0x18FEF121".
void appendStatsJson(std::string& out, const StatsReport& report);

}  // namespace openvcu::trace
