#pragma once
// The writer of schedule.json behind `vcu schedule import`: the thesis' schedule sheet (its
// Excel workbook exported as CSV) converted into the schedule JSON of docs/design/can-tx.md,
// checked against the DBC; loadSchedule (schedule_config.hpp) reads what it writes.
//
//   NodeName,SheetName,UniqueID,Message,Signal,DeltaTime,IsSHM,CycleTime,Value
//   Battery,shm,61427,S1_ES_PGN61427,Control_Es_Relay,0.292,1,20,3
//   Battery,shm,,S1_ES_PGN61427,Service_Mode_Request,,,,3
//   Inverter,nonshm,0x19107171,HC1_Demands,ControlWord,,0,10,6
// ->
//   {"include": ["S1_ES_PGN61427", "HC1_Demands"],
//    "messages": {"S1_ES_PGN61427": {"cycleMs": 20, "group": "Battery",
//                                    "values": {"Control_Es_Relay": 3, "Service_Mode_Request": 3},
//                                    "safety": {"deltaUs": 292}},
//                 "HC1_Demands": {"cycleMs": 10, "group": "Inverter", "values": {"ControlWord": 6}}},
//    "groups": {"Battery": {"signal": "internal.tx.Battery"}, "Inverter": {"signal": "internal.tx.Inverter"}}}
//
// What the columns mean:
// - Header: the first non-empty line, exactly the nine names above (case-sensitive) in any
//   order. A missing, repeated or unknown column is an error naming it; nothing else is read.
// - One row = one signal's default value in one message: messages.<Message>.values.<Signal>
//   = Value, a physical value: a finite number inside the signal's DBC [min|max] when
//   min < max. A row with Signal and Value both empty only lists its message. The same
//   signal twice: an error when the values differ, a warning when they agree.
// - Message: a DBC message name (required). Signal: a signal of that message.
// - Per-message columns (NodeName, UniqueID, CycleTime, IsSHM, DeltaTime): empty means "not
//   said on this row"; they may be empty on all rows of a message but one, and the values
//   given on its rows must agree (the error names the line of the first one).
// - CycleTime: whole milliseconds, 1..3600000, required once per message -> "cycleMs",
//   always written, also when it equals the DBC's GenMsgCycleTime (an import is explicit).
// - IsSHM: 1/0, true/false, yes/no (any case); not said on any row = 0. 1 makes the message
//   a J1939-76 SDM, sent after its SHM: "safety": {"deltaUs": round(DeltaTime ms * 1000)},
//   so 0.292 -> 292 (the original cut the delta to whole ms, which was a defect). An SDM
//   needs a 29-bit identifier and a DeltaTime > 0 that is shorter than its CycleTime. A
//   DeltaTime > 0 on a message that is not an SDM is ignored with a warning. The safety
//   header itself (PGN 0x0E00) cannot be listed: it goes out with its SDM.
// - NodeName: the send group (the original split its rows by node into the battery and
//   the inverter group): "group": NodeName on the message, and in "groups" the catalog key
//   that switches the group, "internal.tx.<NodeName>" unless ImportOptions::groupSignals
//   maps the node to another key. Empty on every row of a message: no group (always sent).
//   A note lists the group keys that vehicle.json does not declare (all of them when no
//   catalog is given).
// - UniqueID (optional): 0x-hex or decimal; must be the message's CAN ID (flags excluded),
//   its J1939 PGN, or its 18-bit PGN field with the PDU1 destination kept, as the original
//   named some messages (S1_ES_PGN61427 = 0x0CEFF321: 0xEFF3 = 61427).
// - SheetName: informational. A sheet named "shm" or "nonshm" (any case; '-', '_', ' '
//   ignored) that contradicts the message's IsSHM gets a warning.
// - UniqueID, CycleTime, IsSHM, DeltaTime: "nan" (pandas' text for an empty cell) is empty.
// The text: RFC 4180 CSV: quoted fields ("a,b", "say ""hi"""), LF or CRLF line ends, a UTF-8
// BOM skipped, empty lines and lines of empty fields skipped, spaces around a field
// trimmed. Text that is not valid UTF-8 is read as Windows-1252 (Excel's "CSV") with a
// warning.
// The JSON: keys in a fixed order ("include", "messages", "groups"; per message "cycleMs",
// "group", "values", "safety"); messages, values and groups in the order first seen;
// "include" lists exactly the imported messages, so the schedule sends what the sheet lists.
//
// Every problem is collected (errors, warnings, notes), each named "file:line" by the row
// (the line where the row starts); with any error there is no result.

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/model.hpp"

namespace openvcu::signals {
class Catalog;
}

namespace openvcu::schedule {

/// The sheet's columns, in the original workbook's order.
inline constexpr std::array<std::string_view, 9> SCHEDULE_CSV_COLUMNS = {
    "NodeName", "SheetName", "UniqueID", "Message", "Signal", "DeltaTime", "IsSHM", "CycleTime", "Value"};

/// Prefix of the default send-group keys: NodeName "Battery" -> "internal.tx.Battery".
inline constexpr std::string_view GROUP_SIGNAL_PREFIX = "internal.tx.";

struct ImportOptions {
  /// This VCU's DBC node: a message it does not transmit gets a warning. Empty: no check.
  std::string node;
  /// NodeName -> the catalog key that switches its group (--group-signal NODE=KEY).
  std::vector<std::pair<std::string, std::string>> groupSignals;
  /// The configuration's catalog, when known: mapped keys must exist in it, and the note
  /// names only the default group keys it lacks. nullptr: no check, every default key is named.
  const signals::Catalog* catalog{};
};

/// Converts the sheet `text` (named `fileName` in diagnostics) into the schedule JSON.
/// Every error, warning and note is appended to *diagnostics (when given) in line order.
/// Returns the schedule, or the first error when there was any.
/// @note pure function: reads nothing but its arguments; not real-time (allocates).
Result<nlohmann::ordered_json> importScheduleCsv(std::string_view text, const std::string& fileName,
                                                 const dbc::Database& database, const ImportOptions& options,
                                                 std::vector<Error>* diagnostics);

}  // namespace openvcu::schedule
