#pragma once
// Small helpers the Qt models share: texts for durations, clock times and hex IDs, a table
// slot read through the stack connection, and the FSM file's rules for the operator
// switches and the state name.
// @note GUI thread only.

#include <QString>
#include <cstdint>
#include <optional>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "openvcu/signals/table.hpp"
#endif

namespace openvcu::hmi {

/// "12.3 s", "4 min 5 s", "2 h 4 min".
[[nodiscard]] QString durationText(std::int64_t nanoseconds);

/// "14:03:07.123" in local time for CLOCK_REALTIME ns.
[[nodiscard]] QString clockText(std::int64_t realtimeNs);

/// "0x18FF50E5" with `digits` hex digits.
[[nodiscard]] QString hexText(std::uint32_t value, int digits);

/// Reads one slot of the table; empty without a stack, an index or a table.
[[nodiscard]] std::optional<signals::SlotSnapshot> readSlot(std::optional<signals::SignalIndex> index);

/// The configuration's FSM rules; empty without a stack or an FSM file, and empty with
/// `error` set when the file is refused.
[[nodiscard]] std::optional<FsmRules> loadRules(QString& error);

}  // namespace openvcu::hmi
