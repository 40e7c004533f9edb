#pragma once
// SVG charts written into a std::string, for the self-contained HTML report of
// `vcu trace report` (html_report.hpp; design: docs/design/trace-report.md): a time series
// line chart, vertical (grouped) and horizontal bar charts, and a lanes chart (rows of
// intervals and point events on a time axis). No library, no Qt; the output is inline SVG
// for an HTML document (no xmlns, no external reference), the same bytes for the same input.
//
//   niceTicks(0, 87, 5)  -> low 0, high 100, step 20, values {0, 20, 40, 60, 80, 100}
//   TimeChartSpec spec{.id = "load", .yLabel = "bus load [%]", .t0 = 0, .t1 = 60};
//   spec.series.push_back({"can0", {{0.0, 12.5}, {0.5, 13.1}}});
//   std::string svg = timeSeriesSvg(spec);   // "<svg class=\"tsvg\" data-t0=\"0\" ..."
//
// Time charts (time series and lanes) share one layout of the x axis (TIME_PLOT_LEFT,
// TIME_PLOT_RIGHT) and carry their time range and plot area as data attributes
// (data-t0, data-t1, data-l, data-w); what moves with the time axis is either in a group
// of class "zx" (an x-only affine transform; strokes do not scale) or an element with a
// data-x attribute (markers and labels moved without stretching). The report's script
// zooms and pans them all together through these; without the script the charts show
// the whole time range.

#include <cstddef>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "openvcu/trace/analysis_types.hpp"

namespace openvcu::trace {

/// Points a time series is drawn with at most: longer series are decimated to the lowest
/// and highest value of each of MAX_SERIES_POINTS / 2 pixel columns (spikes stay visible).
inline constexpr std::size_t MAX_SERIES_POINTS = 2000;
/// Left and right margin of the plot area of every time chart (so their x axes align).
inline constexpr int TIME_PLOT_LEFT = 190;
inline constexpr int TIME_PLOT_RIGHT = 24;
/// Narrowest category of a vertical bar chart; more categories make the chart wider.
inline constexpr int MIN_CATEGORY_PX = 8;

/// Ticks of an axis: the range widened to whole steps, and the tick values in it.
struct AxisTicks {
  double low{};
  double high{};
  double step{};
  std::vector<double> values;
};

/// Ticks at 1, 2 or 5 x 10^n covering [low, high] with at most about `maxTicks` steps;
/// an empty range (low == high) is widened around its value; non-finite input gives [0, 1].
[[nodiscard]] AxisTicks niceTicks(double low, double high, std::size_t maxTicks);
/// Decimals a tick label needs for a step of niceTicks() (0.5 -> 1, 0.02 -> 2, 20 -> 0).
[[nodiscard]] int tickDecimals(double step);
/// `value` with `decimals` decimals, locale-independent ("-0" printed as "0").
[[nodiscard]] std::string formatFixed(double value, int decimals);
/// Appends `text` escaped for XML/HTML text and attribute values (& < > " '); text that
/// is not valid UTF-8 is read as Windows-1252, control characters become U+FFFD.
void appendXmlEscaped(std::string& out, std::string_view text);
/// The colour of series `index` (a palette of 8 colours told apart with colour blindness).
[[nodiscard]] std::string_view seriesColour(std::size_t index);
/// The colour of a severity (info blue, warning orange, fault red).
[[nodiscard]] std::string_view severityColour(Severity severity);

/// One line of a time series chart: (seconds, value) samples in any order.
struct TimeSeries {
  std::string name;
  std::vector<std::pair<double, double>> samples;
};

/// A line chart over [t0, t1] seconds with one y axis shared by its series.
struct TimeChartSpec {
  std::string id;       ///< unique in the document (clip path ids derive from it)
  std::string yLabel;   ///< the y axis with its unit: "bus load [%]"
  double t0{};
  double t1{};
  int width{1300};
  int height{230};
  std::vector<TimeSeries> series{};
};

/// The chart as an <svg> element; non-finite samples are left out.
[[nodiscard]] std::string timeSeriesSvg(const TimeChartSpec& spec);

/// Values of one series of a bar chart, one per category (missing ones count as 0).
struct BarSeries {
  std::string name;
  std::vector<double> values;
};

/// Bars per category, grouped by series.
struct BarChartSpec {
  std::string id;
  std::string valueLabel;              ///< the value axis with its unit: "cycle [ms]"
  std::vector<std::string> categories{};
  std::vector<BarSeries> series{};
  /// Horizontal bars only: a text at the end of each category's bar ("38.2 %"), optional.
  std::vector<std::string> annotations{};
  int width{1300};
  int height{340};                     ///< vertical bars: the plot and its labels
};

/// Vertical bars (zero baseline, negative values downwards); category labels are rotated
/// when they do not fit side by side, and the chart grows wider than `width` when a
/// category would get less than MIN_CATEGORY_PX.
[[nodiscard]] std::string verticalBarsSvg(const BarChartSpec& spec);
/// Horizontal bars, one row per category (the height follows the number of categories).
[[nodiscard]] std::string horizontalBarsSvg(const BarChartSpec& spec);

/// An interval of a lane; `openEnd`: still going at endS (drawn fading out).
struct LaneInterval {
  double startS{};
  double endS{};
  bool openEnd{};
  std::string label;
  Severity severity{Severity::Warning};
};

/// A point event of a lane.
struct LaneEvent {
  double s{};
  std::string label;
  Severity severity{Severity::Info};
};

/// One row of a lanes chart.
struct Lane {
  std::string name;
  std::vector<LaneInterval> intervals;
  std::vector<LaneEvent> events;
};

/// Rows of intervals and events over [t0, t1] seconds.
struct LanesChartSpec {
  std::string id;
  double t0{};
  double t1{};
  int width{1300};
  std::vector<Lane> lanes{};
};

/// The lanes as an <svg> element (height from the number of lanes). Every event and
/// interval carries its text as a tooltip; labels that would overlap the previous one in
/// their lane are hidden (display="none") until a zoom makes room.
[[nodiscard]] std::string lanesSvg(const LanesChartSpec& spec);

}  // namespace openvcu::trace
