// The building blocks of the SVG charts (svg_writer.hpp) and the public basics of
// svg_chart.hpp: nice ticks, fixed-decimal numbers, XML escaping, colours.
#include "svg_writer.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>

#include "openvcu/core/text.hpp"

namespace openvcu::trace {

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

void appendText(std::string& out, double x, double y, std::string_view text, std::string_view anchor,
                std::string_view extra) {
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

std::string tickLabel(double value, double step) { return formatFixed(value, tickDecimals(step)); }


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
  // bounded: at the limits of double precision ++i may not move i
  for (double i = first; i <= last && ticks.values.size() <= 4 * maxTicks + 4; ++i) {
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

}  // namespace openvcu::trace
