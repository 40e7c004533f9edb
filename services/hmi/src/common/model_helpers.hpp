#pragma once
// Small helpers the Qt models share: the rows of a flat list model, texts for durations,
// clock times and hex IDs, a table slot read through the stack connection, and the FSM
// file's rules for the operator switches and the state name.
// @note GUI thread only.

#include <QModelIndex>
#include <QString>
#include <cstdint>
#include <optional>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "openvcu/signals/table.hpp"
#endif

namespace openvcu::hmi {

/// rowCount() of a flat list model with `count` rows: 0 under a valid parent.
[[nodiscard]] inline int listRowCount(const QModelIndex& parent, std::size_t count) noexcept {
  return parent.isValid() ? 0 : static_cast<int>(count);
}

/// The row `index` points at in a flat list of `count` rows; empty for an invalid index or
/// one past the end.
[[nodiscard]] inline std::optional<std::size_t> listRow(const QModelIndex& index, std::size_t count) noexcept {
  if (!index.isValid() || index.row() >= static_cast<int>(count)) return std::nullopt;
  return static_cast<std::size_t>(index.row());
}

/// The element of `rows` that `index` points at; null for an invalid index or one past the end.
template <class Row>
[[nodiscard]] const Row* rowAt(const std::vector<Row>& rows, const QModelIndex& index) noexcept {
  const std::optional<std::size_t> row = listRow(index, rows.size());
  return row ? &rows[*row] : nullptr;
}

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
