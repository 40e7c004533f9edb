#pragma once
// `vcu safety campaign`: what a campaign measured and how it is judged and reported. The
// live part (bringing the vehicle to a state, injecting, observing) is
// safety_campaign_run.cpp; everything here is plain data and pure functions, unit-tested
// without a stack.
//
//   HazardResult hazard{.id = "H-BAT-TIMEOUT", .fttiMs = 4000, ...};
//   hazard.repetitions.push_back(repetition);        // one per injection
//   summarize(hazard) -> per observed item: count, min / median / p99 / max in ms, misses
//   verdictOf(hazard) -> Pass only if every item of every repetition was seen within the FTTI
//   formatText / toJson / toJunit / toHtml (self-contained: no external fetch)
//
// Times are ms since the injection's CLOCK_MONOTONIC stamp (fault events: since its
// CLOCK_REALTIME stamp, the clock LCM events carry).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace openvcu::cli {

/// What kind of safe-state item or detection an observation is.
enum class ItemKind : std::uint8_t {
  FsmState,   ///< the FSM entered one of the safe states (signal table internal.fsm.state)
  BusSignal,  ///< a frame on the simulated bus carries the safe command (decoded with the DBC)
  GpioLevel,  ///< internal.gpio.<line> at the safe level (vcu-gpio's reported level)
  Fault,      ///< an active LCM fault event of the detection mechanism
  Restarted,  ///< the service beats again from a new process
};

/// "fsm", "bus", "gpio", "fault", "restarted".
[[nodiscard]] const char* itemKindName(ItemKind kind) noexcept;

/// One thing a repetition waits for, and when it was seen.
struct ItemResult {
  ItemKind kind{ItemKind::FsmState};
  std::string item;                 ///< "fsm Battery Timeout", "bus PDU_Rx_1.Close_GroupA_Contactors=0"
  std::string detection;            ///< Fault items: the detection kind ("receiveTimeout"); else empty
  std::optional<double> reachedMs;  ///< since the injection; empty: not seen within the window
  std::string reached;              ///< FsmState: the state entered; else empty
  std::string note;                 ///< "already at the safe level before the injection", ...
};

/// One entry of a repetition's timeline (the HTML report draws them).
struct TimelineEntry {
  double ms{};  ///< since the injection; negative: before it
  std::string text;
};

/// One injection of one of a hazard's faults and what followed.
struct Repetition {
  int index{};  ///< 1-based
  std::int64_t injectedMonotonicNs{};
  std::int64_t injectedRealtimeNs{};
  double windowMs{};                  ///< how long it watched (2 x FTTI, or until all items were seen)
  std::vector<std::string> injected;  ///< "silent.VIC", "SIGSTOP vcu-fsm (pid 812)"
  std::vector<ItemResult> items;
  std::vector<TimelineEntry> timeline;
  std::string error;  ///< set: the repetition could not run (precondition, injection)
};

enum class Verdict : std::uint8_t {
  Pass,    ///< every item of every repetition within the FTTI
  Fail,    ///< an item missed the FTTI (or was never seen), or a repetition could not run
  NotRun,  ///< the campaign cannot inject or observe this hazard today (reasons listed)
};

[[nodiscard]] const char* verdictName(Verdict verdict) noexcept;

struct HazardResult {
  std::string id;
  std::string description;
  std::string severity;
  std::int64_t fttiMs{};
  std::vector<std::string> during;
  std::vector<std::string> notRunReasons;  ///< set: NotRun, each reason one line
  std::vector<std::string> unobserved;     ///< detections the campaign cannot observe (listed, not judged)
  std::vector<std::string> notInjected;    ///< faults of the list the campaign cannot inject (listed, not judged)
  std::vector<Repetition> repetitions;
};

/// The figures of one observed item over the repetitions (reached times only).
struct ItemStats {
  ItemKind kind{ItemKind::FsmState};
  std::string item;
  std::size_t seen{};    ///< repetitions that saw it
  std::size_t missed{};  ///< repetitions that did not see it, or saw it after the FTTI
  double minMs{}, medianMs{}, p99Ms{}, maxMs{};
};

/// Per item in first-seen order. p99 is the nearest rank (ceil(0.99 n)) of the sorted times.
[[nodiscard]] std::vector<ItemStats> summarize(const HazardResult& hazard);
[[nodiscard]] Verdict verdictOf(const HazardResult& hazard);

/// What the campaign exercised: FSM states of the safe states entered, detection kinds seen.
struct Coverage {
  std::vector<std::string> fsmStatesReached, fsmStatesMissed;
  std::vector<std::string> detectionsExercised, detectionsMissed;
};

struct CampaignResult {
  std::string vehicle;  ///< vehicle.json as given
  std::string safetyFile;
  std::string host;
  std::int64_t startedRealtimeNs{};
  std::vector<HazardResult> hazards;
  /// Every FSM state the selected hazards' safe states name, and every detection kind of the
  /// safety case's vocabulary: coverage is judged against these.
  std::vector<std::string> safeFsmStates;
  std::vector<std::string> detectionKinds;
};

[[nodiscard]] Coverage coverageOf(const CampaignResult& result);
/// true when no hazard failed (NotRun hazards do not fail the campaign unless `strict`).
[[nodiscard]] bool campaignPassed(const CampaignResult& result, bool strict);

/// One line per repetition ("H-BAT-TIMEOUT #1 PASS fsm Battery Timeout 3012 ms, ..."), one
/// summary line per hazard with min/median/p99/max per item, the coverage, a last line.
[[nodiscard]] std::string formatRepetition(const HazardResult& hazard, const Repetition& repetition);
[[nodiscard]] std::string formatSummary(const CampaignResult& result);
[[nodiscard]] nlohmann::ordered_json toJson(const CampaignResult& result);
/// One <testcase> per hazard: <failure> naming the misses, <skipped> for NotRun.
[[nodiscard]] std::string toJunit(const CampaignResult& result);
/// One HTML page with inline CSS and an inline SVG timeline per repetition; no script, no link.
[[nodiscard]] std::string toHtml(const CampaignResult& result);

}  // namespace openvcu::cli
