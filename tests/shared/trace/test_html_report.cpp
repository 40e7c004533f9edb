// The SVG charts and the self-contained HTML report of `vcu trace report` (issue 21):
// axis ticks, escaping, decimation, label overlap, the document's structure, that it
// references nothing outside itself, and that empty input gives "no data" notes.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>

#include "openvcu/trace/html_report.hpp"
#include "openvcu/trace/svg_chart.hpp"

using namespace openvcu::trace;

namespace {

constexpr double LOG_START_S = 1'700'000'000.0;
constexpr std::int64_t NS_PER_S = 1'000'000'000;
constexpr std::size_t MANY_SAMPLES = 100'000;

std::size_t occurrences(const std::string& text, std::string_view what) {
  std::size_t found = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++found;
  return found;
}

/// The coordinate pairs of the first polyline of an SVG.
std::size_t polylinePoints(const std::string& svg) {
  const std::size_t start = svg.find("points=\"");
  REQUIRE(start != std::string::npos);
  const std::size_t end = svg.find('"', start + 8);
  return occurrences(svg.substr(start + 8, end - start - 8), ",");
}

/// A report with one of everything.
ReportInput fullInput() {
  ReportInput input;
  input.title = "drive.log";
  input.source = "config/hhea/vehicle.json; logs: drive.log";
  input.stats.startS = LOG_START_S;
  input.stats.durationS = 60;
  input.stats.frames = 1000;
  input.buses = {"vehicle"};
  BusStats bus;
  bus.bus = "vehicle";
  bus.bitrate = 500'000;
  bus.frames = 1000;
  bus.loadMeanPct = 40;
  bus.loadSeries = {{0, 38}, {30, 42}, {59, 40}};
  input.stats.buses.push_back(bus);
  NodeStats node;
  node.bus = "vehicle";
  node.sa = 0x27;
  node.name = "VCU";
  node.bitsPerS = 200'000;
  node.sharePct = 100;
  input.stats.nodes.push_back(node);
  MessageStats message;
  message.bus = "vehicle";
  message.id = 0x0CF00427;
  message.extended = true;
  message.name = "EEC1";
  message.count = 6000;
  message.expectedMs = 10;
  message.meanMs = 10.4;
  message.deviationMs = 0.4;
  input.stats.messages.push_back(message);
  input.dtcs.push_back({.bus = 0,
                        .source = 0xEF,
                        .spn = 523,
                        .fmi = 3,
                        .occurrenceCount = 1,
                        .raisedNs = static_cast<std::int64_t>(LOG_START_S + 12) * NS_PER_S,
                        .clearedNs = std::nullopt});
  input.signals.push_back({"VehicleSpeed", "km/h", {{0, 0}, {30, 40}, {60, 0}}});
  input.eventLanes.push_back({"FSM state", {{5, "Driving", Severity::Info}}});
  ReportFindings sink;
  sink.finding({static_cast<std::int64_t>(LOG_START_S + 20) * NS_PER_S, 0, Severity::Fault, Check::Transport,
                "RTS/CTS timed out"});
  input.findings = sink.list();
  return input;
}

}  // namespace

TEST_CASE("nice ticks cover the range with steps of 1, 2 or 5 times a power of ten") {
  const AxisTicks percent = niceTicks(0, 87, 5);
  CHECK(percent.step == 20);
  CHECK(percent.low == 0);
  CHECK(percent.high == 100);
  CHECK(percent.values == std::vector<double>{0, 20, 40, 60, 80, 100});

  const AxisTicks small = niceTicks(0.013, 0.049, 4);
  CHECK(small.step == doctest::Approx(0.01));
  CHECK(small.low == doctest::Approx(0.01));
  CHECK(small.high == doctest::Approx(0.05));
  CHECK(small.values.size() == 5);

  const AxisTicks negative = niceTicks(-3.2, 7.9, 5);  // 11.1 / 5 = 2.22 -> 5
  CHECK(negative.step == 5);
  CHECK(negative.values == std::vector<double>{-5, 0, 5, 10});

  const AxisTicks flat = niceTicks(5, 5, 4);  // widened by 10 %
  CHECK(flat.low == doctest::Approx(4.5));
  CHECK(flat.high == doctest::Approx(5.5));
  CHECK(flat.step == doctest::Approx(0.5));

  const AxisTicks tiny = niceTicks(1e18, 1e18 + 256, 5);  // 1e18 / step 100 > 2^53: ++i stalls
  CHECK(tiny.values.size() <= 4 * 5 + 5);

    const AxisTicks bad = niceTicks(std::numeric_limits<double>::quiet_NaN(), 3, 5);
  CHECK(bad.low == 0);
  CHECK(bad.high == 1);
}

TEST_CASE("tick labels have the decimals of their step and never read -0") {
  CHECK(tickDecimals(20) == 0);
  CHECK(tickDecimals(1) == 0);
  CHECK(tickDecimals(0.5) == 1);
  CHECK(tickDecimals(0.02) == 2);
  CHECK(formatFixed(1.5, 1) == "1.5");
  CHECK(formatFixed(-0.001, 2) == "0.00");
  CHECK(formatFixed(-2.25, 1) == "-2.2");  // round half to even of the binary value
  CHECK(formatFixed(std::numeric_limits<double>::infinity(), 1) == "inf");
}

TEST_CASE("XML escaping covers markup characters, control characters and Windows-1252 text") {
  std::string out;
  appendXmlEscaped(out, "<a href='x'>&\"");
  CHECK(out == "&lt;a href=&#39;x&#39;&gt;&amp;&quot;");
  out.clear();
  appendXmlEscaped(out, "\xB0" "C");  // Windows-1252 degree sign
  CHECK(out == "\xC2\xB0" "C");
  out.clear();
  appendXmlEscaped(out, "a\x01z");
  CHECK(out == "a\xEF\xBF\xBDz");
}

TEST_CASE("a short time series is drawn sample by sample at known coordinates") {
  TimeChartSpec spec;
  spec.id = "t";
  spec.t0 = 0;
  spec.t1 = 10;
  spec.width = 1300;
  spec.height = 230;
  spec.series.push_back({"s", {{5, 10}, {0, 0}, {10, 5}}});  // out of order on purpose
  const std::string svg = timeSeriesSvg(spec);
  // plot: x from 190 over 1300 - 190 - 24 = 1086 px; y ticks 0..10, from 28 over 230 - 28 - 34 = 168 px
  CHECK(svg.find("points=\"190,196 733,28 1276,112 \"") != std::string::npos);
  CHECK(svg.find("data-t0=\"0\" data-t1=\"10\"") != std::string::npos);
  CHECK(svg.find("xmlns") == std::string::npos);
}

TEST_CASE("a long time series is decimated to MAX_SERIES_POINTS and keeps its one spike") {
  TimeChartSpec spec;
  spec.id = "long";
  spec.t0 = 0;
  spec.t1 = 100;
  TimeSeries series{"x", {}};
  for (std::size_t i = 0; i < MANY_SAMPLES; ++i) {
    series.samples.emplace_back(static_cast<double>(i) * 100.0 / MANY_SAMPLES, i == MANY_SAMPLES / 3 ? 1000.0 : 1.0);
  }
  series.samples.emplace_back(50, std::numeric_limits<double>::quiet_NaN());  // left out
  spec.series.push_back(series);
  const std::string svg = timeSeriesSvg(spec);
  const std::size_t points = polylinePoints(svg);
  CHECK(points <= MAX_SERIES_POINTS);
  CHECK(points >= MAX_SERIES_POINTS / 2);
  CHECK(svg.find(">1000</text>") != std::string::npos);  // the y axis reaches the spike
  CHECK(svg.find(",28 ") != std::string::npos);           // a vertex at the top of the plot
  CHECK(svg.find("nan") == std::string::npos);
}

TEST_CASE("vertical bars rotate their labels only when they do not fit and draw negative values down") {
  BarChartSpec few;
  few.id = "few";
  few.categories = {"A", "B"};
  few.series = {{"d", {2, -1}}};
  const std::string fewSvg = verticalBarsSvg(few);
  CHECK(fewSvg.find("rotate(-60") == std::string::npos);
  CHECK(fewSvg.find(">-1.0</text>") != std::string::npos);  // the axis goes below zero

  BarChartSpec many;
  many.id = "many";
  for (int i = 0; i < 80; ++i) many.categories.push_back("VeryLongMessageName_" + std::to_string(i));
  many.series = {{"expected", std::vector<double>(80, 10.0)}, {"measured", std::vector<double>(80, 11.0)}};
  const std::string manySvg = verticalBarsSvg(many);
  CHECK(occurrences(manySvg, "rotate(-60") == 80);
  CHECK(occurrences(manySvg, "<rect") == 80 * 2 + 2);  // bars and the two legend squares
}

TEST_CASE("lanes hide a label that would overlap the next marker or leave the plot and fade intervals still open") {
  LanesChartSpec spec;
  spec.id = "lanes";
  spec.t0 = 0;
  spec.t1 = 100;
  spec.lanes.push_back({"FSM", {}, {{10, "Standby", Severity::Info}, {10.1, "Ready", Severity::Info}}});
  spec.lanes.push_back({"DTC", {{20, 100, true, "OC 1", Severity::Warning}}, {}});
  spec.lanes.push_back({"late", {}, {{99.9, "at the right edge", Severity::Fault}}});
  const std::string svg = lanesSvg(spec);
  CHECK(occurrences(svg, "display=\"none\">at the right edge") == 1);  // would leave the plot
  CHECK(occurrences(svg, "display=\"none\">Standby") == 1);
  CHECK(occurrences(svg, "display=\"none\">Ready") == 0);
  CHECK(svg.find("fill=\"url(#lanes-open-warning)\"") != std::string::npos);
  CHECK(svg.find("still active at the end") != std::string::npos);
}

TEST_CASE("the report is one document with a CSP that forbids fetching, its charts and captions") {
  const std::string html = renderHtmlReport(fullInput());
  CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
  CHECK(html.find("<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src "
                  "'unsafe-inline'; script-src 'unsafe-inline'; img-src data:\">") != std::string::npos);
  CHECK(occurrences(html, "<script") == 1);
  CHECK(occurrences(html, "<pre id=\"chart-layout\" hidden></pre>") == 1);
  for (const char* chart : {"bus-load", "node-rate", "cycle-compare", "cycle-difference", "signals-1", "dtc-timeline",
                            "event-lanes"}) {
    CAPTURE(chart);
    CHECK(occurrences(html, "<div class=\"chart\" data-chart=\"" + std::string(chart) + "\">") == 1);
  }
  CHECK(occurrences(html, "class=\"chart\"") == 7);
  CHECK(html.find("thesis Fig. 7.1") != std::string::npos);
  CHECK(html.find("thesis Fig. 7.2") != std::string::npos);
  CHECK(html.find("thesis Fig. 7.3") != std::string::npos);
  CHECK(html.find("<td class=\"l\">EEC1</td>") != std::string::npos);     // the message table
  CHECK(html.find("12.000 s") != std::string::npos);                       // the DTC at start + 12 s
  CHECK(html.find("<td>20.000000</td>") != std::string::npos);             // the finding at start + 20 s
  CHECK(html.size() > 0);
  CHECK(html.substr(html.size() - 8) == "</html>\n");
}

TEST_CASE("the report references nothing outside itself") {
  const std::string html = renderHtmlReport(fullInput());
  CHECK(html.find("http://") == std::string::npos);
  CHECK(html.find("https://") == std::string::npos);
  CHECK(html.find("//cdn") == std::string::npos);
  CHECK(html.find("src=") == std::string::npos);
  CHECK(html.find("@import") == std::string::npos);
  CHECK(occurrences(html, "href=\"") == occurrences(html, "href=\"#"));  // links inside the document only
  std::size_t urls = occurrences(html, "url(");
  CHECK(urls == occurrences(html, "url(#"));
}

TEST_CASE("markup in names and texts is shown as text, never run (issue 21)") {
  ReportInput input = fullInput();
  input.title = "a & b";
  input.signals.push_back({"<script>alert(1)</script>", "<b>V</b>", {{1, 1}, {2, 2}}});
  input.findings.kept.push_back({0, 0, Severity::Info, Check::Log, "text </script><img src=x>"});
  const std::string html = renderHtmlReport(input);
  CHECK(occurrences(html, "<script") == 1);
  CHECK(occurrences(html, "</script>") == 1);
  CHECK(html.find("&lt;script&gt;alert(1)&lt;/script&gt;") != std::string::npos);
  CHECK(html.find("[&lt;b&gt;V&lt;/b&gt;]") != std::string::npos);
  CHECK(html.find("<title>a &amp; b</title>") != std::string::npos);
  CHECK(html.find("<img") == std::string::npos);
}

TEST_CASE("an empty input gives a valid document with no-data notes and no charts") {
  const std::string html = renderHtmlReport(ReportInput{});
  CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
  CHECK(html.find("No frames: no bus load.") != std::string::npos);
  CHECK(html.find("No messages.") != std::string::npos);
  CHECK(html.find("No signals chosen.") != std::string::npos);
  CHECK(html.find("No DTC was raised") != std::string::npos);
  CHECK(html.find("No events and no findings.") != std::string::npos);
  CHECK(html.find("No findings.") != std::string::npos);
  CHECK(html.find("class=\"chart\"") == std::string::npos);
  CHECK(html.find("<pre id=\"chart-layout\" hidden></pre>") != std::string::npos);
  CHECK(html.substr(html.size() - 8) == "</html>\n");
}

TEST_CASE("non-finite statistics and samples give charts without nan coordinates") {
  ReportInput input = fullInput();
  input.stats.messages[0].meanMs = std::numeric_limits<double>::quiet_NaN();
  input.stats.nodes[0].bitsPerS = std::numeric_limits<double>::infinity();
  input.signals[0].samples.emplace_back(std::numeric_limits<double>::infinity(), 3);
  input.eventLanes[0].events.push_back({std::numeric_limits<double>::quiet_NaN(), "lost", Severity::Info});
  const std::string html = renderHtmlReport(input);
  CHECK(html.find("=\"nan") == std::string::npos);
  CHECK(html.find("=\"inf") == std::string::npos);
  CHECK(html.find(",nan") == std::string::npos);
}

TEST_CASE("the same input renders the same bytes") {
  CHECK(renderHtmlReport(fullInput()) == renderHtmlReport(fullInput()));
}

TEST_CASE("a report keeps the first MAX_REPORT_FINDINGS findings and counts all of them") {
  ReportFindings sut;
  const std::size_t total = MAX_REPORT_FINDINGS + 500;
  for (std::size_t i = 0; i < total; ++i) {
    sut.finding({static_cast<std::int64_t>(i), 0, i % 2 ? Severity::Warning : Severity::Fault, Check::Cycle, "gap"});
  }
  REQUIRE(sut.list().kept.size() == MAX_REPORT_FINDINGS);
  CHECK(sut.list().total == total);
  CHECK(sut.list().bySeverity[static_cast<std::size_t>(Severity::Fault)] == total / 2);
  CHECK(sut.list().bySeverity[static_cast<std::size_t>(Severity::Warning)] == total / 2);
  ReportInput input;
  input.findings = sut.list();
  const std::string html = renderHtmlReport(input);
  CHECK(html.find("The first 2000 of 2500 findings") != std::string::npos);
}
