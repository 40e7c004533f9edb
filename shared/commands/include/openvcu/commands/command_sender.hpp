#pragma once
// One checked command sent to the running stack and its outcome, the way vcu-web (POST
// /api/command) and vcu-telemetry (remote commands) send theirs: a fresh ipc::CommandClient
// to the instance's command sockets, the request, the owner's CommandAck or why none came.
// The owning service decides (the FSM stays the authority); this only carries the answer back.
//
//   auto outcome = commands::sendCommand("hhea", request, std::chrono::seconds(2));   // blocks
//   outcome.verdict() -> "accepted by vcu-fsm" | "refused by vcu-fsm: value 7 is outside the range [0, 1]"
//                      | "the stack is not reachable: ..." | "no service answered within 2 s; ..."

#include <chrono>
#include <string>
#include <string_view>

#include "openvcu/ipc/events.hpp"

namespace openvcu::commands {

/// How one command ended.
struct CommandOutcome {
  enum class Kind {
    Answered,      ///< the owner decided: `ack` (accepted or refused)
    NotReachable,  ///< no command socket could be used (no stack, no access): `error`
    NotOwned,      ///< every service answered "not mine": `error`
    NoAnswer,      ///< nobody decided by the deadline; nothing was or will be applied: `error`
  };
  Kind kind{Kind::NoAnswer};
  ipc::CommandAck ack;
  std::string error;

  [[nodiscard]] bool accepted() const noexcept { return kind == Kind::Answered && ack.accepted; }
  /// One line: "accepted by vcu-fsm", "refused by vcu-fsm: <reason>", "the stack is not reachable: ...", the error.
  [[nodiscard]] std::string verdict() const;
};

/// Connects to every command socket of `instance`, sends `request` (its issuer, timestamp and,
/// when set, deadline as given) and waits for the owner's answer up to `timeout` or the
/// request's deadline.
/// @note blocks up to `timeout`: call it on a worker thread (commands::Worker), never on a
///       loop thread; thread-safe (each call has a connection of its own).
CommandOutcome sendCommand(std::string_view instance, const ipc::CommandRequest& request,
                           std::chrono::nanoseconds timeout);

}  // namespace openvcu::commands
