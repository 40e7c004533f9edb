#pragma once
// One checked command to a running stack, as `vcu signal set` and `vcu schedule ...` send
// it: through the instance's command sockets (ipc::CommandClient: a fresh random request
// id and a deadline), wait for the owning service's CommandAck, and print its verdict.
//
//   ipc::CommandRequest request;
//   request.kind = ipc::CommandKind::ScheduleCycle;
//   request.key = "HC1_Demands";
//   request.value = 50;
//   ExitCode exitCode = sendCommandRequest(stack.config, request, DEFAULT_ACK_TIMEOUT_SECONDS, streams);
//   // out: "accepted" (exit 0) or "refused: <reason>" (exit 1);
//   // err: "vcu: error: no service answered within 2 s; the command expired ..." (exit 1)
//
// Local checks (the key exists, the value parses) belong to the caller, before this is
// called: whatever reaches here is sent.

#include <string>
#include <string_view>

#include "cli.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::cli {

/// Who `vcu` says it is in command requests (the ack carries it back).
inline constexpr std::string_view COMMAND_ISSUER = "vcu";

/// How long the commands wait for the answer by default (--timeout).
inline constexpr double DEFAULT_ACK_TIMEOUT_SECONDS = 2.0;

/// Sends `request` (its kind, key, value and text as given; the request id, deadline, issuer
/// and time stamp are filled in here) to `config`'s instance and waits up to `timeoutSeconds`
/// for the owner's answer; the deadline is the same, so a command not answered in time is
/// never applied later. Prints "accepted" or "refused: REASON" on out; no access to the
/// stack, no owner or no answer in time is reported on err.
/// @note blocks up to timeoutSeconds; connects to the command sockets for the call.
/// `notOwnedHint`, when given, is added to the error when no running service owns the key
/// (e.g. why a received signal cannot be commanded).
ExitCode sendCommandRequest(const config::VehicleConfig& config, ipc::CommandRequest request, double timeoutSeconds,
                            Streams streams, const std::string& notOwnedHint = {});

}  // namespace openvcu::cli
