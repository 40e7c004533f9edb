#pragma once
// What vcu-web's live pages show (docs/design/web.md, "The update event"), built on the io
// thread from the signal table and the events: the header (FSM state and since when, SOC,
// services' health), the active faults (fault events and DM1 summaries), the operator switches
// and, per page, the values of the signals it picked. The display rules are the HMI's
// (openvcu::display): which plane a person sees, staleness, value texts, which switch the
// current state reads.
//
//   web::LiveState live(runtime.config(), runtime.catalog(), runtime.table(), setup);
//   live.onHeartbeat(beat, nowMono);                 // events posted to the io thread
//   auto source = live.openStream({"VIC.HVESSD2_PGN61585.HS_FastUpdSOC"});   // for GET /api/live
//   std::string event = (*source)->next();           // "event: update\ndata: {...}\n\n" or "" (nothing new)

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "http_server.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/display/fsm_rules.hpp"
#include "openvcu/display/health.hpp"
#include "openvcu/display/values.hpp"
#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::web {

/// Signals one page may follow, and how many of them it plots.
inline constexpr std::size_t MAX_LIVE_SIGNALS = 32;
inline constexpr std::size_t MAX_PLOTTED_SIGNALS = 4;
/// A page gets an update at least this often even when nothing changed (its clock and plot move on).
inline constexpr std::chrono::milliseconds LIVE_IDLE_UPDATE{1000};

struct LiveSetup {
  std::string socKey;   ///< dashboard.json's header SOC; empty: none
  std::string fsmFile;  ///< the FSM file (state names, which switch a state reads); empty: none
  std::int64_t busStaleAfterNs{2'000'000'000};
};

/// @note restricted thread-safe: the io thread only (the table is read lock-free).
class LiveState {
 public:
  LiveState(const signals::Catalog& catalog, const signals::SignalTable& table, LiveSetup setup);

  void onHeartbeat(const ipc::Heartbeat& beat, std::int64_t receivedMonoNs);
  void onFault(const ipc::FaultEvent& fault);
  void onTransition(const ipc::FsmTransition& transition);

  /// The shared part of every update (header, faults, operator), recomputed at most every
  /// few milliseconds however many pages ask; `version` changes only when its text changes.
  const std::string& common(std::int64_t nowMonoNs, std::uint64_t& version);
  /// {"key","value","text","status","ageMs"} of one signal appended to `out` (a JSON array body);
  /// `signature` gets what identifies a change (value, status).
  void appendSignal(std::string& out, std::string& signature, signals::SignalIndex index, std::int64_t nowMonoNs) const;

  /// An event source for a page following `keys` (comma-separated in the request):
  /// an error naming unknown keys, or more than MAX_LIVE_SIGNALS.
  Result<std::unique_ptr<EventSource>> openStream(const std::string& keys);

  /// GET /api/catalog, built once.
  [[nodiscard]] const std::string& catalogJson() const noexcept { return m_catalogJson; }
  /// The FSM file's problem, when it did not load (the header then shows state numbers).
  [[nodiscard]] const std::string& rulesError() const noexcept { return m_rulesError; }
  [[nodiscard]] const signals::Catalog& catalog() const noexcept { return m_catalog; }
  /// The operator switch keys (internal.operator.* but FaultReset) with their value texts.
  [[nodiscard]] bool isOperatorKey(const std::string& key) const;

 private:
  struct OperatorRow {
    std::string key;
    std::string label;
    signals::SignalIndex index{};
    double onValue{1};
  };
  struct FaultKey {
    std::string name;
    std::string source;
    auto operator<=>(const FaultKey&) const = default;
  };
  void rebuild(std::int64_t nowMonoNs);
  std::string buildCatalogJson() const;

  const signals::Catalog& m_catalog;
  const signals::SignalTable& m_table;
  LiveSetup m_setup;
  std::optional<display::FsmRules> m_rules;
  std::string m_rulesError;
  display::HealthTracker m_health;
  display::HeartbeatSlots m_slots;  ///< the table's heartbeat slots: who beat, also before vcu-web started
  std::map<FaultKey, ipc::FaultEvent> m_faults;
  std::vector<OperatorRow> m_operator;
  std::vector<std::pair<std::string, signals::SignalIndex>> m_dm1;  ///< node, internal.dm1.<node>.activeDtcs
  std::optional<signals::SignalIndex> m_stateIndex;
  std::optional<signals::SignalIndex> m_socIndex;
  double m_lastState{-1};
  std::int64_t m_stateSinceUnixMs{0};
  std::int64_t m_builtAtNs{-1};
  std::string m_common;
  std::uint64_t m_version{0};
  std::string m_catalogJson;
};

}  // namespace openvcu::web
