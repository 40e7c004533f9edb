#include "openvcu/trace/svg_chart.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>

#include "openvcu/core/text.hpp"
#include "openvcu/trace/sample_ring.hpp"

namespace openvcu::trace {
namespace {

/// Average advance of a character of DejaVu Sans at 12 px (for layout estimates).
constexpr double CHAR_PX = 7.0;
constexpr int FONT_PX = 12;
constexpr int LEGEND_TOP = 28;
constexpr int TIME_AXIS_BOTTOM = 34;
constexpr int LANE_PX = 26;
constexpr int BAR_ROW_PX = 22;
constexpr std::size_t MAX_LABEL_CHARS = 28;
constexpr std::size_t MAX_LANE_NAME_CHARS = 28;
/// Average advance of a character at 11 px (lane labels).
constexpr double LABEL_CHAR_PX = 6.5;
/// The label of an event starts this far right of its marker.
constexpr double EVENT_LABEL_OFFSET = 7;
constexpr std::string_view GRID_COLOUR = "#dddddd";
constexpr std::string_view AXIS_COLOUR = "#555555";
constexpr std::string_view TEXT_COLOUR = "#222222";

/// A coordinate with one decimal ("12.5", "40"): enough for pixels, short to write.
void appendCoord(std::string& out, double value) {
  if (!std::isfinite(value)) value = 0;
  const double rounded = std::round(value * 10.0) / 10.0;
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), rounded == 0 ? 0.0 : rounded,
                                    std::chars_format::fixed, 1);
  std::string_view text(buffer.data(), static_cast<std::size_t>(result.ptr - buffer.data()));
  if (text.size() > 2 && text.substr(text.size() - 2) == ".0") text.remove_suffix(2);
  out += text;
}

void appendAttr(std::string& out, std::string_view name, double value) {
  out += ' ';
  out += name;
  out += "=\"";
  appendCoord(out, value);
  out += '"';
}

void appendAttr(std::string& out, std::string_view name, std::string_view value) {
  out += ' ';
  out += name;
  out += "=\"";
  appendXmlEscaped(out, value);
  out += '"';
}

/// Code points of UTF-8 text (continuation bytes not counted).
std::size_t displayChars(std::string_view text) {
  return static_cast<std::size_t>(
      std::count_if(text.begin(), text.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

/// At most `maxChars` code points of `text`, with "…" when cut.
std::string shortened(std::string_view text, std::size_t maxChars) {
  if (displayChars(text) <= maxChars) return std::string(text);
  std::size_t chars = 0;
  std::size_t end = 0;
  for (; end < text.size(); ++end) {
    if ((static_cast<unsigned char>(text[end]) & 0xC0) != 0x80) {
      if (chars == maxChars - 1) break;
      ++chars;
    }
  }
  return std::string(text.substr(0, end)) + "\xE2\x80\xA6";
}

void openSvg(std::string& out, std::string_view cssClass, std::string_view id, double width, double height) {
  out += "<svg";
  appendAttr(out, "class", cssClass);
  appendAttr(out, "id", id);
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

void appendText(std::string& out, double x, double y, std::string_view text, std::string_view anchor = "start",
                std::string_view extra = {}) {
  out += "<text";
  appendAttr(out, "x", x);
  appendAttr(out, "y", y);
  if (anchor != "start") appendAttr(out, "text-anchor", anchor);
  out += " fill=\"";
  out += TEXT_COLOUR;
  out += '"';
  if (!extra.empty()) {
    out += ' ';
    out += extra;
  }
  out += '>';
  appendXmlEscaped(out, text);
  out += "</text>";
}

void appendLine(std::string& out, double x1, double y1, double x2, double y2, std::string_view colour) {
  out += "<line";
  appendAttr(out, "x1", x1);
  appendAttr(out, "y1", y1);
  appendAttr(out, "x2", x2);
  appendAttr(out, "y2", y2);
  out += " stroke=\"";
  out += colour;
  out += "\"/>";
}

void appendTitle(std::string& out, std::string_view text) {
  out += "<title>";
  appendXmlEscaped(out, text);
  out += "</title>";
}

/// A legend row at the top: a square and the name of each series.
void appendLegend(std::string& out, double left, const std::vector<std::string>& names) {
  double x = left;
  for (std::size_t i = 0; i < names.size(); ++i) {
    out += "<rect";
    appendAttr(out, "x", x);
    appendAttr(out, "y", 8);
    out += " width=\"12\" height=\"12\" fill=\"";
    out += seriesColour(i);
    out += "\"/>";
    const std::string name = shortened(names[i], MAX_LABEL_CHARS * 2);
    appendText(out, x + 16, 18, name);
    x += 16 + static_cast<double>(displayChars(name)) * CHAR_PX + 18;
  }
}

/// A tick label of the time axis ("12.5 s" style: the unit is on the axis title).
std::string tickLabel(double value, double step) { return formatFixed(value, tickDecimals(step)); }

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

/// Horizontal grid lines and labels of a value axis, and its rotated title.
void appendValueAxis(std::string& out, const AxisTicks& ticks, double left, double right, double top, double height,
                     std::string_view label) {
  const auto y = [&](double v) { return top + height - (v - ticks.low) / (ticks.high - ticks.low) * height; };
  for (double value : ticks.values) {
    appendLine(out, left, y(value), right, y(value), GRID_COLOUR);
    appendText(out, left - 6, y(value) + 4, tickLabel(value, ticks.step), "end");
  }
  appendLine(out, left, top, left, top + height, AXIS_COLOUR);
  std::string rotate = "transform=\"rotate(-90 ";
  const double labelX = left - 52;
  const double labelY = top + height / 2;
  appendCoord(rotate, labelX);
  rotate += ' ';
  appendCoord(rotate, labelY);
  rotate += ")\"";
  appendText(out, labelX, labelY, label, "middle", rotate);
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

/// Which labels of a lane to show: a label (at x + offset, anchors sorted by x) shows when it
/// starts after the previous shown label and ends before the next anchor or, the last one,
/// before `right` (the plot's end) (the report's
/// script applies the same rule after a zoom).
std::vector<bool> labelsShown(const std::vector<double>& xs, const std::vector<std::string>& labels, double offset,
                              double right) {
  std::vector<bool> shown(xs.size());
  double end = -INFINITY;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const double start = xs[k] + offset;
    const double labelEnd = start + static_cast<double>(displayChars(labels[k])) * LABEL_CHAR_PX;
    const bool roomBefore = start >= end + 4;
    const bool roomAfter = k + 1 == xs.size() ? labelEnd <= right : xs[k + 1] - 6 > labelEnd;
    shown[k] = roomBefore && roomAfter;
    if (shown[k]) end = labelEnd;
  }
  return shown;
}

}  // namespace

AxisTicks niceTicks(double low, double high, std::size_t maxTicks) {
  AxisTicks ticks;
  if (!std::isfinite(low) || !std::isfinite(high)) {
    low = 0;
    high = 1;
  }
  if (high < low) std::swap(low, high);
  if (high == low) {
    const double pad = low == 0 ? 1.0 : std::fabs(low) * 0.1;
    low -= pad;
    high += pad;
  }
  maxTicks = std::max<std::size_t>(maxTicks, 1);
  const double raw = (high - low) / static_cast<double>(maxTicks);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double residual = raw / magnitude;
  double step = 10 * magnitude;
  for (double candidate : {1.0, 2.0, 5.0}) {
    if (residual <= candidate * (1 + 1e-9)) {
      step = candidate * magnitude;
      break;
    }
  }
  const double first = std::floor(low / step + 1e-9);
  const double last = std::ceil(high / step - 1e-9);
  ticks.step = step;
  ticks.low = first * step;
  ticks.high = last * step;
  for (double i = first; i <= last; ++i) {
    const double value = i * step;
    ticks.values.push_back(std::fabs(value) < step * 1e-9 ? 0.0 : value);
  }
  return ticks;
}

int tickDecimals(double step) {
  if (!(step > 0) || !std::isfinite(step)) return 0;
  return std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
}

std::string formatFixed(double value, int decimals) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  std::array<char, 64> buffer{};
  const auto result =
      std::to_chars(buffer.data(), buffer.data() + buffer.size(), value, std::chars_format::fixed, decimals);
  if (result.ec != std::errc{}) return text::number(value);
  std::string text(buffer.data(), result.ptr);
  if (text.front() == '-' && text.find_first_not_of("-0.") == std::string::npos) text.erase(0, 1);
  return text;
}

void appendXmlEscaped(std::string& out, std::string_view input) {
  std::string converted;
  if (!text::isValidUtf8(input)) {
    converted = text::cp1252ToUtf8(input);
    input = converted;
  }
  for (char c : input) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n') {
          out += "\xEF\xBF\xBD";  // U+FFFD: XML 1.0 has no control characters
        } else {
          out += c;
        }
    }
  }
}

std::string_view seriesColour(std::size_t index) {
  // Okabe & Ito's palette for colour-blind readers (black last).
  static constexpr std::array<std::string_view, 8> PALETTE{"#0072B2", "#E69F00", "#009E73", "#D55E00",
                                                           "#CC79A7", "#56B4E9", "#8C6D00", "#000000"};
  return PALETTE[index % PALETTE.size()];
}

std::string_view severityColour(Severity severity) {
  switch (severity) {
    case Severity::Info: return "#0072B2";
    case Severity::Warning: return "#E69F00";
    case Severity::Fault: return "#D55E00";
  }
  return "#000000";
}

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

std::string verticalBarsSvg(const BarChartSpec& spec) {
  const std::size_t count = spec.categories.size();
  const std::size_t seriesCount = std::max<std::size_t>(spec.series.size(), 1);
  constexpr double LEFT = 80;
  constexpr double RIGHT = 16;
  const double plotWidth = std::max(static_cast<double>(spec.width) - LEFT - RIGHT,
                                    static_cast<double>(count) * MIN_CATEGORY_PX);
  const double width = LEFT + RIGHT + plotWidth;
  const double group = count == 0 ? plotWidth : plotWidth / static_cast<double>(count);
  std::size_t longest = 0;
  for (const std::string& category : spec.categories) {
    longest = std::max(longest, std::min(displayChars(category), MAX_LABEL_CHARS));
  }
  const bool rotated = static_cast<double>(longest) * CHAR_PX + 6 > group;
  const double labelRoom = rotated ? static_cast<double>(longest) * CHAR_PX * 0.87 + 20 : 24;
  const double top = LEGEND_TOP;
  const double plotHeight = std::max(120.0, static_cast<double>(spec.height) - top - 24);
  const double height = top + plotHeight + labelRoom;

  double low = 0;
  double high = 0;
  for (const BarSeries& series : spec.series) {
    for (double v : series.values) {
      if (!std::isfinite(v)) continue;
      low = std::min(low, v);
      high = std::max(high, v);
    }
  }
  const AxisTicks ticks = niceTicks(low, high == low ? low + 1 : high, 6);
  const auto y = [&](double v) { return top + plotHeight - (v - ticks.low) / (ticks.high - ticks.low) * plotHeight; };

  std::string out;
  out.reserve(2048 + count * seriesCount * 160);
  openSvg(out, "bsvg", spec.id, width, height);
  std::vector<std::string> names;
  for (const BarSeries& series : spec.series) names.push_back(series.name);
  if (names.size() > 1) appendLegend(out, LEFT, names);
  appendValueAxis(out, ticks, LEFT, LEFT + plotWidth, top, plotHeight, spec.valueLabel);
  if (count == 0) appendText(out, LEFT + plotWidth / 2, top + plotHeight / 2, "no data", "middle");
  const double barWidth = group * 0.8 / static_cast<double>(seriesCount);
  for (std::size_t c = 0; c < count; ++c) {
    const double groupLeft = LEFT + static_cast<double>(c) * group;
    for (std::size_t s = 0; s < spec.series.size(); ++s) {
      const double v = c < spec.series[s].values.size() ? spec.series[s].values[c] : 0.0;
      if (!std::isfinite(v)) continue;
      const double y0 = y(0);
      const double y1 = y(v);
      out += "<rect";
      appendAttr(out, "x", groupLeft + group * 0.1 + static_cast<double>(s) * barWidth);
      appendAttr(out, "y", std::min(y0, y1));
      appendAttr(out, "width", std::max(barWidth, 1.0));
      appendAttr(out, "height", std::max(std::fabs(y1 - y0), v == 0 ? 0.0 : 1.0));
      out += " fill=\"";
      out += seriesColour(s);
      out += "\">";
      appendTitle(out, spec.categories[c] + (spec.series[s].name.empty() ? "" : " \xE2\x80\x94 " + spec.series[s].name) +
                           ": " + text::number(v));
      out += "</rect>";
    }
    const std::string label = shortened(spec.categories[c], MAX_LABEL_CHARS);
    const double x = groupLeft + group / 2;
    const double labelY = top + plotHeight + 14;
    if (rotated) {
      std::string rotate = "transform=\"rotate(-60 ";
      appendCoord(rotate, x);
      rotate += ' ';
      appendCoord(rotate, labelY);
      rotate += ")\" font-size=\"11\"";
      appendText(out, x + 4, labelY, label, "end", rotate);
    } else {
      appendText(out, x, labelY, label, "middle");
    }
  }
  appendLine(out, LEFT, y(0), LEFT + plotWidth, y(0), AXIS_COLOUR);
  out += "</svg>";
  return out;
}

std::string horizontalBarsSvg(const BarChartSpec& spec) {
  const std::size_t count = spec.categories.size();
  const std::size_t seriesCount = std::max<std::size_t>(spec.series.size(), 1);
  std::size_t longest = 4;
  for (const std::string& category : spec.categories) {
    longest = std::max(longest, std::min(displayChars(category), MAX_LABEL_CHARS + 8));
  }
  const double left = static_cast<double>(longest) * CHAR_PX + 16;
  constexpr double RIGHT = 90;  // room for the annotations
  const double plotWidth = std::max(100.0, static_cast<double>(spec.width) - left - RIGHT);
  const double width = left + plotWidth + RIGHT;
  const double top = spec.series.size() > 1 ? LEGEND_TOP : 8;
  const double plotHeight = static_cast<double>(std::max<std::size_t>(count, 1)) * BAR_ROW_PX;
  const double height = top + plotHeight + TIME_AXIS_BOTTOM + 6;

  double high = 0;
  double low = 0;
  for (const BarSeries& series : spec.series) {
    for (double v : series.values) {
      if (!std::isfinite(v)) continue;
      low = std::min(low, v);
      high = std::max(high, v);
    }
  }
  const AxisTicks ticks = niceTicks(low, high == low ? low + 1 : high, 8);
  const auto x = [&](double v) { return left + (v - ticks.low) / (ticks.high - ticks.low) * plotWidth; };

  std::string out;
  out.reserve(2048 + count * seriesCount * 200);
  openSvg(out, "bsvg", spec.id, width, height);
  std::vector<std::string> names;
  for (const BarSeries& series : spec.series) names.push_back(series.name);
  if (names.size() > 1) appendLegend(out, left, names);
  for (double value : ticks.values) {
    appendLine(out, x(value), top, x(value), top + plotHeight, GRID_COLOUR);
    appendText(out, x(value), top + plotHeight + 15, tickLabel(value, ticks.step), "middle");
  }
  appendText(out, left + plotWidth, top + plotHeight + 30, spec.valueLabel, "end");
  if (count == 0) appendText(out, left + plotWidth / 2, top + plotHeight / 2 + 4, "no data", "middle");
  const double barHeight = (BAR_ROW_PX - 6.0) / static_cast<double>(seriesCount);
  for (std::size_t c = 0; c < count; ++c) {
    const double rowTop = top + static_cast<double>(c) * BAR_ROW_PX;
    appendText(out, left - 6, rowTop + BAR_ROW_PX / 2.0 + 4, shortened(spec.categories[c], MAX_LABEL_CHARS + 8), "end");
    double barEnd = x(0);
    for (std::size_t s = 0; s < spec.series.size(); ++s) {
      const double v = c < spec.series[s].values.size() ? spec.series[s].values[c] : 0.0;
      if (!std::isfinite(v)) continue;
      const double x0 = x(0);
      const double x1 = x(v);
      barEnd = std::max(barEnd, x1);
      out += "<rect";
      appendAttr(out, "x", std::min(x0, x1));
      appendAttr(out, "y", rowTop + 3 + static_cast<double>(s) * barHeight);
      appendAttr(out, "width", std::max(std::fabs(x1 - x0), v == 0 ? 0.0 : 1.0));
      appendAttr(out, "height", barHeight);
      out += " fill=\"";
      out += seriesColour(s);
      out += "\">";
      appendTitle(out, spec.categories[c] + (spec.series[s].name.empty() ? "" : " \xE2\x80\x94 " + spec.series[s].name) +
                           ": " + text::number(v));
      out += "</rect>";
    }
    if (c < spec.annotations.size() && !spec.annotations[c].empty()) {
      appendText(out, barEnd + 6, rowTop + BAR_ROW_PX / 2.0 + 4, spec.annotations[c]);
    }
  }
  appendLine(out, x(0), top, x(0), top + plotHeight, AXIS_COLOUR);
  out += "</svg>";
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
    std::vector<double> xs;
    std::vector<std::string> labels;
    for (const LaneInterval* interval : intervals) {
      xs.push_back(scale.x(interval->startS) + 3);
      labels.push_back(shortened(interval->label, MAX_LABEL_CHARS));
    }
    std::vector<bool> shown = labelsShown(xs, labels, 0, scale.left + scale.width);
    for (std::size_t k = 0; k < intervals.size(); ++k) {
      out += "<text class=\"lbl\"";
      appendAttr(out, "data-x", xs[k]);
      appendAttr(out, "x", xs[k]);
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
    shown = labelsShown(xs, labels, EVENT_LABEL_OFFSET, scale.left + scale.width);
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
