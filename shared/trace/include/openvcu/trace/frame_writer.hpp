#pragma once
// The one writer of decoded frames: `vcu dbc decode` and the HMI trace viewer's CSV export
// both write through FrameWriter. Text goes into a caller-owned, reused buffer with
// std::to_chars: no iostreams and no JSON library per frame, and one room reservation per
// frame instead of a capacity check per piece (why: a million-frame log must decode in
// well under a second of CPU).
//
// JSONL, one object per frame, the shape of /work/shared/tools/dbc-oracle.py decode
// (its "ch" is "bus" here) so both can be compared line by line:
//   {"t":1700000000.012345,"bus":"can0","id":217056510,"ext":true,"msg":"EEC1",
//    "signals":{"EngineSpeed":1250.5},"raw":{"EngineSpeed":10004}}
//   unknown frame: ..."msg":null,"signals":{},"raw":{}}
// CSV (RFC 4180 quoting), a header, then one row per decoded signal; a frame without
// decoded signals (unknown, remote request) is one row with empty signal, raw, physical:
//   t,bus,id,ext,msg,signal,raw,physical
//   1700000000.012345,can0,217056510,true,EEC1,EngineSpeed,10004,1250.5
//
// Numbers follow the oracle's jnum/jraw: a value that is integral and below 2^53 in
// magnitude prints as an integer (-0 as 0); NaN and infinities as "nan", "inf", "-inf"
// (strings in JSON, bare in CSV); anything else as the shortest text that reads back to
// the same double. Integer raw values print exactly; float raws like physical values.
// Times print exactly as logged: seconds with 6 decimals, 9 when the log had nanoseconds.
//
// J1939 records (`vcu dbc decode`, issue 21) extend these shapes; normal frames are unchanged:
//   DM1/DM2 frame:        ...,"raw":{...},"dm1":{"type":"DM1","lamps":{"malfunction":"Off",
//                         "redStop":"Off","amberWarning":"On","protect":"Off"},
//                         "dtcs":[{"spn":100,"fmi":1,"oc":3,"cm":0}]}}
//   reassembled message:  {"t":..,"bus":..,"id":<priority 6, PGN, SA, DA>,"ext":true,"msg":..,
//                         "signals":{..},"raw":{..},"tp":{"pgn":65251,"sa":0,"da":255,"size":34,"bam":true}}
//   session not completed: ...,"tp":{..},"tp_end":{"outcome":"Aborted","reason":"by the responder,
//                         reason 1 AlreadyInSession","received":0,"packets":3,"start":1.5}}
//   CSV: a DM1/DM2 adds rows lamp.malfunction, lamp.redStop, lamp.amberWarning, lamp.protect
//   (raw = physical = the 2-bit state) and dtcN.spn, dtcN.fmi, dtcN.oc, dtcN.cm per DTC
//   (N from 1), msg the DBC name or DM1/DM2; a session not completed is one row with msg
//   "tp_end", signal "<Outcome>: <reason>, <received> of <packets> packets", raw and
//   physical empty.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/can/log_reader.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/transport_monitor.hpp"

namespace openvcu::trace {

enum class DecodeFormat : std::uint8_t { Jsonl, Csv };

/// One decoded signal of a frame: its index in Message::signals and its value.
struct SignalValue {
  std::uint32_t signalIndex{};
  dbc::DecodedValue value;
};

/// Appends a physical value by the jnum rule. `quoteNonFinite`: "nan" in quotes (JSON).
void appendNumber(std::string& out, double value, bool quoteNonFinite);
/// Appends a raw value: integers exactly, float32/float64 raws by the jnum rule.
void appendRaw(std::string& out, const dbc::DecodedValue& value, bool quoteNonFinite);
/// Appends a time in seconds: -1500000 -> "-0.001500", 1000000001 -> "1.000000001".
void appendSeconds(std::string& out, std::int64_t nanoseconds);
/// Appends a JSON string literal, quotes included; bytes that are not UTF-8 are read as Latin-1.
void appendJsonString(std::string& out, std::string_view text);
/// Appends a CSV field, quoted (with doubled quotes) only when it holds , " CR or LF.
void appendCsvField(std::string& out, std::string_view text);

/// Formats decoded frames for one database. Names are escaped once, at construction.
/// @note appendFrame() allocates only when `out` grows or the channel name changes.
class FrameWriter {
 public:
  FrameWriter(const dbc::Database& database, DecodeFormat format);

  /// CSV: the header line; JSONL: nothing.
  void appendHeader(std::string& out) const;

  /// One frame. `messageIndex` indexes Database::messages, or is MessageMatcher::NO_MATCH;
  /// `values` are the signals decoded from the frame, in the codec's order.
  void appendFrame(std::string& out, const can::LogRecord& record, std::int32_t messageIndex,
                   std::span<const SignalValue> values);

  /// A frame carrying a J1939-73 DM1 (or DM2: `previouslyActive`): appendFrame()'s record
  /// plus JSONL "dm1", CSV lamp and DTC rows.
  void appendDmFrame(std::string& out, const can::LogRecord& record, std::int32_t messageIndex,
                     std::span<const SignalValue> values, const j1939::Dm1& dm, bool previouslyActive);

  /// A message reassembled from a J1939-21 session. `record` carries the time and channel
  /// of the TP.DT that completed it and the message's identifier (priority 6, PGN, source,
  /// destination); `dm` (optional) its DM1/DM2 content. JSONL adds "tp" (and "dm1").
  void appendTransportMessage(std::string& out, const can::LogRecord& record, const j1939::TpSessionInfo& session,
                              std::int32_t messageIndex, std::span<const SignalValue> values,
                              const j1939::Dm1* dm, bool previouslyActive);

  /// A J1939-21 session that ended without completing (aborted, timed out, replaced,
  /// protocol error, incomplete, refused); `record` as for appendTransportMessage().
  void appendTransportEnd(std::string& out, const can::LogRecord& record, const j1939::TpSessionEnd& end,
                          std::int32_t messageIndex);

 private:
  struct MessageText {
    std::string name;                      ///< JSON: "\"EEC1\""; CSV: the escaped field
    std::vector<std::string> signalNames;  ///< JSON: "\"EngineSpeed\":"; CSV: the escaped field
    std::size_t longestSignalName{};       ///< bounds the room a frame needs
  };

  void appendJsonFrame(std::string& out, const can::LogRecord& record, const MessageText* message,
                       std::span<const SignalValue> values) const;
  void appendCsvFrame(std::string& out, const can::LogRecord& record, const MessageText* message,
                      std::span<const SignalValue> values) const;
  void rememberChannel(std::string_view channel);
  void appendJsonDm(std::string& out, const j1939::Dm1& dm, bool previouslyActive) const;
  void appendCsvDmRows(std::string& out, const can::LogRecord& record, std::int32_t messageIndex,
                       const j1939::Dm1& dm, bool previouslyActive) const;
  void appendCsvPrefix(std::string& out, const can::LogRecord& record, std::string_view messageField) const;
  [[nodiscard]] const MessageText* messageText(std::int32_t messageIndex) const noexcept;

  std::vector<MessageText> m_messages;  ///< by message index
  std::string m_channel;                ///< the last channel seen ...
  std::string m_channelText;            ///< ... escaped for the format
  DecodeFormat m_format;
};

}  // namespace openvcu::trace
