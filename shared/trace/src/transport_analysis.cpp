// TransportAnalysis: one j1939::TpMonitor per bus, session ends -> findings, DM1/DM2 ->
// DTC raised / cleared findings and intervals (issue 21).
#include "openvcu/trace/transport_analysis.hpp"

#include <cstdio>
#include <limits>
#include <string>
#include <unordered_map>

#include "openvcu/dbc/matcher.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/transport_monitor.hpp"

namespace openvcu::trace {
namespace {

/// The priority of the synthetic identifier a reassembled message is matched with
/// (J1939-21's default for most PGNs; the matcher ignores it in J1939 mode).
constexpr std::uint8_t REASSEMBLED_PRIORITY = 6;
constexpr std::int64_t NO_DEADLINE = std::numeric_limits<std::int64_t>::max();
constexpr std::size_t MIN_DM1_LENGTH = j1939::DM1_MIN_LENGTH;

std::string hexByte(std::uint8_t value) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", static_cast<unsigned>(value));
  return text;
}

std::string pgnText(std::uint32_t pgn) {
  char text[32];
  std::snprintf(text, sizeof text, "PGN %u (0x%04X)", static_cast<unsigned>(pgn), static_cast<unsigned>(pgn));
  return text;
}

std::string millisecondsText(std::int64_t nanoseconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f ms", static_cast<double>(nanoseconds) / 1e6);
  return text;
}

/// "amber on, red stop on", or "all off".
std::string lampsText(const j1939::LampStates& lamps) {
  std::string text;
  const auto add = [&text](j1939::LampStatus status, const char* name) {
    if (status != j1939::LampStatus::On) return;
    if (!text.empty()) text += ", ";
    text += name;
    text += " on";
  };
  add(lamps.malfunction, "malfunction");
  add(lamps.redStop, "red stop");
  add(lamps.amberWarning, "amber");
  add(lamps.protect, "protect");
  return text.empty() ? "all off" : text;
}

std::string timerText(j1939::TpTimer timer) {
  switch (timer) {
    case j1939::TpTimer::T1: return "T1, 750 ms between packets";
    case j1939::TpTimer::T2: return "T2, 1250 ms from CTS to the first packet";
    case j1939::TpTimer::T3: return "T3, 1250 ms to the CTS or EndOfMsgAck";
    case j1939::TpTimer::T4: return "T4, 1050 ms after a CTS(0) hold";
    case j1939::TpTimer::None: break;
  }
  return "no timer";
}

/// A DTC active now, with the interval it opened (or NO_INTERVAL when the list was full).
struct ActiveDtc {
  std::uint32_t spn{};
  std::uint8_t fmi{};
  std::size_t interval{};
};
constexpr std::size_t NO_INTERVAL = std::numeric_limits<std::size_t>::max();

/// What one ECU's DM1 (or DM2) said last.
struct DtcSource {
  bool seen{};
  j1939::LampStates lamps;
  std::vector<ActiveDtc> active;
};

}  // namespace

struct TransportAnalysis::Impl final : j1939::TpMonitorSink {
  struct BusState {
    std::unique_ptr<j1939::TpMonitor> monitor;
    std::int64_t deadlineNs{NO_DEADLINE};  ///< the monitor's next deadline, cached
  };

  const AnalysisSetup* setup;
  dbc::MessageMatcher matcher;
  OnMessage onMessage;
  TransportCounts counts;
  std::vector<DtcInterval> intervals;
  std::vector<BusState> buses;
  std::unordered_map<std::uint32_t, DtcSource> dtcSources;  ///< bus << 9 | dm2 << 8 | source
  // The frame being handled, for the monitor's callbacks.
  std::uint16_t currentBus{};
  FindingSink* currentSink{};

  Impl(const AnalysisSetup& analysisSetup, OnMessage handler)
      : setup(&analysisSetup), matcher(analysisSetup.database, analysisSetup.match), onMessage(std::move(handler)) {}

  std::int32_t matchPgn(std::uint32_t pgn, std::uint8_t source, std::uint8_t destination) const noexcept {
    const std::uint32_t id = j1939::Id::fromPgn(pgn, REASSEMBLED_PRIORITY, source, destination).toCanId();
    return matcher.match(id, true);
  }

  /// "DM1", the DBC message's name, or "" when neither is known.
  std::string messageName(std::uint32_t pgn, std::int32_t message) const {
    if (message >= 0 && static_cast<std::size_t>(message) < setup->database.messages.size()) {
      return setup->database.messages[static_cast<std::size_t>(message)].displayName;
    }
    if (pgn == j1939::PGN_DM1) return "DM1";
    if (pgn == j1939::PGN_DM2) return "DM2";
    return {};
  }

  /// "BAM 0x21 -> all PGN 65226 (0xFECA) DM1 20 bytes"
  std::string sessionText(const j1939::TpSessionInfo& session) const {
    std::string text = session.broadcast ? "BAM " : "RTS/CTS ";
    text += hexByte(session.source);
    text += " -> ";
    text += session.broadcast ? std::string("all") : hexByte(session.destination);
    text += ' ';
    text += pgnText(session.pgn);
    const std::string name = messageName(session.pgn, matchPgn(session.pgn, session.source, session.destination));
    if (!name.empty()) {
      text += ' ';
      text += name;
    }
    text += ' ';
    text += std::to_string(session.size);
    text += " bytes";
    return text;
  }

  BusState& busState(std::uint16_t bus) {
    if (bus >= buses.size()) buses.resize(static_cast<std::size_t>(bus) + 1);
    BusState& state = buses[bus];
    if (!state.monitor) state.monitor = std::make_unique<j1939::TpMonitor>();
    return state;
  }

  void refreshDeadline(BusState& state) noexcept {
    state.deadlineNs = state.monitor->nextDeadlineNs().value_or(NO_DEADLINE);
  }

  /// Timeouts due by `nowNs` on every bus (a bus without frames still times out).
  void pollAll(std::int64_t nowNs, FindingSink& sink) {
    for (std::size_t bus = 0; bus < buses.size(); ++bus) {
      BusState& state = buses[bus];
      if (!state.monitor || state.deadlineNs > nowNs) continue;
      currentBus = static_cast<std::uint16_t>(bus);
      currentSink = &sink;
      state.monitor->poll(nowNs, *this);
      refreshDeadline(state);
    }
  }

  void report(std::int64_t timeNs, Severity severity, Check check, std::string text) {
    currentSink->finding(Finding{timeNs, currentBus, severity, check, std::move(text)});
  }

  // ---- TpMonitorSink

  void completed(const j1939::TpMonitoredMessage& message) noexcept override {
    const j1939::TpSessionInfo& session = message.session;
    const std::int32_t index = matchPgn(session.pgn, session.source, session.destination);
    if (session.pgn == j1939::PGN_DM1 || session.pgn == j1939::PGN_DM2) {
      handleDm(session.pgn, session.source, session.endNs, message.data);
    }
    if (onMessage) {
      onMessage(ReassembledMessage{currentBus, session.pgn, session.source, session.destination, session.broadcast,
                                   session.endNs, index, message.data});
    }
  }

  void ended(const j1939::TpSessionEnd& end) noexcept override {
    const j1939::TpSessionInfo& session = end.session;
    std::string text = sessionText(session);
    const std::string progress =
        std::to_string(session.packetsReceived) + " of " + std::to_string(session.packets) + " packets";
    Severity severity = Severity::Fault;
    switch (end.outcome) {
      case j1939::TpOutcome::Completed:
        ++counts.completed;
        severity = Severity::Info;
        text += " in " + std::to_string(session.packets) + " packets";
        if (!session.broadcast) {
          text += ", " + std::to_string(session.windows) + (session.windows == 1 ? " CTS window" : " CTS windows");
          if (session.holds > 0) text += ", " + std::to_string(session.holds) + (session.holds == 1 ? " hold" : " holds");
        }
        text += ", " + millisecondsText(session.endNs - session.startNs);
        break;
      case j1939::TpOutcome::Aborted:
        ++counts.aborted;
        text += ": aborted by the ";
        text += j1939::tpSideName(end.abortedBy);
        text += ", reason " + std::to_string(static_cast<unsigned>(end.abortReason)) + " ";
        text += j1939::tpAbortReasonName(end.abortReason);
        text += ", after " + progress;
        break;
      case j1939::TpOutcome::TimedOut:
        ++counts.timedOut;
        text += ": timed out (" + timerText(end.timer) + ") after " + progress;
        break;
      case j1939::TpOutcome::Replaced:
        ++counts.replaced;
        severity = Severity::Warning;
        text += ": replaced by a new announcement after " + progress;
        break;
      case j1939::TpOutcome::ProtocolError:
        ++counts.protocolErrors;
        text += ": protocol error: ";
        text += j1939::tpErrorText(end.error);
        text += " after " + progress;
        break;
      case j1939::TpOutcome::Incomplete:
        ++counts.incomplete;
        text += ": incomplete at the end of the log, " + progress;
        break;
      case j1939::TpOutcome::Refused:
        ++counts.refused;
        text += " in " + std::to_string(session.packets) + " packets: not followed: ";
        text += j1939::tpErrorText(end.error);
        break;
    }
    report(session.endNs, severity, Check::Transport, std::move(text));
  }

  // ---- DM1 / DM2

  void handleDm(std::uint32_t pgn, std::uint8_t source, std::int64_t timeNs, std::span<const std::uint8_t> data) {
    const std::optional<j1939::Dm1> maybeDm = j1939::decodeDm1(data);
    if (!maybeDm) return;  // shorter than lamps + one record: nothing to conclude
    ++counts.dm1Messages;
    const bool previouslyActive = pgn == j1939::PGN_DM2;
    const std::uint32_t key = (static_cast<std::uint32_t>(currentBus) << 9) |
                              (static_cast<std::uint32_t>(previouslyActive) << 8) | source;
    DtcSource& state = dtcSources[key];
    const std::string prefix = hexByte(source) + (previouslyActive ? " DM2: " : " DM1: ");
    const std::string lamps = lampsText(maybeDm->lamps);

    const std::span<const j1939::Dtc> now = maybeDm->activeDtcs();
    for (std::size_t i = 0; i < now.size(); ++i) {
      const j1939::Dtc& dtc = now[i];
      bool repeated = false;  // the same SPN/FMI twice in one message counts once
      for (std::size_t j = 0; j < i && !repeated; ++j) repeated = now[j].spn == dtc.spn && now[j].fmi == dtc.fmi;
      if (repeated) continue;
      ActiveDtc* known = nullptr;
      for (ActiveDtc& active : state.active) {
        if (active.spn == dtc.spn && active.fmi == dtc.fmi) known = &active;
      }
      if (known != nullptr) {
        if (known->interval != NO_INTERVAL) intervals[known->interval].occurrenceCount = dtc.occurrenceCount;
        continue;
      }
      std::size_t interval = NO_INTERVAL;
      if (intervals.size() < MAX_DTC_INTERVALS) {
        interval = intervals.size();
        intervals.push_back(DtcInterval{currentBus, source, previouslyActive, dtc.spn, dtc.fmi, dtc.occurrenceCount,
                                        timeNs, std::nullopt});
      } else {
        ++counts.dtcIntervalsSkipped;
      }
      state.active.push_back(ActiveDtc{dtc.spn, dtc.fmi, interval});
      report(timeNs, previouslyActive ? Severity::Info : Severity::Warning, Check::Dtc,
             prefix + (previouslyActive ? "DTC listed " : "DTC raised ") + dtcText(dtc) + " (lamps: " + lamps + ")");
    }
    for (std::size_t i = 0; i < state.active.size();) {
      const ActiveDtc& active = state.active[i];
      bool stillActive = false;
      for (const j1939::Dtc& dtc : now) stillActive = stillActive || (dtc.spn == active.spn && dtc.fmi == active.fmi);
      if (stillActive) {
        ++i;
        continue;
      }
      std::uint8_t occurrences = 0;
      if (active.interval != NO_INTERVAL) {
        intervals[active.interval].clearedNs = timeNs;
        occurrences = intervals[active.interval].occurrenceCount;
      }
      char text[64];
      std::snprintf(text, sizeof text, "SPN %u FMI %u (last OC %u)", static_cast<unsigned>(active.spn),
                    static_cast<unsigned>(active.fmi), static_cast<unsigned>(occurrences));
      report(timeNs, Severity::Info, Check::Dtc,
             prefix + (previouslyActive ? "DTC no longer listed " : "DTC cleared ") + text + " (lamps: " + lamps + ")");
      state.active.erase(state.active.begin() + static_cast<std::ptrdiff_t>(i));
    }
    if (state.seen && !(state.lamps == maybeDm->lamps)) {
      report(timeNs, Severity::Info, Check::Dtc, prefix + "lamps " + lampsText(state.lamps) + " -> " + lamps);
    }
    state.seen = true;
    state.lamps = maybeDm->lamps;
  }

  static std::string dtcText(const j1939::Dtc& dtc) {
    char text[64];
    std::snprintf(text, sizeof text, "SPN %u FMI %u OC %u", static_cast<unsigned>(dtc.spn),
                  static_cast<unsigned>(dtc.fmi), static_cast<unsigned>(dtc.occurrenceCount));
    std::string result = text;
    if (dtc.spnConversionMethod) result += " CM 1";
    return result;
  }
};

TransportAnalysis::TransportAnalysis(const AnalysisSetup& setup, OnMessage onMessage)
    : m_impl(std::make_unique<Impl>(setup, std::move(onMessage))) {}
TransportAnalysis::TransportAnalysis(TransportAnalysis&&) noexcept = default;
TransportAnalysis& TransportAnalysis::operator=(TransportAnalysis&&) noexcept = default;
TransportAnalysis::~TransportAnalysis() = default;

void TransportAnalysis::add(const TraceFrame& frame, FindingSink& sink) {
  Impl& impl = *m_impl;
  impl.pollAll(frame.timeNs, sink);
  const can::Frame& can = frame.frame;
  if (!can.extended() || (can.flags & (can::FLAG_ERROR | can::FLAG_RTR)) != 0) return;
  const std::uint32_t pgn = j1939::pgnOf(can.id);
  impl.currentBus = frame.bus;
  impl.currentSink = &sink;
  if (pgn == j1939::PGN_TP_CM || pgn == j1939::PGN_TP_DT) {
    Impl::BusState& state = impl.busState(frame.bus);
    const j1939::TpMonitorCounters before = state.monitor->counters();
    state.monitor->onFrame(can.id, can.payload(), frame.timeNs, impl);
    impl.refreshDeadline(state);
    const j1939::TpMonitorCounters& after = state.monitor->counters();
    impl.counts.sessions += after.started - before.started;
    impl.counts.bam += after.bam - before.bam;
    impl.counts.rtsCts += after.rtsCts - before.rtsCts;
    return;
  }
  if ((pgn == j1939::PGN_DM1 || pgn == j1939::PGN_DM2) && can.length >= MIN_DM1_LENGTH) {
    const std::uint8_t source = static_cast<std::uint8_t>(can.id & 0xFFu);
    impl.handleDm(pgn, source, frame.timeNs, can.payload());
    if (impl.onMessage) {
      impl.onMessage(ReassembledMessage{frame.bus, pgn, source, j1939::GLOBAL_ADDRESS, true, frame.timeNs,
                                        frame.message, can.payload()});
    }
  }
}

void TransportAnalysis::finish(std::int64_t endNs, FindingSink& sink) {
  Impl& impl = *m_impl;
  impl.currentSink = &sink;
  for (std::size_t bus = 0; bus < impl.buses.size(); ++bus) {
    Impl::BusState& state = impl.buses[bus];
    if (!state.monitor) continue;
    impl.currentBus = static_cast<std::uint16_t>(bus);
    state.monitor->finish(endNs, impl);
    impl.refreshDeadline(state);
  }
}

const TransportCounts& TransportAnalysis::counts() const noexcept { return m_impl->counts; }

const std::vector<DtcInterval>& TransportAnalysis::dtcIntervals() const noexcept { return m_impl->intervals; }

}  // namespace openvcu::trace
