#pragma once
// Which value of a signal-table slot a person sees and how it becomes a status and a text:
// the one place that decides it for every screen of the HMI and of vcu-web.
//
//   classify(bus, nowNs, 2 s) -> ValueStatus::Stale for a bus value 3 s old
//   formatValue(info, 87.456, "%.1f") -> "87.5 %" ; formatValue(relay, 1, "") -> "On"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::display {

/// What a value, a service or a model shows about its freshness (a colour or a marking).
enum class ValueStatus : std::uint8_t {
  Ready,         ///< a valid value within its timeout
  Stale,         ///< a value older than its timeout, or marked Stale/OutOfRange by can-rx
  NotConnected,  ///< never received, or no signal table / no event bus
  Error,         ///< the configuration or the connection failed
};

/// "Ready", "Stale", "NotConnected", "Error".
[[nodiscard]] std::string_view statusName(ValueStatus status) noexcept;

/// How one slot is judged at `nowNs` (CLOCK_MONOTONIC), along the same order as
/// shownValue: a slot with a bus value by that value's quality and age; without one, a
/// command or an active override counts as Ready; nothing written: NotConnected.
/// @note noexcept, allocation-free (display-rate path).
[[nodiscard]] ValueStatus classify(const signals::SlotSnapshot& slot, std::int64_t nowNs,
                                   std::int64_t staleAfterNs) noexcept;

/// The age after which a value counts as Stale: `busTimeoutNs` for DBC signals; 0 (no age
/// limit, quality only) for internal signals, which are written on change (a relay, a fault
/// line, the FSM state) and may rightly stay unchanged for hours.
[[nodiscard]] std::int64_t staleAfterFor(const signals::SignalInfo& signal, std::int64_t busTimeoutNs) noexcept;

/// The one place that decides which value of a slot is shown (the dashboard, the status
/// table, the DBC tree, the header, the live plot, the operator switches), by the signal's
/// direction in the catalog: the bus value once one was received (what another node sent,
/// what can-tx sent, a status); for a transmitted or internal signal without one, the
/// effective command (override, then command plane: signals::effectiveCommand); a
/// received signal shows only what came from the bus. Empty when nothing applies.
/// @note noexcept, allocation-free (display-rate path).
[[nodiscard]] std::optional<double> shownValue(const signals::SignalInfo& signal,
                                               const signals::SlotSnapshot& slot) noexcept;

/// shownValue with the CLOCK_MONOTONIC time its plane was written (an active override's
/// time when one is active, else the bus value's once received, else the command's): what
/// vcu-web's live pages show as the age and vcu-telemetry stamps a sample with.
/// @note noexcept, allocation-free.
struct ShownSample {
  double value{};
  std::int64_t timestampNs{};
};
[[nodiscard]] std::optional<ShownSample> shownSample(const signals::SignalInfo& signal,
                                                     const signals::SlotSnapshot& slot) noexcept;

/// "87.5 %" with a printf format for the number ("%.1f"; empty: shortest), the value text
/// alone when the signal has one for `value` ("Closed"). A format that
/// config::isSafeNumberFormat refuses falls back to "%g".
[[nodiscard]] std::string formatValue(const signals::SignalInfo& signal, double value, std::string_view format);

/// A short row label for a key: transmitter and signal ("HVLP_SA71 InverterStatus"), or
/// the last two components of an internal key ("relay Cl15").
[[nodiscard]] std::string shortLabel(std::string_view key);

/// Green/red/neutral class of a value text: "Normal", "OK", "Closed" -> Good; texts with
/// "Fault", "Error", "Fail", "Alarm" -> Bad; else Neutral.
enum class TextTone : std::uint8_t { Neutral, Good, Bad };
[[nodiscard]] TextTone toneOf(std::string_view text) noexcept;

}  // namespace openvcu::display
