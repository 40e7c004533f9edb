#include "openvcu/j1939/diagnostic_state.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "openvcu/j1939/dm_encode.hpp"

namespace openvcu::j1939 {
namespace {

/// Fast over slow over not flashing (Reserved counts as not flashing).
constexpr LampFlash strongerFlash(LampFlash a, LampFlash b) noexcept {
  const auto rank = [](LampFlash flash) { return flash == LampFlash::Fast ? 2 : flash == LampFlash::Slow ? 1 : 0; };
  return rank(a) >= rank(b) ? a : b;
}

void addLamp(bool on, LampFlash flash, LampStatus& status, LampFlash& combined) noexcept {
  if (!on) return;
  status = LampStatus::On;
  combined = strongerFlash(combined, flash);
}

}  // namespace

Result<DiagnosticState> DiagnosticState::create(std::vector<DtcDefinition> definitions, std::int64_t dm1PeriodNs) {
  if (dm1PeriodNs <= 0) return Error{"the DM1 period must be above 0"};
  if (definitions.size() > DM1_MAX_DTCS) {
    return Error{std::to_string(definitions.size()) + " DTC definitions: one DM1 holds at most " +
                 std::to_string(DM1_MAX_DTCS)};
  }
  for (std::size_t i = 0; i < definitions.size(); ++i) {
    const DtcDefinition& definition = definitions[i];
    const std::string where = "DTC definition " + std::to_string(i) + ": ";
    if (definition.spn > DTC_MAX_SPN) return Error{where + "SPN " + std::to_string(definition.spn) + " is over 524287"};
    if (definition.fmi > DTC_MAX_FMI) return Error{where + "FMI " + std::to_string(definition.fmi) + " is over 31"};
    if (definition.spn == 0 && definition.fmi == 0) return Error{where + "SPN 0 with FMI 0 means \"no DTC\""};
    for (std::size_t j = 0; j < i; ++j) {
      if (definitions[j].spn == definition.spn && definitions[j].fmi == definition.fmi) {
        return Error{where + "SPN " + std::to_string(definition.spn) + " FMI " + std::to_string(definition.fmi) +
                     " is already DTC definition " + std::to_string(j)};
      }
    }
  }
  return DiagnosticState(std::move(definitions), dm1PeriodNs);
}

DiagnosticState::DiagnosticState(std::vector<DtcDefinition> definitions, std::int64_t dm1PeriodNs)
    : m_definitions(std::move(definitions)),
      m_active(m_definitions.size(), 0),
      m_counts(m_definitions.size(), 0),
      m_periodNs(dm1PeriodNs) {
  m_activeDtcs.reserve(m_definitions.size());
  m_previousDtcs.reserve(m_definitions.size());
  rebuild();
}

bool DiagnosticState::update(std::span<const bool> active, std::int64_t nowNs) noexcept {
  bool changed = false;
  const std::size_t count = std::min(active.size(), m_definitions.size());
  for (std::size_t i = 0; i < count; ++i) {
    const bool now = active[i];
    if (now == (m_active[i] != 0)) continue;
    changed = true;
    m_active[i] = now ? 1 : 0;
    if (now && m_counts[i] < DTC_MAX_COUNTED_OCCURRENCES) ++m_counts[i];
  }
  if (changed) {
    rebuild();
    m_changePending = true;
    m_lastChangeNs = nowNs;
  }
  return changed;
}

bool DiagnosticState::clearPreviouslyActive() noexcept {
  if (m_previousDtcs.empty()) return false;
  for (std::size_t i = 0; i < m_definitions.size(); ++i) {
    if (m_active[i] == 0) m_counts[i] = 0;
  }
  rebuild();
  return true;
}

bool DiagnosticState::clearActive() noexcept {
  bool dm1Changed = false;
  const bool dm2Changed = !m_previousDtcs.empty();
  for (std::size_t i = 0; i < m_definitions.size(); ++i) {
    const std::uint8_t cleared = m_active[i] != 0 ? 1 : 0;
    if (m_active[i] != 0 && m_counts[i] != cleared) dm1Changed = true;
    m_counts[i] = cleared;
  }
  if (!dm1Changed && !dm2Changed) return false;
  rebuild();
  if (dm1Changed) m_changePending = true;
  return true;
}

std::size_t DiagnosticState::restoreCounts(std::span<const Dtc> saved) noexcept {
  std::size_t matched = 0;
  for (std::size_t i = 0; i < m_definitions.size(); ++i) {
    for (const Dtc& dtc : saved) {
      if (dtc.spn != m_definitions[i].spn || dtc.fmi != m_definitions[i].fmi) continue;
      m_counts[i] = std::min(dtc.occurrenceCount, DTC_MAX_COUNTED_OCCURRENCES);
      ++matched;
      break;
    }
  }
  rebuild();
  return matched;
}

void DiagnosticState::rebuild() noexcept {
  // Within the capacity reserved at construction: no allocation.
  m_activeDtcs.clear();
  m_previousDtcs.clear();
  LampStates lamps;
  lamps.protect = lamps.amberWarning = lamps.redStop = lamps.malfunction = LampStatus::Off;
  for (std::size_t i = 0; i < m_definitions.size(); ++i) {
    const DtcDefinition& definition = m_definitions[i];
    const Dtc dtc{definition.spn, definition.fmi, m_counts[i], false};
    if (m_active[i] != 0) {
      m_activeDtcs.push_back(dtc);
      const DtcLampRequest& request = definition.lamps;
      addLamp(request.protect, request.protectFlash, lamps.protect, lamps.protectFlash);
      addLamp(request.amberWarning, request.amberWarningFlash, lamps.amberWarning, lamps.amberWarningFlash);
      addLamp(request.redStop, request.redStopFlash, lamps.redStop, lamps.redStopFlash);
      addLamp(request.malfunction, request.malfunctionFlash, lamps.malfunction, lamps.malfunctionFlash);
    } else if (m_counts[i] > 0) {
      m_previousDtcs.push_back(dtc);
    }
  }
  m_lamps = lamps;
}

std::size_t DiagnosticState::encodeDm1(std::span<std::uint8_t> out) const noexcept {
  return j1939::encodeDm1(m_lamps, m_activeDtcs, out);
}

std::size_t DiagnosticState::encodeDm2(std::span<std::uint8_t> out) const noexcept {
  return j1939::encodeDm2(m_lamps, m_previousDtcs, out);
}

bool DiagnosticState::dm1Due(std::int64_t nowNs) const noexcept {
  return nowNs >= nextDm1DueNs();
}

std::int64_t DiagnosticState::nextDm1DueNs() const noexcept {
  if (!m_sentOnce) return std::numeric_limits<std::int64_t>::min();
  std::int64_t next = m_lastSentNs + m_periodNs;
  if (m_changePending) {
    next =
        std::min(next, m_changeSentOnce ? m_lastChangeSentNs + m_periodNs : std::numeric_limits<std::int64_t>::min());
  }
  return next;
}

void DiagnosticState::dm1Sent(std::int64_t nowNs) noexcept {
  m_sentOnce = true;
  m_lastSentNs = nowNs;
  if (m_changePending) {
    m_changeSentOnce = true;
    m_lastChangeSentNs = nowNs;
    m_changePending = false;
  }
}

}  // namespace openvcu::j1939
