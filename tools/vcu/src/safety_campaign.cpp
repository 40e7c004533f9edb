// `vcu safety campaign`: judging and reporting what a campaign measured (no stack here).
#include "safety_campaign.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "openvcu/service/logger.hpp"

namespace openvcu::cli {
namespace {

std::string formatMs(double ms) {
  char text[32];
  std::snprintf(text, sizeof text, ms < 10 ? "%.1f" : "%.0f", ms);
  return text;
}

bool withinFtti(const ItemResult& item, std::int64_t fttiMs) {
  return item.reachedMs && *item.reachedMs <= static_cast<double>(fttiMs);
}

bool repetitionPassed(const Repetition& repetition, std::int64_t fttiMs) {
  if (!repetition.error.empty() || repetition.items.empty()) return false;
  return std::all_of(repetition.items.begin(), repetition.items.end(),
                     [fttiMs](const ItemResult& item) { return withinFtti(item, fttiMs); });
}

std::string escapeXml(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// The misses of a hazard, one line each ("#2: fsm Battery Timeout not seen within 8000 ms").
std::vector<std::string> missesOf(const HazardResult& hazard) {
  std::vector<std::string> misses;
  for (const Repetition& repetition : hazard.repetitions) {
    const std::string prefix = "#" + std::to_string(repetition.index) + ": ";
    if (!repetition.error.empty()) misses.push_back(prefix + repetition.error);
    for (const ItemResult& item : repetition.items) {
      if (!item.reachedMs) {
        misses.push_back(prefix + item.item + " not seen within " + formatMs(repetition.windowMs) + " ms");
      } else if (!withinFtti(item, hazard.fttiMs)) {
        misses.push_back(prefix + item.item + " after " + formatMs(*item.reachedMs) + " ms > FTTI " +
                         std::to_string(hazard.fttiMs) + " ms");
      }
    }
  }
  return misses;
}

void addUnique(std::vector<std::string>& list, const std::string& value) {
  if (std::find(list.begin(), list.end(), value) == list.end()) list.push_back(value);
}

}  // namespace

const char* itemKindName(ItemKind kind) noexcept {
  switch (kind) {
    case ItemKind::FsmState:
      return "fsm";
    case ItemKind::BusSignal:
      return "bus";
    case ItemKind::GpioLevel:
      return "gpio";
    case ItemKind::Fault:
      return "fault";
    case ItemKind::Restarted:
      return "restarted";
  }
  return "?";
}

const char* verdictName(Verdict verdict) noexcept {
  switch (verdict) {
    case Verdict::Pass:
      return "PASS";
    case Verdict::Fail:
      return "FAIL";
    case Verdict::NotRun:
      return "NOT RUN";
  }
  return "?";
}

std::vector<ItemStats> summarize(const HazardResult& hazard) {
  std::vector<ItemStats> stats;
  std::map<std::string, std::vector<double>> times;
  for (const Repetition& repetition : hazard.repetitions) {
    for (const ItemResult& item : repetition.items) {
      auto found = std::find_if(stats.begin(), stats.end(), [&](const ItemStats& s) { return s.item == item.item; });
      if (found == stats.end()) {
        stats.push_back(ItemStats{.kind = item.kind, .item = item.item});
        found = stats.end() - 1;
      }
      if (item.reachedMs) {
        ++found->seen;
        times[item.item].push_back(*item.reachedMs);
      }
      if (!withinFtti(item, hazard.fttiMs)) ++found->missed;
    }
  }
  for (ItemStats& s : stats) {
    std::vector<double>& sorted = times[s.item];
    if (sorted.empty()) continue;
    std::sort(sorted.begin(), sorted.end());
    const std::size_t n = sorted.size();
    s.minMs = sorted.front();
    s.maxMs = sorted.back();
    s.medianMs = n % 2 == 1 ? sorted[n / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
    const auto rank = static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(n)));
    s.p99Ms = sorted[std::max<std::size_t>(rank, 1) - 1];
  }
  return stats;
}

Verdict verdictOf(const HazardResult& hazard) {
  if (!hazard.notRunReasons.empty()) return Verdict::NotRun;
  if (hazard.repetitions.empty()) return Verdict::Fail;
  for (const Repetition& repetition : hazard.repetitions) {
    if (!repetitionPassed(repetition, hazard.fttiMs)) return Verdict::Fail;
  }
  return Verdict::Pass;
}

Coverage coverageOf(const CampaignResult& result) {
  Coverage coverage;
  for (const HazardResult& hazard : result.hazards) {
    for (const Repetition& repetition : hazard.repetitions) {
      for (const ItemResult& item : repetition.items) {
        if (!item.reachedMs) continue;
        if (item.kind == ItemKind::FsmState) addUnique(coverage.fsmStatesReached, item.reached);
        if (item.kind == ItemKind::Fault && !item.detection.empty()) {
          addUnique(coverage.detectionsExercised, item.detection);
        }
      }
    }
  }
  for (const std::string& state : result.safeFsmStates) {
    if (std::find(coverage.fsmStatesReached.begin(), coverage.fsmStatesReached.end(), state) ==
        coverage.fsmStatesReached.end()) {
      addUnique(coverage.fsmStatesMissed, state);
    }
  }
  for (const std::string& kind : result.detectionKinds) {
    if (std::find(coverage.detectionsExercised.begin(), coverage.detectionsExercised.end(), kind) ==
        coverage.detectionsExercised.end()) {
      addUnique(coverage.detectionsMissed, kind);
    }
  }
  return coverage;
}

bool campaignPassed(const CampaignResult& result, bool strict) {
  return std::none_of(result.hazards.begin(), result.hazards.end(), [strict](const HazardResult& hazard) {
    const Verdict verdict = verdictOf(hazard);
    return verdict == Verdict::Fail || (strict && verdict == Verdict::NotRun);
  });
}

std::string formatRepetition(const HazardResult& hazard, const Repetition& repetition) {
  std::string line = hazard.id + " #" + std::to_string(repetition.index) + " " +
                     (repetitionPassed(repetition, hazard.fttiMs) ? "PASS" : "FAIL");
  if (!repetition.error.empty()) return line + ": " + repetition.error + "\n";
  std::string separator = " ";
  for (const ItemResult& item : repetition.items) {
    line +=
        separator + item.item + " " + (item.reachedMs ? formatMs(*item.reachedMs) + " ms" : std::string("not seen"));
    if (item.reachedMs && !withinFtti(item, hazard.fttiMs)) line += " (late)";
    if (item.note.starts_with("already")) line += " (already safe)";
    separator = ", ";
  }
  return line + " (FTTI " + std::to_string(hazard.fttiMs) + " ms)\n";
}

std::string formatSummary(const CampaignResult& result) {
  std::string out;
  std::size_t passed = 0;
  std::size_t failed = 0;
  std::size_t notRun = 0;
  for (const HazardResult& hazard : result.hazards) {
    const Verdict verdict = verdictOf(hazard);
    passed += verdict == Verdict::Pass ? 1 : 0;
    failed += verdict == Verdict::Fail ? 1 : 0;
    notRun += verdict == Verdict::NotRun ? 1 : 0;
    out += hazard.id + ": " + verdictName(verdict) + " (FTTI " + std::to_string(hazard.fttiMs) + " ms, " +
           std::to_string(hazard.repetitions.size()) + " repetitions)\n";
    for (const std::string& reason : hazard.notRunReasons) out += "  not run: " + reason + "\n";
    for (const ItemStats& s : summarize(hazard)) {
      out += "  " + s.item + ": ";
      out += s.seen == 0 ? std::string("never seen")
                         : "min " + formatMs(s.minMs) + " / median " + formatMs(s.medianMs) + " / p99 " +
                               formatMs(s.p99Ms) + " / max " + formatMs(s.maxMs) + " ms";
      out += ", " + std::to_string(s.missed) + " missed\n";
    }
    for (const std::string& miss : missesOf(hazard)) out += "  miss " + miss + "\n";
    for (const std::string& detection : hazard.unobserved) out += "  not observed: " + detection + "\n";
    for (const std::string& fault : hazard.notInjected) out += "  not injected: " + fault + "\n";
  }
  const Coverage coverage = coverageOf(result);
  auto list = [](const std::vector<std::string>& items) {
    std::string text;
    for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
    return text.empty() ? std::string("-") : text;
  };
  out += "coverage: FSM safe states reached: " + list(coverage.fsmStatesReached) +
         "; not reached: " + list(coverage.fsmStatesMissed) + "\n";
  out += "coverage: detections exercised: " + list(coverage.detectionsExercised) +
         "; not exercised: " + list(coverage.detectionsMissed) + "\n";
  out += std::string(campaignPassed(result, false) ? "campaign passed" : "campaign FAILED") + ": " +
         std::to_string(passed) + " passed, " + std::to_string(failed) + " failed, " + std::to_string(notRun) +
         " not run\n";
  return out;
}

nlohmann::ordered_json toJson(const CampaignResult& result) {
  nlohmann::ordered_json out;
  out["vehicle"] = result.vehicle;
  out["safety"] = result.safetyFile;
  out["host"] = result.host;
  out["started"] = service::formatUtc(result.startedRealtimeNs);
  out["passed"] = campaignPassed(result, false);
  nlohmann::ordered_json hazards = nlohmann::ordered_json::array();
  for (const HazardResult& hazard : result.hazards) {
    nlohmann::ordered_json h;
    h["id"] = hazard.id;
    h["description"] = hazard.description;
    h["severity"] = hazard.severity;
    h["fttiMs"] = hazard.fttiMs;
    h["during"] = hazard.during;
    h["verdict"] = verdictName(verdictOf(hazard));
    h["notRun"] = hazard.notRunReasons;
    h["notObserved"] = hazard.unobserved;
    h["notInjected"] = hazard.notInjected;
    nlohmann::ordered_json items = nlohmann::ordered_json::array();
    for (const ItemStats& s : summarize(hazard)) {
      nlohmann::ordered_json item{
          {"kind", itemKindName(s.kind)}, {"item", s.item}, {"seen", s.seen}, {"missed", s.missed}};
      if (s.seen > 0) {
        item["minMs"] = s.minMs;
        item["medianMs"] = s.medianMs;
        item["p99Ms"] = s.p99Ms;
        item["maxMs"] = s.maxMs;
      }
      items.push_back(std::move(item));
    }
    h["items"] = std::move(items);
    nlohmann::ordered_json repetitions = nlohmann::ordered_json::array();
    for (const Repetition& repetition : hazard.repetitions) {
      nlohmann::ordered_json r{{"index", repetition.index},
                               {"injectedMonotonicNs", repetition.injectedMonotonicNs},
                               {"injectedRealtimeNs", repetition.injectedRealtimeNs},
                               {"windowMs", repetition.windowMs},
                               {"injected", repetition.injected},
                               {"passed", repetitionPassed(repetition, hazard.fttiMs)}};
      if (!repetition.error.empty()) r["error"] = repetition.error;
      nlohmann::ordered_json seen = nlohmann::ordered_json::array();
      for (const ItemResult& item : repetition.items) {
        nlohmann::ordered_json i{{"kind", itemKindName(item.kind)}, {"item", item.item}};
        if (!item.detection.empty()) i["detection"] = item.detection;
        i["reachedMs"] = item.reachedMs ? nlohmann::ordered_json(*item.reachedMs) : nlohmann::ordered_json(nullptr);
        if (!item.note.empty()) i["note"] = item.note;
        seen.push_back(std::move(i));
      }
      r["items"] = std::move(seen);
      nlohmann::ordered_json timeline = nlohmann::ordered_json::array();
      for (const TimelineEntry& entry : repetition.timeline)
        timeline.push_back({{"ms", entry.ms}, {"text", entry.text}});
      r["timeline"] = std::move(timeline);
      repetitions.push_back(std::move(r));
    }
    h["repetitions"] = std::move(repetitions);
    hazards.push_back(std::move(h));
  }
  out["hazards"] = std::move(hazards);
  const Coverage coverage = coverageOf(result);
  out["coverage"] = {{"fsmStatesReached", coverage.fsmStatesReached},
                     {"fsmStatesNotReached", coverage.fsmStatesMissed},
                     {"detectionsExercised", coverage.detectionsExercised},
                     {"detectionsNotExercised", coverage.detectionsMissed}};
  return out;
}

std::string toJunit(const CampaignResult& result) {
  std::size_t failures = 0;
  std::size_t skipped = 0;
  for (const HazardResult& hazard : result.hazards) {
    failures += verdictOf(hazard) == Verdict::Fail ? 1 : 0;
    skipped += verdictOf(hazard) == Verdict::NotRun ? 1 : 0;
  }
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<testsuite name=\"vcu safety campaign\" tests=\"" + std::to_string(result.hazards.size()) + "\" failures=\"" +
         std::to_string(failures) + "\" skipped=\"" + std::to_string(skipped) + "\" timestamp=\"" +
         escapeXml(service::formatUtc(result.startedRealtimeNs)) + "\" hostname=\"" + escapeXml(result.host) + "\">\n";
  for (const HazardResult& hazard : result.hazards) {
    double seconds = 0;
    for (const Repetition& repetition : hazard.repetitions) seconds += repetition.windowMs / 1000;
    out += "  <testcase classname=\"safety." + escapeXml(result.vehicle) + "\" name=\"" + escapeXml(hazard.id) +
           "\" time=\"" + formatMs(seconds) + "\">\n";
    const Verdict verdict = verdictOf(hazard);
    if (verdict == Verdict::NotRun) {
      std::string reasons;
      for (const std::string& reason : hazard.notRunReasons) reasons += (reasons.empty() ? "" : "; ") + reason;
      out += "    <skipped message=\"" + escapeXml(reasons) + "\"/>\n";
    } else if (verdict == Verdict::Fail) {
      std::string text;
      for (const std::string& miss : missesOf(hazard)) text += miss + "\n";
      out += "    <failure message=\"FTTI " + std::to_string(hazard.fttiMs) + " ms missed\">" + escapeXml(text) +
             "</failure>\n";
    }
    std::string lines;
    for (const Repetition& repetition : hazard.repetitions) lines += formatRepetition(hazard, repetition);
    out += "    <system-out>" + escapeXml(lines) + "</system-out>\n";
    out += "  </testcase>\n";
  }
  out += "</testsuite>\n";
  return out;
}

std::string toHtml(const CampaignResult& result) {
  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>openvcu safety campaign</title>\n"
      "<style>body{font-family:sans-serif;margin:1.5em;color:#222}table{border-collapse:collapse;margin:.5em 0}"
      "td,th{border:1px solid #bbb;padding:3px "
      "8px;text-align:left}th{background:#eee}.PASS{color:#070;font-weight:bold}"
      ".FAIL{color:#b00;font-weight:bold}.NOT{color:#777;font-weight:bold}svg{background:#fafafa;border:1px solid #ddd}"
      "</style></head><body>\n";
  out += "<h1>Safety campaign: " + escapeXml(result.vehicle) + "</h1>\n";
  out += "<p>Safety case " + escapeXml(result.safetyFile) + ", host " + escapeXml(result.host) + ", started " +
         escapeXml(service::formatUtc(result.startedRealtimeNs)) + ". Times are ms from the injection.</p>\n";
  out += "<p id=\"verdict\" class=\"" + std::string(campaignPassed(result, false) ? "PASS" : "FAIL") + "\">" +
         (campaignPassed(result, false) ? "campaign passed" : "campaign FAILED") + "</p>\n";
  out += "<table><tr><th>hazard</th><th>severity</th><th>FTTI ms</th><th>verdict</th><th>repetitions</th></tr>\n";
  for (const HazardResult& hazard : result.hazards) {
    const std::string verdict = verdictName(verdictOf(hazard));
    out += "<tr><td><a href=\"#" + escapeXml(hazard.id) + "\">" + escapeXml(hazard.id) + "</a></td><td>" +
           escapeXml(hazard.severity) + "</td><td>" + std::to_string(hazard.fttiMs) + "</td><td class=\"" +
           verdict.substr(0, 4) + "\">" + verdict + "</td><td>" + std::to_string(hazard.repetitions.size()) +
           "</td></tr>\n";
  }
  out += "</table>\n";
  const Coverage coverage = coverageOf(result);
  auto list = [](const std::vector<std::string>& items) {
    std::string text;
    for (const std::string& item : items) text += (text.empty() ? "" : ", ") + escapeXml(item);
    return text.empty() ? std::string("-") : text;
  };
  out += "<h2>Coverage</h2><p>FSM safe states reached: " + list(coverage.fsmStatesReached) +
         "<br>not reached: " + list(coverage.fsmStatesMissed) +
         "<br>Detections exercised: " + list(coverage.detectionsExercised) +
         "<br>not exercised: " + list(coverage.detectionsMissed) + "</p>\n";
  for (const HazardResult& hazard : result.hazards) {
    const std::string verdict = verdictName(verdictOf(hazard));
    out += "<h2 id=\"" + escapeXml(hazard.id) + "\">" + escapeXml(hazard.id) + " <span class=\"" +
           verdict.substr(0, 4) + "\">" + verdict + "</span></h2>\n<p>" + escapeXml(hazard.description) + " (FTTI " +
           std::to_string(hazard.fttiMs) + " ms" +
           (hazard.during.empty() ? std::string() : ", injected in " + list(hazard.during)) + ")</p>\n";
    for (const std::string& reason : hazard.notRunReasons) out += "<p>Not run: " + escapeXml(reason) + "</p>\n";
    for (const std::string& detection : hazard.unobserved) out += "<p>Not observed: " + escapeXml(detection) + "</p>\n";
    for (const std::string& fault : hazard.notInjected) out += "<p>Not injected: " + escapeXml(fault) + "</p>\n";
    const std::vector<ItemStats> stats = summarize(hazard);
    if (!stats.empty()) {
      out +=
          "<table><tr><th>item</th><th>seen</th><th>missed</th><th>min</th><th>median</th><th>p99</th>"
          "<th>max</th></tr>\n";
      for (const ItemStats& s : stats) {
        out += "<tr><td>" + escapeXml(s.item) + "</td><td>" + std::to_string(s.seen) + "</td><td>" +
               std::to_string(s.missed) + "</td>";
        for (const double ms : {s.minMs, s.medianMs, s.p99Ms, s.maxMs}) {
          out += "<td>" + (s.seen > 0 ? formatMs(ms) : std::string("-")) + "</td>";
        }
        out += "</tr>\n";
      }
      out += "</table>\n";
    }
    for (const Repetition& repetition : hazard.repetitions) {
      out += "<h3>" + escapeXml(hazard.id) + " #" + std::to_string(repetition.index) +
             "</h3>\n<p>Injected: " + list(repetition.injected) +
             (repetition.error.empty() ? "" : "<br>Error: " + escapeXml(repetition.error)) + "</p>\n";
      // the timeline: 0 .. window ms across 800 px, the FTTI as a red line, one row per entry
      const double span = std::max({repetition.windowMs, static_cast<double>(hazard.fttiMs) * 1.05, 1.0});
      const std::size_t rows = repetition.timeline.size();
      const int height = 30 + static_cast<int>(rows) * 18;
      constexpr double LEFT = 10;
      constexpr double WIDTH = 800;
      auto x = [&](double ms) { return LEFT + std::clamp(ms, 0.0, span) / span * WIDTH; };
      out += "<svg width=\"1300\" height=\"" + std::to_string(height) + "\">";
      out += "<line x1=\"" + formatMs(x(0)) + "\" y1=\"0\" x2=\"" + formatMs(x(0)) + "\" y2=\"" +
             std::to_string(height) + "\" stroke=\"#333\"/>";
      const double ftti = x(static_cast<double>(hazard.fttiMs));
      out += "<line x1=\"" + formatMs(ftti) + "\" y1=\"0\" x2=\"" + formatMs(ftti) + "\" y2=\"" +
             std::to_string(height) + "\" stroke=\"#c00\" stroke-dasharray=\"4 3\"/>";
      out += "<text x=\"" + formatMs(ftti + 3) + "\" y=\"12\" font-size=\"11\" fill=\"#c00\">FTTI " +
             std::to_string(hazard.fttiMs) + " ms</text>";
      for (std::size_t i = 0; i < rows; ++i) {
        const TimelineEntry& entry = repetition.timeline[i];
        const double y = 28 + static_cast<double>(i) * 18;
        out += "<circle cx=\"" + formatMs(x(entry.ms)) + "\" cy=\"" + formatMs(y - 4) + "\" r=\"4\" fill=\"" +
               (entry.ms <= static_cast<double>(hazard.fttiMs) ? "#070" : "#b00") + "\"/>";
        out += "<text x=\"" + formatMs(WIDTH + 30) + "\" y=\"" + formatMs(y) + "\" font-size=\"11\">" +
               formatMs(entry.ms) + " ms " + escapeXml(entry.text) + "</text>";
      }
      out += "</svg>\n";
    }
  }
  out += "</body></html>\n";
  return out;
}

}  // namespace openvcu::cli
