#pragma once
// The VCU's own diagnostic trouble codes (SAE J1939-73), as an engine without threads or
// I/O: the caller says which DTC definitions are active now; the state keeps occurrence
// counts, the DM1 content (active DTCs and lamps), the DM2 content (previously active DTCs),
// answers DM3 and DM11 clears and says when a DM1 is due (design note:
// docs/design/j1939-diagnostics.md).
//
//   auto stateResult = DiagnosticState::create({{520192, 12, {.redStop = true}}});
//   DiagnosticState& sut = *stateResult;
//   const bool active[] = {true};
//   sut.update(active, now);          // -> true: SPN 520192 FMI 12 active, count 1, red stop on
//   if (sut.dm1Due(now)) { auto n = sut.encodeDm1(buffer); send(buffer, n); sut.dm1Sent(now); }
//
// Rules applied (J1939-73):
//   - the occurrence count of a definition increments on each inactive -> active transition
//     and stays at 126 (127 means "not available");
//   - DM1 lists the active definitions with their counts; lamps are the OR of the active
//     definitions' lamps (a lamp's flash: fast over slow over none), all Off when none is
//     active;
//   - DM2 lists the definitions that are not active and have a count above 0, with the
//     current lamps;
//   - DM3 (clearPreviouslyActive) sets the counts of inactive definitions to 0: DM2 empties;
//   - DM11 (clearActive) sets every count to 0 (DM2 empties); a condition still present
//     stays active and counts as its first occurrence after the clear (count 1);
//   - DM1 timing: every period (1 s) whether or not a DTC is active, and at once when the
//     DM1 content changes, but at most one on-change DM1 per period (J1939-73 asks for no
//     more than one state change per DTC per second; one per period for all DTCs is
//     stricter). A DM1 sent for a change restarts the period.
//
// @note not thread-safe: one thread (the transmit thread) owns it. Allocation-free after
//       create(); every member except create() is noexcept.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/j1939/dm1.hpp"

namespace openvcu::j1939 {

inline constexpr std::uint8_t DTC_MAX_COUNTED_OCCURRENCES = 126;  ///< J1939-73: the count saturates at 126
inline constexpr std::int64_t DM1_PERIOD_NS = 1'000'000'000;      ///< J1939-73: DM1 once per second

/// The lamps a DTC definition asks for while it is active; flash applies to a lamp that is on.
struct DtcLampRequest {
  bool protect{};
  bool amberWarning{};
  bool redStop{};
  bool malfunction{};
  LampFlash protectFlash{LampFlash::NotFlashing};
  LampFlash amberWarningFlash{LampFlash::NotFlashing};
  LampFlash redStopFlash{LampFlash::NotFlashing};
  LampFlash malfunctionFlash{LampFlash::NotFlashing};
  friend constexpr bool operator==(const DtcLampRequest&, const DtcLampRequest&) = default;
};

/// One DTC the VCU can raise.
struct DtcDefinition {
  std::uint32_t spn{};  ///< 1..524287 (SPN 0 with FMI 0 means "no DTC" on the bus)
  std::uint8_t fmi{};   ///< 0..31
  DtcLampRequest lamps;
};

class DiagnosticState {
 public:
  /// Refused: an SPN over 524287, an FMI over 31, SPN 0 with FMI 0, the same SPN and FMI
  /// twice, more than 445 definitions (one DM1), a period of 0 or less. The error names
  /// the definition's index.
  static Result<DiagnosticState> create(std::vector<DtcDefinition> definitions,
                                        std::int64_t dm1PeriodNs = DM1_PERIOD_NS);

  /// Takes which definitions are active now (active[i] for definitions()[i]; a shorter span
  /// leaves the rest as they were, extra entries are ignored). true when the DM1 content
  /// changed (a definition became active or inactive); the next DM1 is then due at once
  /// (subject to the on-change limit).
  bool update(std::span<const bool> active, std::int64_t nowNs) noexcept;

  /// DM3: counts of inactive definitions to 0. true when DM2 changed.
  bool clearPreviouslyActive() noexcept;
  /// DM11: every count to 0, a still-active definition to 1. true when DM1 or DM2 changed;
  /// a DM1 change makes the next DM1 due at once.
  bool clearActive() noexcept;

  /// Restores persisted counts by SPN and FMI (each saved DTC's occurrenceCount, capped at
  /// 126); entries that match no definition are ignored. Returns how many matched.
  std::size_t restoreCounts(std::span<const Dtc> saved) noexcept;

  [[nodiscard]] std::span<const DtcDefinition> definitions() const noexcept { return m_definitions; }
  /// Occurrence count per definition (index-aligned with definitions()).
  [[nodiscard]] std::span<const std::uint8_t> counts() const noexcept { return m_counts; }
  [[nodiscard]] bool active(std::size_t index) const noexcept { return index < m_active.size() && m_active[index]; }

  /// DM1 content: active DTCs in definition order, with their counts.
  [[nodiscard]] std::span<const Dtc> activeDtcs() const noexcept { return m_activeDtcs; }
  /// DM2 content: previously active DTCs in definition order.
  [[nodiscard]] std::span<const Dtc> previouslyActiveDtcs() const noexcept { return m_previousDtcs; }
  [[nodiscard]] const LampStates& lamps() const noexcept { return m_lamps; }

  /// The current DM1 / DM2 bytes (dm_encode.hpp); 0 when `out` is too small.
  [[nodiscard]] std::size_t encodeDm1(std::span<std::uint8_t> out) const noexcept;
  [[nodiscard]] std::size_t encodeDm2(std::span<std::uint8_t> out) const noexcept;

  /// true when a DM1 should be sent now: none sent yet, a period since the last one, or a
  /// change pending and no on-change DM1 within the last period.
  [[nodiscard]] bool dm1Due(std::int64_t nowNs) const noexcept;
  /// When the next DM1 is due (for the caller's sleep); INT64_MIN when none was sent yet.
  [[nodiscard]] std::int64_t nextDm1DueNs() const noexcept;
  /// The caller sent the current DM1 at `nowNs`.
  void dm1Sent(std::int64_t nowNs) noexcept;
  /// Time of the last update() that changed the DM1 content; 0 before any.
  [[nodiscard]] std::int64_t lastChangeNs() const noexcept { return m_lastChangeNs; }

 private:
  DiagnosticState(std::vector<DtcDefinition> definitions, std::int64_t dm1PeriodNs);
  void rebuild() noexcept;

  std::vector<DtcDefinition> m_definitions;
  std::vector<std::uint8_t> m_active;  ///< 0/1 per definition
  std::vector<std::uint8_t> m_counts;
  std::vector<Dtc> m_activeDtcs;  ///< capacity = definitions, filled by rebuild()
  std::vector<Dtc> m_previousDtcs;
  LampStates m_lamps;
  std::int64_t m_periodNs;
  std::int64_t m_lastSentNs{};
  std::int64_t m_lastChangeSentNs{};
  std::int64_t m_lastChangeNs{};
  bool m_sentOnce{};
  bool m_changeSentOnce{};
  bool m_changePending{};
};

}  // namespace openvcu::j1939
