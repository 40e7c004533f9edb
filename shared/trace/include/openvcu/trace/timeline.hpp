#pragma once
// The input of the trace analysis (`vcu trace stats|check|report`, the HMI's Statistics
// page): what is known of the vehicle (AnalysisSetup, from a vehicle configuration or from
// DBC files) and one or more CAN logs read as one timeline, merged by time (LogTimeline).
// Streaming: one frame per log is held, whatever the logs' sizes.
//
//   auto setup = loadSetupFromConfig("config/hhea/vehicle.json");   // or loadSetupFromDbc({"a.dbc"})
//   auto timeline = LogTimeline::open({"drive/vehicle.log"}, *setup, [](const Error& e) { warn(e); });
//   TraceFrame frame;
//   while (timeline->next(frame)) stats.add(frame);
//
// Bad input: a malformed line is passed to the error handler (file:line:column: reason)
// and skipped; a frame older than the previous frame of the same log ("time goes
// backwards") is reported once per log with its line, kept, and counted in
// LogCounts::backwards; the analyses treat the interval before it as unknown.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/trace/analysis_types.hpp"

namespace openvcu::trace {

/// Where a message's expected cycle comes from.
enum class CycleSource : std::uint8_t {
  None,       ///< not known: the message is measured but has no expectation
  Schedule,   ///< the vehicle's transmit schedule (cycleMs), for what the VCU sends
  Attribute,  ///< the DBC's GenMsgCycleTime
};

/// A bus as the analysis knows it. Log channels that no configured bus names get the
/// default bit rates (500 kbit/s, CAN FD data 2 Mbit/s).
struct AnalysisBus {
  std::string name;  ///< the log channel: "vehicle" (vcu record), "can0", ASC "1"
  std::uint32_t bitrate{500'000};
  std::uint32_t dataBitrate{2'000'000};
};

/// A J1939-76 safety pair the analysis checks with its configured timing.
struct SafetyPairSetup {
  std::int32_t message{};            ///< the SDM's database message
  std::uint32_t dataCanId{};         ///< the SDM identifier as sent (schedule substitution applied)
  std::int64_t deltaNs{};            ///< configured SHM -> SDM delay (schedule "safety.deltaUs")
  std::int64_t maxHeaderToDataNs{};  ///< SRVT: the longest accepted SHM -> SDM time
  std::int64_t maxHeaderCycleNs{};   ///< SCT: the longest accepted SHM -> SHM time
  /// The schedule's send group that switches the SDM on and off ("keepAlive"); empty when it
  /// is always sent. A switched pair that falls silent was most likely switched off: the
  /// check reports it as a warning, not a fault.
  std::string switchedBy;
};

/// What the analysis knows of the vehicle.
struct AnalysisSetup {
  std::string source;  ///< the configuration or the DBC files, for headers: "config/hhea/vehicle.json"
  dbc::Database database;
  dbc::MatchMode match{dbc::MatchMode::J1939};
  std::vector<AnalysisBus> buses;  ///< configured buses (may be empty: defaults for all channels)
  /// Per database message: the expected cycle in ns (0: none) and where it comes from.
  std::vector<std::int64_t> expectedCycleNs;
  std::vector<CycleSource> cycleSource;
  /// Safety pairs from the schedule (--config). With --dbc only, the check finds pairs on
  /// the bus by their SHM (PGN 0x0E00) and uses the default timing below.
  std::vector<SafetyPairSetup> safetyPairs;
  /// Node names by J1939 source address: the DBC nodes that transmit a message with that
  /// source address (BO_ transmitter), joined by '/' in DBC order when several do
  /// ("Vehicle_Control_Unit/HVLP_SA71"), empty when unknown.
  std::array<std::string, 256> nodeNames;

  /// The bit rates of the bus named `name` (a configured bus, else the defaults).
  [[nodiscard]] AnalysisBus bus(const std::string& name) const;
};

/// SRVT / SCT used when the configuration gives none: J1939-76 leaves them to the
/// application; the defaults accept an SDM up to 10 ms after its SHM (our can-tx sends it
/// within the configured delta, below 1 ms) and an SHM cycle up to 3 x the SDM's cycle.
inline constexpr std::int64_t DEFAULT_SRVT_NS = 10'000'000;
inline constexpr std::int64_t DEFAULT_SCT_CYCLES = 3;

/// The setup of a vehicle configuration (vehicle.json): its DBC files, buses, and the
/// schedule's cycles and safety pairs (messages the VCU sends); GenMsgCycleTime for the
/// others. Errors name the file and the JSON path or DBC line.
[[nodiscard]] Result<AnalysisSetup> loadSetupFromConfig(const std::string& path);

/// The setup of DBC files alone (merged in order): GenMsgCycleTime cycles, no schedule.
/// Errors name the file, line and reason (the first error of each file).
[[nodiscard]] Result<AnalysisSetup> loadSetupFromDbc(const std::vector<std::string>& paths);

/// The setup without any DBC: every frame is unknown; bus load, nodes and J1939 protocol
/// checks (TP, DM1, requests, SHM/SDM found on the bus) still work.
[[nodiscard]] AnalysisSetup emptySetup();

/// Frames read per log, and what was skipped.
struct LogCounts {
  std::string path;
  std::uint64_t frames{};         ///< frames delivered
  std::uint64_t errorFrames{};    ///< error frames (delivered; the analyses count them as bus errors)
  std::uint64_t malformedLines{};
  std::uint64_t backwards{};      ///< frames older than the previous frame of this log
  std::uint64_t untimed{};        ///< lines without a timestamp (skipped: no time to analyse)
};

/// Several CAN logs (candump -L, candump, Vector ASC) read as one timeline, in time order
/// (ties: the earlier log first). Bus names are the union of the logs' channels in order
/// of first appearance.
/// @note not thread-safe; next() allocates only when a new channel name appears.
class LogTimeline {
 public:
  using ErrorHandler = std::function<void(const Error&)>;

  /// Opens every log. Fails with the first log that cannot be opened (the Error names it).
  /// `onError` receives malformed lines and the first backwards step of each log.
  [[nodiscard]] static Result<LogTimeline> open(const std::vector<std::string>& paths, const AnalysisSetup& setup,
                                                ErrorHandler onError = {});

  LogTimeline(LogTimeline&&) noexcept;
  LogTimeline& operator=(LogTimeline&&) noexcept;
  ~LogTimeline();

  /// The next frame in time order; false at the end of all logs.
  [[nodiscard]] bool next(TraceFrame& frame);

  /// Bus names seen so far (TraceFrame::bus indexes them).
  [[nodiscard]] const std::vector<std::string>& buses() const noexcept;
  [[nodiscard]] const std::vector<LogCounts>& counts() const noexcept;
  /// Time of the first frame delivered (0 before it).
  [[nodiscard]] std::int64_t startNs() const noexcept;

 private:
  struct Impl;
  explicit LogTimeline(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace openvcu::trace
