#include "openvcu/display/commands.hpp"

#include <array>
#include <cstdio>

namespace openvcu::display {

CommandTracker::CommandTracker(std::string issuer, std::int64_t firstId, std::int64_t timeoutNs)
    : m_issuer(std::move(issuer)), m_nextId(firstId > 0 ? firstId : 1), m_timeoutNs(timeoutNs) {}

void CommandTracker::prepare(ipc::CommandRequest& request, std::int64_t nowNs) {
  request.requestId = m_nextId++;
  request.issuer = m_issuer;
  m_pending[request.requestId] = nowNs + m_timeoutNs;
}

std::optional<std::pair<std::int64_t, CommandOutcome>> CommandTracker::onAck(const ipc::CommandAck& ack) {
  if (ack.issuer != m_issuer) return std::nullopt;
  const auto it = m_pending.find(ack.requestId);
  if (it == m_pending.end()) return std::nullopt;
  m_pending.erase(it);
  CommandOutcome outcome;
  if (ack.accepted) {
    outcome.state = CommandOutcome::State::Accepted;
    outcome.text = "accepted by " + ack.responder;
  } else {
    outcome.state = CommandOutcome::State::Refused;
    outcome.text = "refused by " + ack.responder + ": " + ack.reason;
  }
  return std::make_pair(ack.requestId, std::move(outcome));
}

std::vector<std::pair<std::int64_t, CommandOutcome>> CommandTracker::expire(std::int64_t nowNs) {
  std::vector<std::pair<std::int64_t, CommandOutcome>> expired;
  for (auto it = m_pending.begin(); it != m_pending.end();) {
    if (nowNs >= it->second) {
      std::array<char, 64> text{};
      std::snprintf(text.data(), text.size(), "no answer within %.1f s", static_cast<double>(m_timeoutNs) / 1e9);
      expired.emplace_back(it->first, CommandOutcome{CommandOutcome::State::TimedOut, text.data()});
      it = m_pending.erase(it);
    } else {
      ++it;
    }
  }
  return expired;
}

}  // namespace openvcu::display
