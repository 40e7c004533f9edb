// Time charts of svg_chart.hpp: the time series line chart and the lanes chart, which share
// one x layout and carry their time range for the report's zoom script.
#include "openvcu/trace/svg_chart.hpp"

#include <algorithm>
#include <cmath>

#include "openvcu/core/text.hpp"
#include "openvcu/trace/sample_ring.hpp"
#include "svg_writer.hpp"

namespace openvcu::trace {
namespace {

constexpr int LANE_PX = 26;
constexpr std::size_t MAX_LANE_NAME_CHARS = 28;
/// Average advance of a character at 11 px (lane labels).
constexpr double LABEL_CHAR_PX = 6.5;
/// The label of an event starts this far right of its marker.
constexpr double EVENT_LABEL_OFFSET = 7;
/// The label of an interval starts this far right of the interval's start.
constexpr double INTERVAL_LABEL_OFFSET = 3;

/// The time range a chart draws (never empty).
std::pair<double, double> timeRange(double t0, double t1) {
  if (!std::isfinite(t0)) t0 = 0;
  if (!std::isfinite(t1) || !(t1 > t0)) t1 = t0 + 1;
  return {t0, t1};
}

/// Maps seconds to pixels of a time chart.
struct TimeScale {
  double t0{}, t1{}, left{}, width{};
  [[nodiscard]] double x(double t) const { return left + (t - t0) / (t1 - t0) * width; }
};

/// The opening of a time chart: the svg element with its time range and plot area.
void openTimeSvg(std::string& out, std::string_view id, const TimeScale& scale, double width, double height) {
  out += "<svg class=\"tsvg\"";
  appendAttr(out, "id", id);
  out += " data-t0=\"" + text::number(scale.t0) + "\" data-t1=\"" + text::number(scale.t1) + "\"";
  appendAttr(out, "data-l", scale.left);
  appendAttr(out, "data-w", scale.width);
  appendAttr(out, "width", width);
  appendAttr(out, "height", height);
  out += " viewBox=\"0 0 ";
  appendCoord(out, width);
  out += ' ';
  appendCoord(out, height);
  out += "\" font-family=\"DejaVu Sans, sans-serif\" font-size=\"";
  out += std::to_string(FONT_PX);
  out += "\" role=\"img\">";
}

/// The time axis: vertical grid lines and labels in group "xa" (the script redraws it on
/// zoom from data-y0/data-y1), and the axis title.
void appendTimeAxis(std::string& out, const TimeScale& scale, double top, double bottom) {
  out += "<g class=\"xa\"";
  appendAttr(out, "data-y0", top);
  appendAttr(out, "data-y1", bottom);
  out += '>';
  const AxisTicks ticks = niceTicks(scale.t0, scale.t1, 10);
  for (double value : ticks.values) {
    if (value < scale.t0 - ticks.step * 1e-9 || value > scale.t1 + ticks.step * 1e-9) continue;
    const double x = scale.x(value);
    appendLine(out, x, top, x, bottom, GRID_COLOUR);
    appendText(out, x, bottom + 15, tickLabel(value, ticks.step), "middle");
  }
  out += "</g>";
  appendLine(out, scale.left, bottom, scale.left + scale.width, bottom, AXIS_COLOUR);
  appendText(out, scale.left + scale.width, bottom + 30, "time [s]", "end");
}

void appendClip(std::string& out, std::string_view id, double x, double y, double width, double height) {
  out += "<defs><clipPath";
  appendAttr(out, "id", std::string(id) + "-clip");
  out += "><rect";
  appendAttr(out, "x", x);
  appendAttr(out, "y", y);
  appendAttr(out, "width", width);
  appendAttr(out, "height", height);
  out += "/></clipPath></defs>";
}

/// The finite samples of a series inside [t0, t1], in time order.
std::vector<std::pair<double, double>> visibleSamples(const TimeSeries& series, double t0, double t1) {
  std::vector<std::pair<double, double>> samples;
  samples.reserve(series.samples.size());
  for (const auto& sample : series.samples) {
    if (std::isfinite(sample.first) && std::isfinite(sample.second) && sample.first >= t0 && sample.first <= t1) {
      samples.push_back(sample);
    }
  }
  std::stable_sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return samples;
}

/// The points a series is drawn with: all samples when few, else per pixel column the
/// lowest and highest value (decimate() of sample_ring.hpp) at the column's centre.
std::vector<std::pair<double, double>> drawnPoints(const std::vector<std::pair<double, double>>& samples,
                                                   double t0, double t1) {
  if (samples.size() <= MAX_SERIES_POINTS) return samples;
  SampleRing ring(samples.size());
  for (const auto& [t, v] : samples) ring.push(t, v);
  const std::size_t columns = MAX_SERIES_POINTS / 2;
  std::vector<float> decimated(columns * 3);
  const double end = std::nextafter(t1, t1 + 1.0);  // decimate()'s window is half-open
  const std::size_t filled = decimate(ring, t0, end, columns, decimated);
  std::vector<std::pair<double, double>> points;
  points.reserve(filled * 2);
  const double columnS = (end - t0) / static_cast<double>(columns);
  for (std::size_t i = 0; i < filled; ++i) {
    const double t = t0 + (static_cast<double>(decimated[i * 3]) + 0.5) * columnS;
    points.emplace_back(t, decimated[i * 3 + 1]);
    points.emplace_back(t, decimated[i * 3 + 2]);
  }
  return points;
}

/// Which labels of a lane to show: a label (at anchor + offset, anchors sorted by x) shows
/// when it lies inside [left, right] (the plot), starts after the previous shown label and
/// ends before the next anchor (the report's script applies the same rule after a zoom).
std::vector<bool> labelsShown(const std::vector<double>& xs, const std::vector<std::string>& labels, double offset,
                              double left, double right) {
  std::vector<bool> shown(xs.size());
  double end = -INFINITY;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const double start = xs[k] + offset;
    const double labelEnd = start + static_cast<double>(displayChars(labels[k])) * LABEL_CHAR_PX;
    const bool inside = start >= left && labelEnd <= right;
    const bool roomBefore = start >= end + 4;
    const bool roomAfter = k + 1 == xs.size() || xs[k + 1] - 6 > labelEnd;
    shown[k] = inside && roomBefore && roomAfter;
    if (shown[k]) end = labelEnd;
  }
  return shown;
}

}  // namespace

std::string timeSeriesSvg(const TimeChartSpec& spec) {
  const auto [t0, t1] = timeRange(spec.t0, spec.t1);
  const double width = std::max(spec.width, TIME_PLOT_LEFT + TIME_PLOT_RIGHT + 100);
  const double height = std::max(spec.height, LEGEND_TOP + TIME_AXIS_BOTTOM + 60);
  const TimeScale scale{t0, t1, TIME_PLOT_LEFT, width - TIME_PLOT_LEFT - TIME_PLOT_RIGHT};
  const double top = LEGEND_TOP;
  const double plotHeight = height - LEGEND_TOP - TIME_AXIS_BOTTOM;

  std::vector<std::vector<std::pair<double, double>>> points;
  double low = INFINITY;
  double high = -INFINITY;
  for (const TimeSeries& series : spec.series) {
    points.push_back(drawnPoints(visibleSamples(series, t0, t1), t0, t1));
    for (const auto& point : points.back()) {
      low = std::min(low, point.second);
      high = std::max(high, point.second);
    }
  }
  const bool empty = !(low <= high);
  const AxisTicks ticks = empty ? niceTicks(0, 1, 5) : niceTicks(low, high, 5);

  std::string out;
  out.reserve(4096 + 24 * MAX_SERIES_POINTS * spec.series.size());
  openTimeSvg(out, spec.id, scale, width, height);
  appendClip(out, spec.id, scale.left, top, scale.width, plotHeight);
  std::vector<std::string> names;
  for (const TimeSeries& series : spec.series) names.push_back(series.name);
  appendLegend(out, scale.left, names);
  appendValueAxis(out, ticks, scale.left, scale.left + scale.width, top, plotHeight, spec.yLabel);
  appendTimeAxis(out, scale, top, top + plotHeight);
  if (empty) appendText(out, scale.left + scale.width / 2, top + plotHeight / 2, "no data", "middle");

  out += "<g clip-path=\"url(#";
  appendXmlEscaped(out, spec.id);
  out += "-clip)\"><g class=\"zx\">";
  const auto y = [&](double v) { return top + plotHeight - (v - ticks.low) / (ticks.high - ticks.low) * plotHeight; };
  for (std::size_t s = 0; s < points.size(); ++s) {
    if (points[s].empty()) continue;
    out += "<polyline fill=\"none\" stroke=\"";
    out += seriesColour(s);
    out += "\" stroke-width=\"1.5\" vector-effect=\"non-scaling-stroke\" points=\"";
    for (const auto& [t, v] : points[s]) {
      appendCoord(out, scale.x(t));
      out += ',';
      appendCoord(out, y(v));
      out += ' ';
    }
    if (points[s].size() == 1) {  // a single sample: a short mark so it shows
      appendCoord(out, scale.x(points[s][0].first) + 2);
      out += ',';
      appendCoord(out, y(points[s][0].second));
    }
    out += "\">";
    appendTitle(out, spec.series[s].name);
    out += "</polyline>";
  }
  out += "</g></g></svg>";
  return out;
}

std::string lanesSvg(const LanesChartSpec& spec) {
  const auto [t0, t1] = timeRange(spec.t0, spec.t1);
  const double width = std::max(spec.width, TIME_PLOT_LEFT + TIME_PLOT_RIGHT + 100);
  const TimeScale scale{t0, t1, TIME_PLOT_LEFT, width - TIME_PLOT_LEFT - TIME_PLOT_RIGHT};
  constexpr double TOP = 8;
  const double plotHeight = static_cast<double>(std::max<std::size_t>(spec.lanes.size(), 1)) * LANE_PX;
  const double height = TOP + plotHeight + TIME_AXIS_BOTTOM + 6;

  std::string out;
  out.reserve(4096 + spec.lanes.size() * 2048);
  openTimeSvg(out, spec.id, scale, width, height);
  appendClip(out, spec.id, scale.left, TOP, scale.width, plotHeight);
  // an interval still open at the end fades out towards it
  out += "<defs>";
  for (Severity severity : {Severity::Info, Severity::Warning, Severity::Fault}) {
    out += "<linearGradient";
    appendAttr(out, "id", std::string(spec.id) + "-open-" + std::string(severityName(severity)));
    out += "><stop offset=\"0.6\" stop-color=\"";
    out += severityColour(severity);
    out += "\"/><stop offset=\"1\" stop-color=\"";
    out += severityColour(severity);
    out += "\" stop-opacity=\"0.15\"/></linearGradient>";
  }
  out += "</defs>";
  for (std::size_t i = 0; i < spec.lanes.size(); ++i) {
    const double laneTop = TOP + static_cast<double>(i) * LANE_PX;
    if (i % 2 == 1) {
      out += "<rect";
      appendAttr(out, "x", scale.left);
      appendAttr(out, "y", laneTop);
      appendAttr(out, "width", scale.width);
      appendAttr(out, "height", LANE_PX);
      out += " fill=\"#f3f3f3\"/>";
    }
    out += "<text";
    appendAttr(out, "x", scale.left - 8);
    appendAttr(out, "y", laneTop + LANE_PX / 2.0 + 4);
    out += " text-anchor=\"end\" font-size=\"11\" fill=\"#222222\">";
    appendTitle(out, spec.lanes[i].name);
    appendXmlEscaped(out, shortened(spec.lanes[i].name, MAX_LANE_NAME_CHARS));
    out += "</text>";
  }
  appendTimeAxis(out, scale, TOP, TOP + plotHeight);
  if (spec.lanes.empty()) appendText(out, scale.left + scale.width / 2, TOP + LANE_PX / 2.0 + 4, "no data", "middle");

  const std::string clip = "url(#" + spec.id + "-clip)";
  // Bars of the intervals stretch with the zoom (group "zx").
  out += "<g";
  appendAttr(out, "clip-path", clip);
  out += "><g class=\"zx\">";
  for (std::size_t i = 0; i < spec.lanes.size(); ++i) {
    const double laneTop = TOP + static_cast<double>(i) * LANE_PX;
    for (const LaneInterval& interval : spec.lanes[i].intervals) {
      if (!std::isfinite(interval.startS) || !std::isfinite(interval.endS)) continue;
      const double x0 = scale.x(std::max(interval.startS, t0 - (t1 - t0)));
      const double x1 = scale.x(std::min(std::max(interval.endS, interval.startS), t1 + (t1 - t0)));
      out += "<rect";
      appendAttr(out, "x", x0);
      appendAttr(out, "y", laneTop + 5);
      appendAttr(out, "width", std::max(x1 - x0, 1.0));
      appendAttr(out, "height", LANE_PX - 10);
      if (interval.openEnd) {
        appendAttr(out, "fill", "url(#" + spec.id + "-open-" + std::string(severityName(interval.severity)) + ")");
      } else {
        out += " fill=\"";
        out += severityColour(interval.severity);
        out += '"';
      }
      out += " fill-opacity=\"0.75\">";
      appendTitle(out, interval.label + ": " + formatFixed(interval.startS, 3) + " s \xE2\x80\x93 " +
                           (interval.openEnd ? std::string("still active at the end")
                                             : formatFixed(interval.endS, 3) + " s"));
      out += "</rect>";
    }
  }
  out += "</g>";
  // Labels and event markers keep their size: moved one by one (data-x).
  for (std::size_t i = 0; i < spec.lanes.size(); ++i) {
    const double laneMiddle = TOP + static_cast<double>(i) * LANE_PX + LANE_PX / 2.0;
    std::vector<const LaneInterval*> intervals;
    for (const LaneInterval& interval : spec.lanes[i].intervals) {
      if (std::isfinite(interval.startS) && !interval.label.empty()) intervals.push_back(&interval);
    }
    std::stable_sort(intervals.begin(), intervals.end(),
                     [](const LaneInterval* a, const LaneInterval* b) { return a->startS < b->startS; });
    // an interval's label sits at its start, or at the plot's left edge when it began before
    std::vector<double> xs;
    std::vector<std::string> labels;
    for (const LaneInterval* interval : intervals) {
      const double x0 = scale.x(interval->startS);
      xs.push_back(x0 < scale.left && scale.x(interval->endS) > scale.left ? scale.left : x0);
      labels.push_back(shortened(interval->label, MAX_LABEL_CHARS));
    }
    std::vector<bool> shown = labelsShown(xs, labels, INTERVAL_LABEL_OFFSET, scale.left, scale.left + scale.width);
    for (std::size_t k = 0; k < intervals.size(); ++k) {
      out += "<text class=\"lbl\"";
      appendAttr(out, "data-x", scale.x(intervals[k]->startS));
      appendAttr(out, "data-e", scale.x(intervals[k]->endS));
      appendAttr(out, "x", xs[k] + INTERVAL_LABEL_OFFSET);
      appendAttr(out, "y", laneMiddle + 4);
      out += " font-size=\"11\" fill=\"#000000\"";
      if (!shown[k]) out += " display=\"none\"";
      out += '>';
      appendXmlEscaped(out, labels[k]);
      out += "</text>";
    }
    std::vector<const LaneEvent*> events;
    for (const LaneEvent& event : spec.lanes[i].events) {
      if (std::isfinite(event.s)) events.push_back(&event);
    }
    std::stable_sort(events.begin(), events.end(), [](const LaneEvent* a, const LaneEvent* b) { return a->s < b->s; });
    xs.clear();
    labels.clear();
    for (const LaneEvent* event : events) {
      xs.push_back(scale.x(event->s));
      labels.push_back(shortened(event->label, MAX_LABEL_CHARS));
    }
    shown = labelsShown(xs, labels, EVENT_LABEL_OFFSET, scale.left, scale.left + scale.width);
    for (std::size_t k = 0; k < events.size(); ++k) {
      out += "<g class=\"ev\"";
      appendAttr(out, "data-x", xs[k]);
      appendAttr(out, "data-y", laneMiddle);
      out += " transform=\"translate(";
      appendCoord(out, xs[k]);
      out += ' ';
      appendCoord(out, laneMiddle);
      out += ")\">";
      appendTitle(out, formatFixed(events[k]->s, 3) + " s: " + events[k]->label);
      out += "<path d=\"M0 -8L5 0L0 8L-5 0Z\" fill=\"";
      out += severityColour(events[k]->severity);
      out += "\"/><text x=\"7\" y=\"4\" font-size=\"11\" fill=\"#222222\"";
      if (!shown[k]) out += " display=\"none\"";
      out += '>';
      appendXmlEscaped(out, labels[k]);
      out += "</text></g>";
    }
  }
  out += "</g></svg>";
  return out;
}

}  // namespace openvcu::trace
