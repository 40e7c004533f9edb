#pragma once
// Pieces the SVG charts of svg_chart.hpp are written with (private to shared/trace):
// coordinates with one decimal, escaped attributes and texts, lines, titles (tooltips), the
// legend row and a value axis. Layout estimates assume DejaVu Sans at 12 px.
//
//   std::string out;
//   appendLine(out, 10, 20, 110, 20, GRID_COLOUR);   // <line x1="10" y1="20" x2="110" y2="20" stroke="#dddddd"/>

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/trace/svg_chart.hpp"

namespace openvcu::trace {

/// Average advance of a character of DejaVu Sans at 12 px (for layout estimates).
inline constexpr double CHAR_PX = 7.0;
inline constexpr int FONT_PX = 12;
/// Room above a plot for the legend row.
inline constexpr int LEGEND_TOP = 28;
/// Room below a plot for the tick labels and the axis title.
inline constexpr int TIME_AXIS_BOTTOM = 34;
/// Longest category or label text drawn (longer ones end in "…"; the tooltip has all).
inline constexpr std::size_t MAX_LABEL_CHARS = 28;
inline constexpr std::string_view GRID_COLOUR = "#dddddd";
inline constexpr std::string_view AXIS_COLOUR = "#555555";
inline constexpr std::string_view TEXT_COLOUR = "#222222";

/// A coordinate with one decimal ("12.5", "40"); non-finite values as 0.
void appendCoord(std::string& out, double value);
/// ` name="value"` with a coordinate or an escaped text.
void appendAttr(std::string& out, std::string_view name, double value);
void appendAttr(std::string& out, std::string_view name, std::string_view value);
/// Code points of UTF-8 text.
[[nodiscard]] std::size_t displayChars(std::string_view text);
/// At most `maxChars` code points of `text`, with "…" when cut.
[[nodiscard]] std::string shortened(std::string_view text, std::size_t maxChars);
/// `<svg class id width height viewBox font-family font-size role="img">`.
void openSvg(std::string& out, std::string_view cssClass, std::string_view id, double width, double height);
/// A <text> at (x, y); `extra` is written into the element as it is (attributes).
void appendText(std::string& out, double x, double y, std::string_view text, std::string_view anchor = "start",
                std::string_view extra = {});
void appendLine(std::string& out, double x1, double y1, double x2, double y2, std::string_view colour);
/// A <title> child: the tooltip of its parent.
void appendTitle(std::string& out, std::string_view text);
/// A legend row at the top: a square in the series colour and the name of each series.
void appendLegend(std::string& out, double left, const std::vector<std::string>& names);
/// A tick label with the decimals of the step.
[[nodiscard]] std::string tickLabel(double value, double step);
/// Horizontal grid lines and labels of a value axis from `top` over `height` px, and its
/// rotated title left of it.
void appendValueAxis(std::string& out, const AxisTicks& ticks, double left, double right, double top, double height,
                     std::string_view label);

}  // namespace openvcu::trace
