// vcu-fixture-service: a TEST-ONLY service, never installed or shipped. It stands in for
// the real services (which arrive in later issues) so that tests can drive `vcu` and the
// harness against a real running process built on openvcu::service:
//   - answers operator commands for every "internal." key through the CommandHandler
//     (heartbeat slots refused by its veto), writing the signal table;
//   - counts frames arriving on each configured bus's rx stream (the loop's iceoryx back
//     end; --no-frames runs without iox-roudi);
//   - heartbeats on LCM and in "internal.service.fixture.heartbeat" (declared by the test
//     configuration tests/data/integration/vehicle.json);
//   - READY=1 / STOPPING=1 on NOTIFY_SOCKET, exit 0 on SIGTERM.
// It is also the shape of a real service's main.cpp: options, open, policy, run.

#include <deque>

#include "openvcu/config/services.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/service/service.hpp"

namespace ipc = openvcu::ipc;
namespace service = openvcu::service;

namespace {

constexpr openvcu::signals::WriterId FIXTURE_WRITER = 0xF0;  // 240: outside the real services' ids

std::optional<std::string> refuseHeartbeats(const ipc::CommandRequest& /*request*/,
                                            const openvcu::signals::SignalInfo& signal) {
  if (signal.key.starts_with("internal.service.")) return "heartbeat counters are written by their service only";
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  service::ServiceInfo info{.name = "fixture",
                            .program = "vcu-fixture-service",
                            .description = "TEST ONLY: answers commands for internal.* keys and heartbeats",
                            .version = {},
                            .writerId = FIXTURE_WRITER,
                            .usesFrameStreams = true};
  bool noFrames = false;
  bool quiet = false;
  std::string as;
  service::CommandLine commandLine(info);
  commandLine.addFlag("--no-frames", noFrames, "do not register with iox-roudi (no frame streams)");
  commandLine.addFlag("--quiet", quiet, "answer no commands (e.g. with --as, when the real owner answers)");
  commandLine.addOption("--as", as, "heartbeat as this service (e.g. fsm: a stand-in command writer)");
  if (const auto maybeExit = commandLine.parseOrExit(argc, argv)) return *maybeExit;
  info.usesFrameStreams = !noFrames;
  if (!as.empty()) {
    info.name = as;
    // a stand-in writes as the service it stands in for (config/services.hpp)
    if (const auto* known = openvcu::config::findService(as)) info.writerId = known->writer;
  }

  auto serviceResult = service::Service::open(info, commandLine.options());
  if (!serviceResult) return service::reportStartupError(info, serviceResult.error());
  service::Service& runtime = **serviceResult;

  service::CommandPolicy policy = service::CommandPolicy::byPrefix("internal.");
  policy.veto = refuseHeartbeats;
  if (auto answering = quiet ? openvcu::Status{} : runtime.answerCommands(std::move(policy)); !answering) {
    return service::reportStartupError(info, answering.error());
  }

  std::deque<ipc::FrameSubscriber> subscribers;  // deque: the loop keeps their addresses
  service::CounterRef framesRx = runtime.addCounter("frames_rx");
  for (std::size_t i = 0; info.usesFrameStreams && i < runtime.config().buses.size(); ++i) {
    auto subscriberResult =
        ipc::FrameSubscriber::create({runtime.instance(), runtime.config().buses[i].name, ipc::FrameStream::Received});
    if (!subscriberResult) return service::reportStartupError(info, subscriberResult.error());
    ipc::FrameSubscriber& subscriber = subscribers.emplace_back(std::move(*subscriberResult));
    auto added = runtime.loop().addSubscriber(subscriber, [&subscriber, framesRx]() mutable {
      while (subscriber.take()) framesRx.increment();
    });
    if (!added) return service::reportStartupError(info, added.error());
  }
  return runtime.run();
}
