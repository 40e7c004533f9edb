#pragma once
// The types the trace analysis passes around (design: docs/design/trace-analysis.md):
// a frame of the merged timeline of one or more logs (TraceFrame), and a finding of a
// protocol check (Finding) with the sink that receives findings as they are made.
//
//   TraceFrame{frame 0x18FECA21 [8], timeNs 1700000000123456000, bus 0 ("can0"),
//              message 12 (DM1 in the DBC), log 0, line 4711}
//   Finding{timeNs ..., bus 0, Severity::Fault, Check::Safety,
//           "S1_ES (0x0CEFF321): CrcMismatch: SHM CRC 0x8100EFA3, SDM data CRC 0x12345678"}
//
// Time is the log's own time (candump: ns since 1970; ASC: ns since the log's start);
// texts print it as seconds from the first frame of the timeline.

#include <cstdint>
#include <string>
#include <string_view>

#include "openvcu/can/frame.hpp"

namespace openvcu::trace {

/// One frame of the analysed timeline (one log, or several merged by time).
struct TraceFrame {
  can::Frame frame{};        ///< frame.timestampNs == timeNs
  std::int64_t timeNs{};     ///< the log's time of the frame
  std::uint16_t bus{};       ///< index into the timeline's bus names (the log channel: "can0", "vehicle", ASC "1")
  std::int32_t message{-1};  ///< index into the database's messages, or -1 (no DBC message)
  std::uint16_t log{};       ///< index of the log file the frame came from
  std::uint64_t line{};      ///< 1-based line in that log
};

/// How bad a finding is. Fault makes `vcu trace check` exit with 1.
enum class Severity : std::uint8_t {
  Info,     ///< worth a line (a TP session completed, a DTC cleared)
  Warning,  ///< suspicious but not a protocol fault (a DTC raised, a gap in a cyclic message)
  Fault,    ///< a protocol fault (broken J1939-76 pair, aborted or timed-out TP session, unanswered request)
};

/// Which check made a finding.
enum class Check : std::uint8_t {
  Log,        ///< the log itself: time going backwards, malformed lines
  Safety,     ///< J1939-76 safety pairs (SHM/SDM)
  Transport,  ///< J1939-21 transport sessions (BAM, RTS/CTS)
  Dtc,        ///< J1939-73 DM1/DM2: DTCs raised and cleared, lamps
  Request,    ///< J1939-21 requests (PGN 59904) and their answers
};

/// "info", "warning", "fault".
[[nodiscard]] constexpr std::string_view severityName(Severity severity) noexcept {
  switch (severity) {
    case Severity::Info: return "info";
    case Severity::Warning: return "warning";
    case Severity::Fault: return "fault";
  }
  return "?";
}

/// "log", "j1939-76", "tp", "dtc", "request".
[[nodiscard]] constexpr std::string_view checkName(Check check) noexcept {
  switch (check) {
    case Check::Log: return "log";
    case Check::Safety: return "j1939-76";
    case Check::Transport: return "tp";
    case Check::Dtc: return "dtc";
    case Check::Request: return "request";
  }
  return "?";
}

/// One thing a check found, at a time of the timeline.
struct Finding {
  std::int64_t timeNs{};  ///< the log's time at which it was found
  std::uint16_t bus{};    ///< index into the timeline's bus names
  Severity severity{Severity::Info};
  Check check{Check::Log};
  std::string text;       ///< one line, no newline: what, which message/node, and why
};

/// Receives findings as the checks make them (in time order per check).
/// Why virtual: the CLI prints them as they come, the HTML report keeps a bounded list.
class FindingSink {
 public:
  virtual ~FindingSink() = default;
  virtual void finding(const Finding& finding) = 0;
};

}  // namespace openvcu::trace
