#pragma once
// One checked command to a running stack, as `vcu signal set` and `vcu schedule ...` send
// it: publish a CommandRequest with a fresh request id on the instance's COMMAND channel
// (LCM), wait for the CommandAck carrying that id, and print the service's verdict.
//
//   ipc::CommandRequest request;
//   request.kind = ipc::CommandKind::ScheduleCycle;
//   request.key = "HC1_Demands";
//   request.value = 50;
//   ExitCode exitCode = sendCommandRequest(stack.config, request, DEFAULT_ACK_TIMEOUT_SECONDS, streams);
//   // out: "accepted" (exit 0) or "refused: <reason>" (exit 1);
//   // err: "vcu: error: no service answered within 2 s" (exit 1)
//
// Local checks (the key exists, the value parses) belong to the caller, before this is
// called: whatever reaches here is sent.

#include <string_view>

#include "cli.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/events.hpp"

namespace openvcu::cli {

/// Who `vcu` says it is in command requests (the ack carries it back).
inline constexpr std::string_view COMMAND_ISSUER = "vcu";

/// How long the commands wait for the answer by default (--timeout).
inline constexpr double DEFAULT_ACK_TIMEOUT_SECONDS = 2.0;

/// Publishes `request` (its kind, key, value and text as given; the request id, issuer and
/// time stamp are filled in here) on `config`'s event bus and waits up to `timeoutSeconds`
/// for its acknowledgement. Prints "accepted" or "refused: REASON" on out; a bus that does
/// not open, a failed send or no answer in time is reported on err.
/// @note blocks up to timeoutSeconds; opens its own LCM connection for the call.
ExitCode sendCommandRequest(const config::VehicleConfig& config, ipc::CommandRequest request, double timeoutSeconds,
                            Streams streams);

}  // namespace openvcu::cli
