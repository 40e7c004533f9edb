#pragma once
// The generic simulated vehicle ("model": "generic" in simulation.json): every other node's
// cyclic messages from the DBC's start values (the virtual bus does that), changed by the
// file's rules, follow, integrate and faults (config::SimRules, compiled at load), stepped
// with the time passed in (tests drive it with a fake clock). One step:
//   1. every signal the file reads is sampled: the VCU's as last received (no value before
//      its first frame), the simulated nodes' as their payloads hold them now, sim.safety.ok;
//   2. the rules in file order: a rule whose `when` has held for `after` sets its `set`
//      values, else its `otherwise` values;
//   3. follow: a first-order lag toward the target while `when` holds, toward 0 otherwise;
//   4. integrate: += rate x dt, within [min, max];
//   5. the active faults' values (a signal a fault set returns, once no fault sets it, to
//      what steps 2-4 last gave it, else to its start value);
// each later write of a signal wins, and each written signal is encoded once (clamped to
// its DBC range, through the bus' bridge binding). All of it reads the values sampled in 1:
// a rule does not see what an earlier rule set in the same step. A rule that sets a followed
// or integrated signal restarts that lag or integral from the value it set.
//
//   auto modelResult = ecusim::GenericModel::create(bus, simConfig);
//   model.receive(frame, atNs);   // a VCU frame (J1939-76 pairs judged first)
//   model.step(nowNs);            // every tick
//   bus.sendDue(nowNs, send);

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/config/simulation.hpp"
#include "safety_pairs.hpp"
#include "virtual_bus.hpp"

namespace openvcu::ecusim {

/// @note restricted thread-safe: one thread (the simulation's). receive() and step() are
///       noexcept and allocate nothing.
class GenericModel {
 public:
  /// Errors name the JSON path of a signal the bus cannot carry.
  static Result<GenericModel> create(VirtualBus& bus, const config::SimConfig& config);

  /// A VCU frame: the configured J1939-76 pairs judge it first (a refused SDM is not used).
  void receive(const can::Frame& frame, std::int64_t atNs) noexcept;
  /// Advances the rules, follow and integrate to `nowNs` and writes the results.
  void step(std::int64_t nowNs) noexcept;

  /// The fault named `name` in the file, or empty.
  [[nodiscard]] std::optional<std::size_t> faultIndex(std::string_view name) const noexcept;
  [[nodiscard]] std::size_t faultCount() const noexcept { return m_active.size(); }
  [[nodiscard]] const std::string& faultName(std::size_t index) const noexcept { return m_rules->faults[index].name; }
  void setFault(std::size_t index, bool active) noexcept { m_active[index] = active ? 1 : 0; }
  [[nodiscard]] bool fault(std::size_t index) const noexcept { return m_active[index] != 0; }

  [[nodiscard]] const SafetyStats& safety() const noexcept { return m_pairs.stats(); }
  [[nodiscard]] bool checksPairs() const noexcept { return !m_pairs.empty(); }
  [[nodiscard]] std::optional<j1939::SafetyResult> takeSafetyChange() noexcept { return m_pairs.takeChange(); }

  /// The value `key` had at the last step's sampling (tests); NaN when none or unknown.
  [[nodiscard]] double sampled(std::string_view key) const noexcept;

 private:
  static constexpr std::int64_t NOT_HOLDING = std::numeric_limits<std::int64_t>::min();

  GenericModel(VirtualBus& bus, const config::SimConfig& config)
      : m_bus(&bus), m_rules(&config.rules), m_pairs(config.safety) {}
  bool holds(std::uint32_t node, std::int64_t nowNs) noexcept;
  bool evaluate(std::uint32_t node, std::int64_t nowNs) noexcept;
  void write(std::uint32_t slot, double value) noexcept;
  void writeAll(const std::vector<config::SimAssignment>& values) noexcept;
  [[nodiscard]] double startValue(std::uint32_t slot) const noexcept;

  VirtualBus* m_bus;
  const config::SimRules* m_rules;
  SafetyPairs m_pairs;
  std::vector<bridge::SignalRef> m_refs;  ///< by SimRules::signals index
  std::vector<double> m_sampled;          ///< step 1's values
  std::vector<double> m_written;          ///< this step's writes ...
  std::vector<std::uint8_t> m_isWritten;  ///< ... and which slots have one
  std::vector<std::uint8_t> m_byRule;     ///< ... by a rule (restarts a lag or integral)
  std::vector<std::int64_t> m_timers;     ///< `for` timers: since when the node holds
  std::vector<std::int64_t> m_ruleSince;  ///< since when each rule's `when` holds
  std::vector<double> m_followState;
  std::vector<double> m_integrateState;
  std::vector<std::uint8_t> m_active;     ///< by fault index
  std::vector<double> m_lastNormal;       ///< the last value written by steps 2-4 (else the start value)
  std::vector<std::uint8_t> m_faultTouched;  ///< some fault sets this slot
  std::int64_t m_lastStepNs{NOT_HOLDING};
};

}  // namespace openvcu::ecusim
