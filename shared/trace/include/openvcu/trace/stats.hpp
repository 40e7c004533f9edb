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

/// Width of a period histogram bin up to PERIOD_LINEAR_NS: there p50/p99 are the true
/// value rounded to a multiple of PERIOD_BIN_NS (clamped to the exact min/max), so within
/// PERIOD_BIN_NS / 2 of it; an exact 10 ms cycle reads 10.000 ms.
inline constexpr std::int64_t PERIOD_BIN_NS = 100'000;  // 0.1 ms
/// Periods up to here have linear bins; above, each octave (200-400 ms, 400-800 ms, ...)
/// has PERIOD_OCTAVE_BINS bins (relative resolution 1/128 = 0.8 %) up to PERIOD_RANGE_NS;
/// longer periods share one overflow bin (their percentile is the exact max). Above
/// PERIOD_LINEAR_NS a percentile is the middle of its bin: within 1/256 (0.4 %).
inline constexpr std::int64_t PERIOD_LINEAR_NS = 200'000'000;     // 200 ms
inline constexpr std::int64_t PERIOD_OCTAVE_BINS = 128;
inline constexpr std::int64_t PERIOD_RANGE_NS = 12'800'000'000;   // 12.8 s (6 octaves)
/// Sliding window of the peak bus load.
inline constexpr std::int64_t LOAD_WINDOW_NS = 1'000'000'000;  // 1 s
/// The window slides in steps of this (a ring of LOAD_WINDOW_NS / LOAD_STEP_NS buckets).
inline constexpr std::int64_t LOAD_STEP_NS = 10'000'000;  // 10 ms
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
  double loadMeanPct{};         ///< wire time of all frames (nominal bits at bitrate, CAN FD data
                                ///< phase at the data bit rate, error frames 17 bits) / duration
  double loadMaxPct{};          ///< the highest load of any LOAD_WINDOW_NS window (windows
                                ///< start at the bus' first frame + k x LOAD_STEP_NS); the
                                ///< mean when the bus was seen for less than one window
  /// Load over time: (seconds from the timeline's start to the bucket's start, % of the
  /// bucket's width that frames took), bucket width loadBucketS (LOAD_STEP_NS, doubled at
  /// each pairwise merge); at most LOAD_SERIES_POINTS points. A bucket the log ends inside
  /// still counts its whole width (it reads low).
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
  double sharePct{};            ///< of all wire bits on the bus (error frames included)
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
  std::uint64_t periods{};      ///< periods measured (count - 1 - backward steps of this stream)
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
  /// Every bus is measured at the default bit rates (AnalysisBus{}): use the constructor
  /// with the bus names when the setup configures other rates.
  explicit TraceStats(const AnalysisSetup& setup);
  /// `busNames` is the timeline's list (LogTimeline::buses(), which grows as channels
  /// appear): a bus is measured at setup.bus(name)'s bit rates from its first frame.
  /// Both `setup` and `busNames` must outlive this object.
  TraceStats(const AnalysisSetup& setup, const std::vector<std::string>& busNames);
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

/// Aligned text tables: a summary line, then buses, nodes, messages (units in the headers;
/// periods in ms with 3 decimals, loads in % with 2). "-" where there is no figure.
void appendStatsText(std::string& out, const StatsReport& report);
/// One JSON object, followed by a newline:
///   {"start_s","duration_s","frames","skipped_frames","backward_steps",
///    "period_resolution":{"bin_ms":0.1,"linear_up_to_ms":200,"octave_bins":128,"range_ms":12800},
///    "buses":[{bus,bitrate,frames,error_frames,duration_s,
///              load_mean_pct,load_max_pct,load_window_s}],
///    "nodes":[{bus,sa,standard,name,frames,bits_per_s,share_pct}],
///    "messages":[{bus,id,extended,name,sa,count,periods,expected_ms,cycle_source,mean_ms,p50_ms,
///                 p99_ms,max_ms,min_ms,deviation_ms,gaps,missing}]}
/// "id" is "0x18FEF121" (8 hex digits extended, 3 standard); "sa" is null for the node of
/// 11-bit frames and for 11-bit messages; "name" is null when unknown; expected_ms,
/// cycle_source and deviation_ms are null without an expectation; the period figures are
/// null below 2 frames. cycle_source: "schedule" or "GenMsgCycleTime". Numbers are
/// rounded: ms to 3 decimals, % to 2, bit/s to 1.
void appendStatsJson(std::string& out, const StatsReport& report);

}  // namespace openvcu::trace
