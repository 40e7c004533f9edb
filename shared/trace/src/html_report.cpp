#include "openvcu/trace/html_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>

#include "openvcu/core/text.hpp"
#include "openvcu/trace/frame_writer.hpp"
#include "openvcu/trace/svg_chart.hpp"
#include "report_assets.hpp"
#include "svg_writer.hpp"

namespace openvcu::trace {
namespace {

constexpr int CHART_WIDTH = 1300;
constexpr double NS_PER_S = 1e9;
/// Lanes of the DTC timeline (one per bus, source, SPN, FMI, DM1/DM2); further ones are counted.
constexpr std::size_t MAX_DTC_LANES = 60;
/// Rows of the DTC table; all intervals are drawn.
constexpr std::size_t MAX_DTC_ROWS = 1000;
/// Longest bus name in a node label (cut in the middle): leaves the DBC name 10 characters.
constexpr std::size_t NODE_LABEL_BUS_CHARS = 20;
static_assert(NODE_LABEL_BUS_CHARS + 6 + 10 <= HORIZONTAL_LABEL_CHARS);

void esc(std::string& out, std::string_view text) { appendXmlEscaped(out, text); }

std::string hex(std::uint32_t value, int digits) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%0*X", digits, value);
  return buffer;
}

std::string count(std::uint64_t value) { return std::to_string(value); }

std::string busName(const ReportInput& input, std::uint16_t bus) {
  return bus < input.buses.size() ? input.buses[bus] : "bus " + std::to_string(bus);
}

double secondsFromStart(const ReportInput& input, std::int64_t ns) {
  return static_cast<double>(ns) / NS_PER_S - input.stats.startS;
}

/// At most `maxChars` code points of `text`, cut in the middle ("vehicle_b…_can_1"): names
/// that differ only at their end stay apart.
std::string middleShortened(std::string_view text, std::size_t maxChars) {
  const std::size_t chars = displayChars(text);
  if (chars <= maxChars || maxChars < 3) return std::string(text);
  const std::size_t head = (maxChars - 1) / 2;
  const std::size_t tail = maxChars - 1 - head;
  std::size_t headEnd = 0;
  std::size_t tailStart = 0;
  std::size_t seen = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if ((static_cast<unsigned char>(text[i]) & 0xC0) == 0x80) continue;  // UTF-8 continuation byte
    if (seen == head) headEnd = i;
    if (seen == chars - tail) tailStart = i;
    ++seen;
  }
  return std::string(text.substr(0, headEnd)) + "\xE2\x80\xA6" + std::string(text.substr(tailStart));
}

/// A node's row label in the data-rate chart: the SA first, then the DBC name, the bus in front
/// when there are several ("can1 0x27 Vehicle_Control_Unit"). What tells nodes apart (bus and
/// SA) is never cut: only the name is shortened to the chart's label width (the table has all).
std::string nodeLabel(const NodeStats& node, bool withBus) {
  std::string label = withBus ? middleShortened(node.bus, NODE_LABEL_BUS_CHARS) + " " : std::string();
  if (node.standard) return label + "11-bit frames";
  label += hex(node.sa, 2);
  if (node.name.empty()) return label;
  const std::size_t used = displayChars(label) + 1;
  return label + " " + shortened(node.name, HORIZONTAL_LABEL_CHARS - used);
}

std::string messageId(const MessageStats& message) { return hex(message.id, message.extended ? 8 : 3); }

std::string messageLabel(const MessageStats& message, bool withBus) {
  std::string label = withBus ? message.bus + " " : std::string();
  return label + (message.name.empty() ? messageId(message) : message.name + " " + messageId(message));
}

std::string_view cycleSourceName(CycleSource source) {
  switch (source) {
    case CycleSource::None: return "-";
    case CycleSource::Schedule: return "schedule";
    case CycleSource::Attribute: return "DBC";
  }
  return "?";
}

/// Table building: header cells then rows; "l" marks left-aligned (text) columns.
void openTable(std::string& out, std::initializer_list<std::string_view> headers, std::string_view leftColumns) {
  out += "<div class=\"tablewrap\"><table><thead><tr>";
  std::size_t i = 0;
  for (std::string_view header : headers) {
    out += i < leftColumns.size() && leftColumns[i] == 'l' ? "<th class=\"l\">" : "<th>";
    esc(out, header);
    out += "</th>";
    ++i;
  }
  out += "</tr></thead><tbody>";
}

void appendRow(std::string& out, std::initializer_list<std::string> cells, std::string_view leftColumns,
               std::string_view rowClass = {}) {
  out += rowClass.empty() ? "<tr>" : "<tr class=\"" + std::string(rowClass) + "\">";
  std::size_t i = 0;
  for (const std::string& cell : cells) {
    const char kind = i < leftColumns.size() ? leftColumns[i] : 'r';
    out += kind == 'l' ? "<td class=\"l\">" : kind == 'w' ? "<td class=\"l w\">" : "<td>";
    esc(out, cell);
    out += "</td>";
    ++i;
  }
  out += "</tr>";
}

void closeTable(std::string& out) { out += "</tbody></table></div>"; }

void noData(std::string& out, std::string_view what) {
  out += "<p class=\"nodata\">";
  esc(out, what);
  out += "</p>";
}

/// A figure: the chart element (class "chart", data-chart) and its caption.
void appendFigure(std::string& out, int& number, std::string_view id, const std::string& svg,
                  std::string_view caption) {
  out += "<figure><div class=\"chart\" data-chart=\"";
  esc(out, id);
  out += "\">";
  out += svg;
  out += "</div><figcaption><b>Figure " + std::to_string(++number) + ".</b> ";
  esc(out, caption);
  out += "</figcaption></figure>";
}

/// The time range of the time charts: the timeline, widened to every sample and event.
std::pair<double, double> timeAxis(const ReportInput& input) {
  double t0 = 0;
  double t1 = input.stats.durationS;
  const auto widen = [&](double s) {
    if (!std::isfinite(s)) return;
    t0 = std::min(t0, s);
    t1 = std::max(t1, s);
  };
  for (const BusStats& bus : input.stats.buses) {
    if (!bus.loadSeries.empty()) widen(bus.loadSeries.back().first + bus.loadBucketS);
  }
  for (const SignalSeries& signal : input.signals) {
    for (const auto& sample : signal.samples) widen(sample.first);
  }
  for (const EventLane& lane : input.eventLanes) {
    for (const ReportEvent& event : lane.events) widen(event.s);
  }
  if (!(t1 > t0)) t1 = t0 + 1;
  return {t0, t1};
}

void appendHeader(std::string& out, const ReportInput& input) {
  const StatsReport& stats = input.stats;
  out += "<header><h1>";
  esc(out, input.title.empty() ? std::string("CAN trace report") : input.title);
  out += "</h1><p class=\"source\">";
  esc(out, input.source);
  out += "</p><table class=\"summary\"><tbody>";
  const auto row = [&](std::string_view name, const std::string& value) {
    out += "<tr><th class=\"l\">";
    esc(out, name);
    out += "</th><td>";
    esc(out, value);
    out += "</td></tr>";
  };
  row("first frame", formatFixed(stats.startS, 6) + " s (the log's time; the time axes count from it)");
  row("duration", formatFixed(stats.durationS, 3) + " s");
  row("frames", count(stats.frames) + (stats.skippedFrames ? " (" + count(stats.skippedFrames) +
                                                                    " of streams beyond the limit of " +
                                                                    count(MAX_STREAMS) + " not measured)"
                                                              : std::string()));
  row("buses / nodes / messages", count(stats.buses.size()) + " / " + count(stats.nodes.size()) + " / " +
                                      count(stats.messages.size()));
  const FindingList& findings = input.findings;
  row("findings", count(findings.total) + " (" + count(findings.bySeverity[2]) + " faults, " +
                      count(findings.bySeverity[1]) + " warnings, " + count(findings.bySeverity[0]) + " info)");
  if (stats.backwardSteps) row("time going backwards", count(stats.backwardSteps) + " periods not measured");
  out += "</tbody></table>";
  out += "<nav><a href=\"#load\">Bus load</a><a href=\"#nodes\">Nodes</a><a href=\"#cycles\">Cycles</a>"
         "<a href=\"#signals\">Signals</a><a href=\"#dtc\">DTCs</a><a href=\"#events\">Events</a>"
         "<a href=\"#findings\">Findings</a></nav>";
  out += "<p class=\"hint\">Time charts share one time axis: the mouse wheel zooms, dragging pans, a double "
         "click shows everything again; hover over a bar or marker for its values. "
         "<span id=\"view-range\"></span></p></header>";
}

void appendBusSection(std::string& out, const ReportInput& input, double t0, double t1, int& figure) {
  out += "<section id=\"load\"><h2>Bus load</h2>";
  if (input.stats.buses.empty()) {
    noData(out, "No frames: no bus load.");
    out += "</section>";
    return;
  }
  openTable(out, {"bus", "bit rate [bit/s]", "frames", "error frames", "duration [s]", "mean load [%]",
                  "peak load [%] (1 s window)"},
            "l");
  for (const BusStats& bus : input.stats.buses) {
    appendRow(out, {bus.bus, count(bus.bitrate), count(bus.frames), count(bus.errorFrames),
                    formatFixed(bus.durationS, 3), formatFixed(bus.loadMeanPct, 2), formatFixed(bus.loadMaxPct, 2)},
              "l");
  }
  closeTable(out);
  TimeChartSpec spec{.id = "bus-load", .yLabel = "bus load [%]", .t0 = t0, .t1 = t1, .width = CHART_WIDTH};
  for (const BusStats& bus : input.stats.buses) {
    TimeSeries series{bus.bus, {}};
    for (const auto& [s, pct] : bus.loadSeries) series.samples.emplace_back(s, pct);
    spec.series.push_back(std::move(series));
  }
  appendFigure(out, figure, "bus-load", timeSeriesSvg(spec),
               "Bus load over time per bus: the wire bits of each frame (stuff bits included) per bucket "
               "divided by the bucket's length and the bus's bit rate.");
  out += "</section>";
}

void appendNodeSection(std::string& out, const ReportInput& input, int& figure) {
  out += "<section id=\"nodes\"><h2>Data rate per node</h2>";
  if (input.stats.nodes.empty()) {
    noData(out, "No frames: no nodes.");
    out += "</section>";
    return;
  }
  BarChartSpec spec{.id = "node-rate", .valueLabel = "data rate [kbit/s]", .width = CHART_WIDTH};
  BarSeries rate{"data rate", {}};
  const bool severalBuses = input.stats.buses.size() > 1;
  for (const NodeStats& node : input.stats.nodes) {
    spec.categories.push_back(nodeLabel(node, severalBuses));
    rate.values.push_back(node.bitsPerS / 1000.0);
    spec.annotations.push_back(formatFixed(node.sharePct, 1) + " %");
  }
  spec.series.push_back(std::move(rate));
  appendFigure(out, figure, "node-rate", horizontalBarsSvg(spec),
               "Data rate per transmitting node (thesis Fig. 7.1): wire bits per second of every node "
               "(J1939 source address; all 11-bit frames of a bus as one), with its share of its bus's bits.");
  openTable(out, {"bus", "node", "SA", "frames", "data rate [bit/s]", "share [%]"}, "ll");
  for (const NodeStats& node : input.stats.nodes) {
    appendRow(out, {node.bus, node.standard ? "11-bit frames" : node.name, node.standard ? "-" : hex(node.sa, 2),
                    count(node.frames), formatFixed(node.bitsPerS, 0), formatFixed(node.sharePct, 2)},
              "ll");
  }
  closeTable(out);
  out += "</section>";
}

void appendCycleSection(std::string& out, const ReportInput& input, int& figure) {
  out += "<section id=\"cycles\"><h2>Message cycles</h2>";
  const std::vector<MessageStats>& messages = input.stats.messages;
  if (messages.empty()) {
    noData(out, "No messages.");
    out += "</section>";
    return;
  }
  const bool severalBuses = input.stats.buses.size() > 1;
  // The bars: messages with a measured period, those with an expectation first, then the busiest.
  std::vector<std::size_t> chosen;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (messages[i].meanMs > 0) chosen.push_back(i);
  }
  const std::size_t measured = chosen.size();
  std::stable_sort(chosen.begin(), chosen.end(), [&](std::size_t a, std::size_t b) {
    return std::make_tuple(messages[a].expectedMs <= 0, -static_cast<double>(messages[a].count)) <
           std::make_tuple(messages[b].expectedMs <= 0, -static_cast<double>(messages[b].count));
  });
  if (chosen.size() > MAX_CYCLE_BARS) chosen.resize(MAX_CYCLE_BARS);
  std::sort(chosen.begin(), chosen.end());  // back to bus, identifier order
  const std::string limitNote =
      measured > chosen.size()
          ? " The " + count(chosen.size()) + " of " + count(measured) +
                " measured messages drawn are those with an expected cycle, then the most frequent; the table lists all."
          : std::string();

  if (chosen.empty()) {
    noData(out, "No message was seen twice: no periods measured.");
  } else {
    BarChartSpec expectedVsMeasured{.id = "cycle-compare", .valueLabel = "cycle [ms]", .width = CHART_WIDTH};
    BarSeries expected{"expected", {}};
    BarSeries mean{"measured (mean)", {}};
    for (std::size_t i : chosen) {
      expectedVsMeasured.categories.push_back(messageLabel(messages[i], severalBuses));
      expected.values.push_back(messages[i].expectedMs);
      mean.values.push_back(messages[i].meanMs);
    }
    expectedVsMeasured.series = {std::move(expected), std::move(mean)};
    appendFigure(out, figure, "cycle-compare", verticalBarsSvg(expectedVsMeasured),
                 "Expected vs measured cycle per message (thesis Fig. 7.2): the expected cycle from the "
                 "transmit schedule or the DBC's GenMsgCycleTime (none: no bar), and the mean measured "
                 "period between frames." + limitNote);
  }
  BarChartSpec difference{.id = "cycle-difference", .valueLabel = "measured - expected [ms]", .width = CHART_WIDTH,
                          .height = 280};
  BarSeries deviation{"", {}};
  for (std::size_t i : chosen) {
    if (messages[i].expectedMs <= 0) continue;
    difference.categories.push_back(messageLabel(messages[i], severalBuses));
    deviation.values.push_back(messages[i].deviationMs);
  }
  if (difference.categories.empty()) {
    noData(out, "No message with both an expected cycle and a measured period: no differences (Fig. 7.3).");
  } else {
    difference.series.push_back(std::move(deviation));
    appendFigure(out, figure, "cycle-difference", verticalBarsSvg(difference),
                 "Difference between measured and expected cycle per message (thesis Fig. 7.3): mean measured "
                 "period minus expected cycle; above zero the message comes late, below it early.");
  }
  out += "<h3>All messages</h3>";
  openTable(out, {"bus", "id", "name", "SA", "count", "expected [ms]", "from", "mean [ms]", "p50 [ms]",
                  "p99 [ms]", "max [ms]", "mean - expected [ms]", "gaps", "missing"},
            "lll");
  for (const MessageStats& m : messages) {
    const bool hasPeriod = m.meanMs > 0;
    const bool hasExpectation = m.expectedMs > 0;
    appendRow(out, {m.bus, messageId(m), m.name, m.extended ? hex(m.sa, 2) : "-", count(m.count),
                    hasExpectation ? formatFixed(m.expectedMs, 1) : "-", std::string(cycleSourceName(m.cycleSource)),
                    hasPeriod ? formatFixed(m.meanMs, 2) : "-", hasPeriod ? formatFixed(m.p50Ms, 1) : "-",
                    hasPeriod ? formatFixed(m.p99Ms, 1) : "-", hasPeriod ? formatFixed(m.maxMs, 1) : "-",
                    hasPeriod && hasExpectation ? formatFixed(m.deviationMs, 2) : "-", count(m.gaps), count(m.missing)},
              "lll", m.missing > 0 ? "sev-warning" : "");
  }
  closeTable(out);
  out += "<p class=\"hint\">Periods are binned at " + formatFixed(PERIOD_BIN_NS / 1e6, 1) +
         " ms (p50, p99); max and mean are exact. A gap is a period over 1.5 expected cycles.</p>";
  out += "</section>";
}

void appendSignalSection(std::string& out, const ReportInput& input, double t0, double t1, int& figure) {
  out += "<section id=\"signals\"><h2>Signals</h2>";
  if (input.signals.empty()) {
    noData(out, "No signals chosen.");
    out += "</section>";
    return;
  }
  // One chart per unit, in order of first appearance.
  std::vector<std::string> units;
  for (const SignalSeries& signal : input.signals) {
    if (std::find(units.begin(), units.end(), signal.unit) == units.end()) units.push_back(signal.unit);
  }
  for (std::size_t u = 0; u < units.size(); ++u) {
    const std::string id = "signals-" + std::to_string(u + 1);
    TimeChartSpec spec{.id = id,
                       .yLabel = units[u].empty() ? std::string("value") : "[" + units[u] + "]",
                       .t0 = t0,
                       .t1 = t1,
                       .width = CHART_WIDTH,
                       .height = 200};
    std::string names;
    std::size_t samples = 0;
    for (const SignalSeries& signal : input.signals) {
      if (signal.unit != units[u]) continue;
      spec.series.push_back({signal.name, signal.samples});
      names += (names.empty() ? "" : ", ") + signal.name;
      samples += signal.samples.size();
    }
    appendFigure(out, figure, id, timeSeriesSvg(spec),
                 names + " (" + (units[u].empty() ? std::string("no unit") : units[u]) + "), " + count(samples) +
                     " samples; series of more than " + count(MAX_SERIES_POINTS) +
                     " samples are drawn as the lowest and highest value per pixel column.");
  }
  out += "</section>";
}

void appendDtcSection(std::string& out, const ReportInput& input, double t0, double t1, int& figure) {
  out += "<section id=\"dtc\"><h2>Diagnostic trouble codes</h2>";
  if (input.dtcs.empty()) {
    noData(out, "No DTC was raised (DM1/DM2).");
    out += "</section>";
    return;
  }
  using Key = std::tuple<std::uint16_t, std::uint8_t, std::uint32_t, std::uint8_t, bool>;
  std::map<Key, std::size_t> laneOf;
  LanesChartSpec spec{.id = "dtc-timeline", .t0 = t0, .t1 = t1, .width = CHART_WIDTH};
  std::uint64_t notDrawn = 0;
  const bool severalBuses = std::any_of(input.dtcs.begin(), input.dtcs.end(),
                                        [&](const DtcInterval& dtc) { return dtc.bus != input.dtcs.front().bus; });
  for (const DtcInterval& dtc : input.dtcs) {
    const Key key{dtc.bus, dtc.source, dtc.spn, dtc.fmi, dtc.previouslyActive};
    auto found = laneOf.find(key);
    if (found == laneOf.end()) {
      if (spec.lanes.size() == MAX_DTC_LANES) {
        ++notDrawn;
        continue;
      }
      found = laneOf.emplace(key, spec.lanes.size()).first;
      spec.lanes.push_back({(severalBuses ? busName(input, dtc.bus) + " " : std::string()) + "SPN " +
                                std::to_string(dtc.spn) + " FMI " + std::to_string(dtc.fmi) + " (" +
                                hex(dtc.source, 2) + (dtc.previouslyActive ? ", DM2)" : ")"),
                            {},
                            {}});
    }
    LaneInterval interval;
    interval.startS = secondsFromStart(input, dtc.raisedNs);
    interval.openEnd = !dtc.clearedNs.has_value();
    interval.endS = dtc.clearedNs ? secondsFromStart(input, *dtc.clearedNs) : t1;
    interval.label = "OC " + std::to_string(dtc.occurrenceCount);
    interval.severity = dtc.previouslyActive ? Severity::Info : Severity::Warning;
    spec.lanes[found->second].intervals.push_back(std::move(interval));
  }
  std::string caption = "DTC timeline: each row one DTC (SPN, FMI) of one ECU (source address; the bus when several); a bar from "
                        "the DM1 that raised it to the DM1 that no longer lists it (fading out: still active at "
                        "the end). DM2 rows (previously active) are blue.";
  if (notDrawn) caption += " " + count(notDrawn) + " intervals of further DTCs are only in the table.";
  if (input.dtcIntervalsSkipped) caption += " " + count(input.dtcIntervalsSkipped) + " intervals beyond the limit of the analysis were not kept.";
  appendFigure(out, figure, "dtc-timeline", lanesSvg(spec), caption);
  openTable(out, {"bus", "SA", "SPN", "FMI", "OC", "list", "raised [s]", "cleared [s]"}, "l");
  std::size_t rows = 0;
  for (const DtcInterval& dtc : input.dtcs) {
    if (++rows > MAX_DTC_ROWS) break;
    appendRow(out, {busName(input, dtc.bus), hex(dtc.source, 2), std::to_string(dtc.spn), std::to_string(dtc.fmi),
                    std::to_string(dtc.occurrenceCount), dtc.previouslyActive ? "DM2" : "DM1",
                    formatFixed(secondsFromStart(input, dtc.raisedNs), 3),
                    dtc.clearedNs ? formatFixed(secondsFromStart(input, *dtc.clearedNs), 3) : "active at end"},
              "l");
  }
  closeTable(out);
  if (input.dtcs.size() > MAX_DTC_ROWS) {
    noData(out, "The table shows the first " + count(MAX_DTC_ROWS) + " of " + count(input.dtcs.size()) + " intervals.");
  }
  out += "</section>";
}

void appendEventSection(std::string& out, const ReportInput& input, double t0, double t1, int& figure) {
  out += "<section id=\"events\"><h2>Events</h2>";
  LanesChartSpec spec{.id = "event-lanes", .t0 = t0, .t1 = t1, .width = CHART_WIDTH};
  for (const EventLane& lane : input.eventLanes) {
    Lane drawn{lane.name, {}, {}};
    for (const ReportEvent& event : lane.events) drawn.events.push_back({event.s, event.label, event.severity});
    spec.lanes.push_back(std::move(drawn));
  }
  // The kept findings, one lane per check.
  for (Check check : {Check::Log, Check::Safety, Check::Transport, Check::Dtc, Check::Request}) {
    Lane lane{"findings: " + std::string(checkName(check)), {}, {}};
    for (const Finding& finding : input.findings.kept) {
      if (finding.check != check) continue;
      lane.events.push_back({secondsFromStart(input, finding.timeNs), finding.text, finding.severity});
    }
    if (!lane.events.empty()) spec.lanes.push_back(std::move(lane));
  }
  if (spec.lanes.empty()) {
    noData(out, "No events and no findings.");
  } else {
    appendFigure(out, figure, "event-lanes", lanesSvg(spec),
                 "Events on the time axis: FSM transitions and faults, and the findings of the protocol checks "
                 "(one row per check); blue info, orange warning, red fault. Labels that would overlap are "
                 "hidden until zoomed in; every marker shows its text on hover.");
  }
  out += "</section>";
}

void appendFindingSection(std::string& out, const ReportInput& input) {
  const FindingList& findings = input.findings;
  out += "<section id=\"findings\"><h2>Findings</h2>";
  if (findings.kept.empty()) {
    noData(out, findings.total ? "Findings were counted but none kept." : "No findings.");
    out += "</section>";
    return;
  }
  if (findings.total > findings.kept.size()) {
    out += "<p>The first " + count(findings.kept.size()) + " of " + count(findings.total) +
           " findings (the counts above are of all).</p>";
  }
  // the log's own time first (as its lines stamp it: grep finds the frame), then the
  // time axis' seconds from the first frame
  openTable(out, {"log time [s]", "from start [s]", "bus", "severity", "check", "finding"}, "rrllll");
  std::string logTime;
  for (const Finding& finding : findings.kept) {
    logTime.clear();
    appendSeconds(logTime, finding.timeNs);
    appendRow(out, {logTime, formatFixed(secondsFromStart(input, finding.timeNs), 6), busName(input, finding.bus),
                    std::string(severityName(finding.severity)), std::string(checkName(finding.check)), finding.text},
              "rrlllw", finding.severity == Severity::Fault     ? "sev-fault"
                       : finding.severity == Severity::Warning ? "sev-warning"
                                                               : "");
  }
  closeTable(out);
  out += "</section>";
}

}  // namespace

void ReportFindings::finding(const Finding& finding) {
  ++m_list.total;
  ++m_list.bySeverity[static_cast<std::size_t>(finding.severity) % m_list.bySeverity.size()];
  if (m_list.kept.size() < MAX_REPORT_FINDINGS) m_list.kept.push_back(finding);
}

std::string renderHtmlReport(const ReportInput& input) {
  std::string out;
  out.reserve(1 << 20);
  out += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
         "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src 'unsafe-inline'; "
         "script-src 'unsafe-inline'; img-src data:\">"
         "<meta name=\"viewport\" content=\"width=device-width\"><meta name=\"generator\" content=\"openvcu vcu trace report\"><title>";
  esc(out, input.title.empty() ? std::string("CAN trace report") : input.title);
  out += "</title><style>";
  out += reportStyle();
  out += "</style></head><body>";
  appendHeader(out, input);
  const auto [t0, t1] = timeAxis(input);
  int figure = 0;
  appendBusSection(out, input, t0, t1, figure);
  appendNodeSection(out, input, figure);
  appendCycleSection(out, input, figure);
  appendSignalSection(out, input, t0, t1, figure);
  appendDtcSection(out, input, t0, t1, figure);
  appendEventSection(out, input, t0, t1, figure);
  appendFindingSection(out, input);
  out += "<pre id=\"chart-layout\" hidden></pre><script>";
  out += reportScript();
  out += "</script></body></html>\n";
  return out;
}

}  // namespace openvcu::trace
