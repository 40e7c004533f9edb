#pragma once
// Reading an LCM event log (the events.lcmlog that `vcu record` has lcm-logger write): the
// FSM transitions and faults of any instance (channels ending in _FSM and _FAULT), decoded
// into the plain structs of events.hpp, for the trace report's time axis.
//
//   auto eventsResult = ipc::readEventLog("drive1/events.lcmlog");
//   for (const FsmTransition& t : eventsResult->transitions) lane.add(t.timestampNs, t.toState);
//
// Bad input: a file that is not an LCM log fails with the path and the reason; events that
// do not decode are counted and skipped; at most `maxEvents` of each kind are kept.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "openvcu/core/result.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::ipc {

struct LoggedEvents {
  std::vector<FsmTransition> transitions;  ///< in log order
  std::vector<FaultEvent> faults;          ///< in log order
  std::uint64_t events{};       ///< events read, all channels
  std::uint64_t undecodable{};  ///< _FSM / _FAULT events that did not decode
  std::uint64_t dropped{};      ///< transitions and faults beyond maxEvents
};

/// Reads the LCM log at `path`. Fails when it cannot be opened or its first event cannot be
/// read (not an LCM log).
[[nodiscard]] Result<LoggedEvents> readEventLog(const std::string& path, std::size_t maxEvents = 100'000);

}  // namespace openvcu::ipc
