#pragma once
// The HTML report of a CAN trace (`vcu trace report`, issue 21; design:
// docs/design/trace-report.md): ONE self-contained document (inline CSS, inline SVG charts
// of svg_chart.hpp, a small inline script for zoom and pan) that opens offline in any
// browser and can be mailed. Its Content-Security-Policy forbids every fetch. Figures:
// bus load over time, data rate per node (thesis Fig. 7.1), expected vs measured cycle per
// message (Fig. 7.2), their difference (Fig. 7.3), chosen signals, the DTC timeline, event
// lanes (FSM transitions and faults) and the findings on the time axis; tables per bus,
// node and message, and the findings list.
//
//   ReportInput input;
//   input.title = "drive.log";
//   input.stats = stats.finish(timeline.buses());
//   input.buses = timeline.buses();
//   input.dtcs = transport.dtcIntervals();
//   input.findings = findingSink.list();          // ReportFindings: bounded
//   input.signals.push_back({"VehicleSpeed", "km/h", samples});
//   writeFile("report.html", renderHtmlReport(input));
//
// Time: every time axis is in seconds from stats.startS (the timeline's first frame);
// DtcInterval and Finding times (the log's ns) are converted with it. The findings table
// shows the log's own time too (trace::appendSeconds: as candump -L stamps it), and the
// summary the first frame's.
//
// The script: all time charts share one x range; the wheel zooms around the pointer,
// dragging pans, a double click resets; report.html#view=T0,T1 opens on that range. On
// load it writes the bounding rectangles of all chart elements (class "chart", attribute
// data-chart) as JSON into <pre id="chart-layout"> (the browser test reads them).
// Without the script the charts show the whole range.

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "openvcu/trace/analysis_types.hpp"
#include "openvcu/trace/stats.hpp"
#include "openvcu/trace/transport_analysis.hpp"

namespace openvcu::trace {

/// Findings a report lists; later ones are only counted.
inline constexpr std::size_t MAX_REPORT_FINDINGS = 2000;
/// Messages drawn in Figures 7.2 and 7.3 (the busiest ones with a measured period); all
/// are in the message table.
inline constexpr std::size_t MAX_CYCLE_BARS = 200;

/// The findings of a run as a report keeps them: the first MAX_REPORT_FINDINGS, and counts of all.
struct FindingList {
  std::vector<Finding> kept;
  std::uint64_t total{};
  std::array<std::uint64_t, 3> bySeverity{};  ///< indexed by Severity
};

/// A FindingSink that keeps a FindingList.
/// @note not thread-safe; allocates for each kept finding only.
class ReportFindings final : public FindingSink {
 public:
  void finding(const Finding& finding) override;
  [[nodiscard]] const FindingList& list() const noexcept { return m_list; }

 private:
  FindingList m_list;
};

/// A signal drawn on the time axis: (seconds from the start, value) samples.
struct SignalSeries {
  std::string name;
  std::string unit;
  std::vector<std::pair<double, double>> samples;
};

/// A point event of an event lane (an FSM transition, a fault), seconds from the start.
struct ReportEvent {
  double s{};
  std::string label;
  Severity severity{Severity::Info};
};

/// A row of the events figure ("FSM state", "FSM faults").
struct EventLane {
  std::string name;
  std::vector<ReportEvent> events;
};

/// Everything a report shows. Empty parts give a "no data" note instead of a figure.
struct ReportInput {
  std::string title;              ///< the heading: "drive.log"
  std::string source;             ///< what was analysed: "config/hhea/vehicle.json; logs: drive.log"
  StatsReport stats;
  std::vector<std::string> buses;  ///< names for DtcInterval::bus and Finding::bus
  std::vector<DtcInterval> dtcs;
  std::uint64_t dtcIntervalsSkipped{};
  FindingList findings;
  std::vector<SignalSeries> signals;  ///< signals of one unit share a chart
  std::vector<EventLane> eventLanes;
};

/// The whole HTML document (UTF-8). Deterministic: the same input gives the same bytes.
/// @note allocates; not for a real-time path.
[[nodiscard]] std::string renderHtmlReport(const ReportInput& input);

}  // namespace openvcu::trace
