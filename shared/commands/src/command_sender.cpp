#include "openvcu/commands/command_sender.hpp"

#include "openvcu/ipc/command_socket.hpp"

namespace openvcu::commands {

std::string CommandOutcome::verdict() const {
  switch (kind) {
    case Kind::Answered:
      return ack.accepted ? "accepted by " + ack.responder : "refused by " + ack.responder + ": " + ack.reason;
    case Kind::NotReachable:
      return "the stack is not reachable: " + error;
    case Kind::NotOwned:
    case Kind::NoAnswer:
      break;
  }
  return error;
}

CommandOutcome sendCommand(std::string_view instance, const ipc::CommandRequest& request,
                           std::chrono::nanoseconds timeout) {
  auto client = ipc::CommandClient::connect(instance);
  if (!client)
    return CommandOutcome{.kind = CommandOutcome::Kind::NotReachable, .ack = {}, .error = client.error().message};
  auto answer = client->send(request, timeout);
  if (answer) return CommandOutcome{.kind = CommandOutcome::Kind::Answered, .ack = std::move(*answer), .error = {}};
  // CommandClient::send says "no running service answers for '<key>' (...: not theirs)" when
  // every service disowned the key; anything else is a timeout
  const bool unowned = answer.error().message.find("no running service answers for") != std::string::npos;
  return CommandOutcome{.kind = unowned ? CommandOutcome::Kind::NotOwned : CommandOutcome::Kind::NoAnswer,
                        .ack = {},
                        .error = answer.error().message};
}

}  // namespace openvcu::commands
