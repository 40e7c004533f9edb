// The bar charts of svg_chart.hpp: vertical (grouped, Figures 7.2 and 7.3) and horizontal
// (Figure 7.1).
#include <algorithm>
#include <cmath>

#include "openvcu/core/text.hpp"
#include "openvcu/trace/svg_chart.hpp"
#include "svg_writer.hpp"

namespace openvcu::trace {
namespace {
constexpr int BAR_ROW_PX = 22;
}  // namespace

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
}  // namespace openvcu::trace
