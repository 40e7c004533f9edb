#pragma once
// The inline stylesheet and script of the HTML report (html_report.hpp), kept apart from
// the document's structure. The script zooms and pans every time chart (svg.tsvg, see
// svg_chart.hpp) together and writes the chart layout into <pre id="chart-layout">.

#include <string_view>

namespace openvcu::trace {

/// The report's CSS (no url(), no @import: nothing to fetch).
[[nodiscard]] std::string_view reportStyle() noexcept;
/// The report's script (plain ES5, no eval, nothing fetched).
[[nodiscard]] std::string_view reportScript() noexcept;

}  // namespace openvcu::trace
