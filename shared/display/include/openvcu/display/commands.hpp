#pragma once
// Operator commands and their acknowledgements: the request ids one issuer (an HMI, a
// vcu-web instance) hands out and what became of each request.

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "openvcu/ipc/events.hpp"

namespace openvcu::display {

/// What became of one command.
struct CommandOutcome {
  enum class State : std::uint8_t { Pending, Accepted, Refused, TimedOut };
  State state{State::Pending};
  std::string text;  ///< "accepted by vcu-fsm", "refused by vcu-fsm: <reason>", "no answer within 2.0 s"
};

/// Request ids of one issuer and the answers to them. Ids are unique per issuer: a counter
/// seeded by the caller (from the clock), so a restarted issuer does not reuse the previous
/// ids. Acks for another issuer or an unknown id are ignored.
/// @note not thread-safe: one thread prepares, feeds acks and expires.
class CommandTracker {
 public:
  CommandTracker(std::string issuer, std::int64_t firstId, std::int64_t timeoutNs);
  /// Fills requestId and issuer and remembers the request as pending from `nowNs`.
  void prepare(ipc::CommandRequest& request, std::int64_t nowNs);
  /// The outcome for an ack to one of ours; empty for anyone else's.
  std::optional<std::pair<std::int64_t, CommandOutcome>> onAck(const ipc::CommandAck& ack);
  /// Pending requests whose time ran out, now TimedOut (removed from pending).
  std::vector<std::pair<std::int64_t, CommandOutcome>> expire(std::int64_t nowNs);
  /// Drops a pending request that failed before any answer (not sent, no owner, expired);
  /// true when it was pending.
  bool forget(std::int64_t requestId) { return m_pending.erase(requestId) > 0; }
  /// The monotonic time at which the pending request `requestId` times out (0: not pending).
  [[nodiscard]] std::int64_t deadlineOf(std::int64_t requestId) const noexcept {
    const auto found = m_pending.find(requestId);
    return found == m_pending.end() ? 0 : found->second;
  }
  [[nodiscard]] std::size_t pending() const noexcept { return m_pending.size(); }
  [[nodiscard]] const std::string& issuer() const noexcept { return m_issuer; }

 private:
  std::string m_issuer;
  std::int64_t m_nextId;
  std::int64_t m_timeoutNs;
  std::map<std::int64_t, std::int64_t> m_pending;  ///< id -> deadline
};

}  // namespace openvcu::display
