#include "command_request.hpp"

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "diagnostics.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

ExitCode sendCommandRequest(const config::VehicleConfig& config, ipc::CommandRequest request, double timeoutSeconds,
                            Streams streams, const std::string& notOwnedHint) {
  auto clientResult = ipc::CommandClient::connect(config.instance);
  if (!clientResult) {
    reportError(streams.err, clientResult.error().message);
    return ExitCode::Failure;
  }
  request.timestampNs = 0;  // stamped when encoded
  request.issuer = std::string(COMMAND_ISSUER);
  const auto timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(timeoutSeconds));
  auto answer = clientResult->send(std::move(request), timeout);
  if (!answer) {
    const std::string& message = answer.error().message;
    const bool notOwned = message.starts_with("no running service answers");
    reportError(streams.err, notOwned && !notOwnedHint.empty() ? message + "; " + notOwnedHint : message);
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
