#pragma once
// The simulator's J1939-76 receivers for the VCU's safety pairs ("safety" in simulation.json),
// shared by the HHEA VIC and the generic model: CRC, sequence, SHM->SDM time (SRVT) and SHM
// cycle (SCT) through j1939::SafetyPairChecker, taking as the SDM the next frame after the
// SHM with the SDM's PGN, SA and DA whatever its priority, as J1939-76 does.
//
//   SafetyPairs pairs(config.safety);
//   switch (pairs.receive(frame, atNs, false)) {
//     case SafetyPairs::Outcome::Used: bus.receive(frame, atNs); break;   // a good pair's SDM
//     case SafetyPairs::Outcome::NotPaired: bus.receive(frame, atNs); break;  // an ordinary frame
//     default: break;                                                     // an SHM, or an SDM not to use
//   }

#include <cstdint>
#include <optional>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/config/simulation.hpp"
#include "openvcu/j1939/safety.hpp"

namespace openvcu::ecusim {

/// What the pair checks saw, for the heartbeat and the fault events.
struct SafetyStats {
  std::uint64_t ok{};
  std::uint64_t refused{};
  j1939::SafetyResult last{j1939::SafetyResult::Ok};
  j1939::SafetyResult lastRefusal{j1939::SafetyResult::Ok};  ///< the verdict of the last refused pair
};

/// @note restricted thread-safe: one thread (the simulation's); receive() is noexcept and allocates nothing.
class SafetyPairs {
 public:
  enum class Outcome : std::uint8_t {
    NotPaired,  ///< no frame of a configured pair: an ordinary frame
    Header,     ///< an SHM, taken by its receiver
    Used,       ///< the SDM of a good pair: its data may be used
    NotUsed,    ///< an SDM refused, synchronising, before any SHM, or whose SHM another frame took
  };

  explicit SafetyPairs(const std::vector<config::SafetyCheckConfig>& pairs);

  /// Judges `frame` when it belongs to a pair. `otherCrc`: the receiver expects another CRC
  /// (HHEA's fault shm_expectation), so every pair is refused.
  Outcome receive(const can::Frame& frame, std::int64_t atNs, bool otherCrc) noexcept;
  /// Forgets every receiver's history (a woken ECU): SDMs are not judged until the next SHM,
  /// and the pair it heads synchronises.
  void reset() noexcept;

  [[nodiscard]] bool empty() const noexcept { return m_pairs.empty(); }
  [[nodiscard]] const SafetyStats& stats() const noexcept { return m_stats; }
  /// The last verdict (Ok or a refusal; synchronising is none); empty before the first.
  [[nodiscard]] const std::optional<j1939::SafetyResult>& verdict() const noexcept { return m_reported; }
  /// The verdict changed since the previous call (for one fault event per change).
  [[nodiscard]] std::optional<j1939::SafetyResult> takeChange() noexcept;

 private:
  struct Pair {
    j1939::SafetyPairChecker checker;
    std::uint32_t headerId;
    bool awaitingData{};        ///< an SHM came: the next frame with the SDM's PGN, SA and DA is the SDM
    bool headerTakenByOther{};  ///< that frame was not the SDM's identifier: the SDM after it is not judged
    bool headerSeen{};          ///< an SHM came since the start or reset(): SDMs before it are not judged
  };

  std::vector<Pair> m_pairs;
  SafetyStats m_stats;
  std::optional<j1939::SafetyResult> m_reported;
  bool m_changed{};
};

}  // namespace openvcu::ecusim
