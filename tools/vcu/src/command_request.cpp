#include "command_request.hpp"

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "diagnostics.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

ExitCode sendCommandRequest(const config::VehicleConfig& config, ipc::CommandRequest request, double timeoutSeconds,
                            Streams streams) {
  auto eventsResult = ipc::EventBus::open(config.lcmUrl, config.instance);
  if (!eventsResult) {
    reportError(streams.err, eventsResult.error().message);
    return ExitCode::Failure;
  }
  ipc::EventBus& events = *eventsResult;
  request.timestampNs = 0;  // stamped when published
  request.requestId = ipc::randomRequestId();
  request.issuer = std::string(COMMAND_ISSUER);
  std::optional<ipc::CommandAck> answer;
  auto subscribed = events.onAck([&](const ipc::CommandAck& ack) {
    if (!answer && ack.requestId == request.requestId && ack.issuer == request.issuer) answer = ack;
  });
  if (!subscribed) {
    reportError(streams.err, subscribed.error().message);
    return ExitCode::Failure;
  }
  if (!events.publish(request)) {
    reportError(streams.err, "cannot send the command on " + events.channel(ipc::EventKind::Command));
    return ExitCode::Failure;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                               std::chrono::duration<double>(timeoutSeconds));
  while (!answer) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    if (events.handle(left) == ipc::HandleResult::Failed) break;
  }
  if (!answer) {
    reportError(streams.err, "no service answered within " + formatNumber(timeoutSeconds) + " s");
    return ExitCode::Failure;
  }
  if (answer->accepted) {
    streams.out.write("accepted\n");
    return ExitCode::Ok;
  }
  streams.out.write("refused: " + answer->reason + "\n");
  return ExitCode::Failure;
}

}  // namespace openvcu::cli
