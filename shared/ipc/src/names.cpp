// Name rules shared by the two planes: instance and bus names end up in iceoryx ids
// (max 100 chars) and in LCM channel names (regular expressions), so both accept only
// a conservative character set.

#include <cctype>

#include "openvcu/ipc/events.hpp"
#include "openvcu/ipc/topics.hpp"

namespace openvcu::ipc {

namespace {
constexpr std::size_t MAX_NAME_LENGTH = 32;
}

bool isValidName(std::string_view name) noexcept {
  if (name.empty() || name.size() > MAX_NAME_LENGTH) return false;
  for (const char c : name) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

std::string_view channelSuffix(EventKind kind) noexcept {
  switch (kind) {
    case EventKind::Command:
      return "COMMAND";
    case EventKind::Ack:
      return "ACK";
    case EventKind::Fsm:
      return "FSM";
    case EventKind::Fault:
      return "FAULT";
    case EventKind::Log:
      return "LOG";
    case EventKind::Heartbeat:
      return "HEARTBEAT";
    case EventKind::Snapshot:
      return "SNAPSHOT";
    case EventKind::Stats:
      return "STATS";
    case EventKind::Schedule:
      return "SCHEDULE";
    case EventKind::J1939:
      return "J1939";
    case EventKind::Dm1:
      return "DM1";
  }
  return "UNKNOWN";
}

std::string_view claimStateName(ClaimState state) noexcept {
  switch (state) {
    case ClaimState::Off:
      return "off";
    case ClaimState::Claiming:
      return "claiming";
    case ClaimState::Claimed:
      return "claimed";
    case ClaimState::CannotClaim:
      return "cannot claim";
  }
  return "unknown";
}

std::string channelName(std::string_view instance, EventKind kind) {
  std::string channel = "OPENVCU_";
  for (const char c : instance) channel += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  channel += '_';
  channel += channelSuffix(kind);
  return channel;
}

}  // namespace openvcu::ipc
