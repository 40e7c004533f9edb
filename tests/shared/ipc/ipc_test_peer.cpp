// The other process of the two-process IPC tests (started by test_ipc inside the sandbox).
//
//   ipc_test_peer publish-frames INSTANCE BUS COUNT
//       registers with RouDi, waits for a subscriber, publishes COUNT frames losslessly
//       (frame.id = i % 0x800, data[0..7] = i little-endian), prints "SENDER <id>" first.
//   ipc_test_peer echo-events URL INSTANCE ECHO_INSTANCE COUNT
//       re-publishes every event of INSTANCE on ECHO_INSTANCE and answers each command with
//       an accepted CommandAck on INSTANCE; prints "READY" once subscribed; exits after COUNT
//       events. Exit codes: 0 done, 1 usage, 2 set-up failed, 3 timed out.

#include <time.h>
#include <unistd.h>

#include <charconv>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <string_view>

#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace ipc = openvcu::ipc;
using namespace std::chrono_literals;

namespace {

constexpr auto PEER_TIMEOUT = 30s;

std::int64_t realtimeNs() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

std::optional<std::uint64_t> parseCount(std::string_view text) {
  std::uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

int publishFrames(const std::string& instance, const std::string& bus, std::uint64_t count) {
  const std::string name = "ipc_test_peer-" + std::to_string(::getpid());
  if (auto initResult = ipc::Runtime::init(name, 10s); !initResult) {
    std::cout << "ERROR " << initResult.error().toString() << std::endl;
    return 2;
  }
  auto publisherResult = ipc::FramePublisher::create({instance, bus, ipc::FrameStream::Received},
                                                     ipc::FramePublisherOptions{.waitForSlowSubscribers = true});
  if (!publisherResult) {
    std::cout << "ERROR " << publisherResult.error().toString() << std::endl;
    return 2;
  }
  ipc::FramePublisher& publisher = *publisherResult;
  std::cout << "SENDER " << publisher.senderId() << std::endl;
  if (!publisher.waitForSubscribers(PEER_TIMEOUT)) {
    std::cout << "ERROR no subscriber" << std::endl;
    return 3;
  }
  for (std::uint64_t i = 0; i < count; ++i) {
    ipc::FrameSample sample{};
    sample.busIndex = 1;
    sample.hardwareNs = realtimeNs();
    sample.frame.timestampNs = sample.hardwareNs;
    sample.frame.id = static_cast<std::uint32_t>(i % 0x800);
    sample.frame.length = 8;
    for (std::size_t b = 0; b < 8; ++b) sample.frame.data[b] = static_cast<std::uint8_t>(i >> (8 * b));
    while (!publisher.publish(sample)) {
      // Only when the mempool is exhausted: let the subscriber catch up.
      ::usleep(100);
    }
  }
  std::cout << "DONE " << count << std::endl;
  return 0;
}

int echoEvents(const std::string& url, const std::string& instance, const std::string& echoInstance,
               std::uint64_t count) {
  auto inResult = ipc::EventBus::open(url, instance);
  auto outResult = ipc::EventBus::open(url, echoInstance);
  if (!inResult || !outResult) {
    std::cout << "ERROR " << (!inResult ? inResult.error() : outResult.error()).toString() << std::endl;
    return 2;
  }
  ipc::EventBus& in = *inResult;
  ipc::EventBus& out = *outResult;
  std::uint64_t seen = 0;
  bool ok = true;
  ok = ok && in.onAck([&](const ipc::CommandAck& m) {
                 out.publish(m);
                 ++seen;
               }).ok();
  ok = ok && in.onFsmTransition([&](const ipc::FsmTransition& m) {
                 out.publish(m);
                 ++seen;
               }).ok();
  ok = ok && in.onFault([&](const ipc::FaultEvent& m) {
                 out.publish(m);
                 ++seen;
               }).ok();
  ok = ok && in.onLog([&](const ipc::LogRecord& m) {
                 out.publish(m);
                 ++seen;
               }).ok();
  ok = ok && in.onHeartbeat([&](const ipc::Heartbeat& m) {
                 out.publish(m);
                 ++seen;
               }).ok();
  ok = ok && in.onSnapshot([&](const ipc::SignalSnapshot& m) {
                 out.publish(m);
                 ++seen;
               }).ok();
  if (!ok) {
    std::cout << "ERROR subscribe failed" << std::endl;
    return 2;
  }
  std::cout << "READY" << std::endl;
  const auto deadline = std::chrono::steady_clock::now() + PEER_TIMEOUT;
  while (seen < count) {
    if (std::chrono::steady_clock::now() >= deadline) return 3;
    if (in.handle(100ms) == ipc::HandleResult::Failed) return 2;
  }
  std::cout << "DONE " << seen << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string_view mode = argc > 1 ? argv[1] : "";
  if (mode == "publish-frames" && argc == 5) {
    if (auto count = parseCount(argv[4])) return publishFrames(argv[2], argv[3], *count);
  } else if (mode == "echo-events" && argc == 6) {
    if (auto count = parseCount(argv[5])) return echoEvents(argv[2], argv[3], argv[4], *count);
  }
  std::cerr << "usage: ipc_test_peer publish-frames INSTANCE BUS COUNT\n"
               "       ipc_test_peer echo-events URL INSTANCE ECHO_INSTANCE COUNT\n";
  return 1;
}
