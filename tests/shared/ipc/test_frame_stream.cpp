// Integration tests of the frame streams: a real iox-roudi (config/iceoryx/roudi.toml) and
// real processes, inside the sandbox of run_isolated.sh (ctest runs every case there).

#include <doctest/doctest.h>

#include "skip.hpp"
#include <unistd.h>

#include <filesystem>
#include <map>
#include <thread>

#include "ipc_test_support.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/request_stream.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/ipc/waiter.hpp"

namespace ipc = openvcu::ipc;
namespace ipctest = openvcu::ipctest;
using namespace std::chrono_literals;

namespace {

const std::string ROUDI_CONFIG = std::string(OPENVCU_SOURCE_DIR) + "/config/iceoryx/roudi.toml";
const std::string PEER = OPENVCU_IPC_TEST_PEER;
constexpr std::uint64_t FRAMES_PER_SENDER = 10'000;
constexpr std::uint64_t RX_ID = 1;
constexpr std::uint64_t TX_ID = 2;
constexpr std::uint64_t EVENTS_ID = 3;

/// Starts the sandbox's RouDi and registers this process; false (with a MESSAGE) outside
/// the sandbox.
bool startRoudiAndRuntime() {
  if (!ipctest::isolated()) {
    MESSAGE(ipctest::NOT_ISOLATED_MESSAGE);
    ++openvcu::testing::skippedCases();  // the caller returns: the case is skipped
    return false;
  }
  REQUIRE_MESSAGE(ipctest::startIsolatedRoudi(ROUDI_CONFIG), "iox-roudi did not become ready, see /tmp/iox-roudi.log");
  auto initResult = ipc::Runtime::init("test_ipc-" + std::to_string(::getpid()), 5000ms);
  REQUIRE_MESSAGE(initResult.ok(), (initResult.ok() ? "" : initResult.error().toString()));
  return true;
}

ipc::FrameSample sampleWithId(std::uint32_t id) {
  ipc::FrameSample sample{};
  sample.frame.id = id;
  sample.frame.length = 1;
  sample.frame.data[0] = static_cast<std::uint8_t>(id);
  return sample;
}

/// Publishers and subscribers find each other through RouDi's discovery (~100 ms):
/// wait for the connection, never for a fixed time.
void requireConnected(const ipc::FramePublisher& publisher) {
  REQUIRE_MESSAGE(publisher.waitForSubscribers(5000ms), "subscriber never connected");
}

}  // namespace

TEST_CASE("Runtime::init reports that iox-roudi is not running instead of blocking") {
  if (!ipctest::isolated()) {
    OPENVCU_SKIP(ipctest::NOT_ISOLATED_MESSAGE);
  }
  if (ipc::Runtime::roudiReachable()) {
    OPENVCU_SKIP("skipped: an earlier test case of this process started RouDi");
  }
  const auto start = std::chrono::steady_clock::now();
  auto initResult = ipc::Runtime::init("test_ipc-no-roudi", 200ms);
  const auto elapsed = std::chrono::steady_clock::now() - start;
  REQUIRE_FALSE(initResult.ok());
  CHECK(initResult.error().message.find("iox-roudi is not running") != std::string::npos);
  CHECK(elapsed < 2s);
  CHECK_FALSE(ipc::Runtime::initialized());
}

TEST_CASE("Runtime::init refuses names iceoryx cannot use") {
  auto initResult = ipc::Runtime::init("has/slash");
  REQUIRE_FALSE(initResult.ok());
  CHECK(initResult.error().message.find("invalid iceoryx runtime name") != std::string::npos);
}

TEST_CASE("frames from two publisher processes arrive in order per sender, complete and time-stamped") {
  if (!startRoudiAndRuntime()) return;
  auto subscriberResult =
      ipc::FrameSubscriber::create({"test", "vehicle", ipc::FrameStream::Received},
                                   ipc::FrameSubscriberOptions{.queueCapacity = 256, .blockPublisher = true});
  REQUIRE(subscriberResult.ok());
  ipc::FrameSubscriber& sut = *subscriberResult;
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  REQUIRE(waiterResult->attach(sut, RX_ID).ok());

  const std::string count = std::to_string(FRAMES_PER_SENDER);
  auto first = ipctest::ChildProcess::spawn({PEER, "publish-frames", "test", "vehicle", count});
  auto second = ipctest::ChildProcess::spawn({PEER, "publish-frames", "test", "vehicle", count});
  REQUIRE(first);
  REQUIRE(second);

  struct SenderState {
    std::uint64_t lastSequence{0};
    std::int64_t lastMonotonicNs{0};
    std::uint64_t received{0};
  };
  std::map<std::uint32_t, SenderState> senders;
  std::uint64_t outOfOrder = 0;
  std::uint64_t missingTimestamps = 0;
  std::uint64_t wrongPayload = 0;
  std::uint64_t total = 0;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (total < 2 * FRAMES_PER_SENDER && std::chrono::steady_clock::now() < deadline) {
    for (const std::uint64_t id : waiterResult->waitUntil(deadline)) {
      REQUIRE(id == RX_ID);
      while (auto maybeSample = sut.take()) {
        const ipc::FrameSample& sample = *maybeSample;
        SenderState& sender = senders[sample.senderId];
        if (sample.sequence != sender.lastSequence + 1) ++outOfOrder;
        if (sample.monotonicNs < sender.lastMonotonicNs) ++outOfOrder;
        if (sample.monotonicNs == 0 || sample.hardwareNs == 0) ++missingTimestamps;
        const std::uint64_t index = sample.sequence - 1;
        if (sample.frame.id != index % 0x800 || sample.frame.data[0] != static_cast<std::uint8_t>(index) ||
            sample.frame.data[1] != static_cast<std::uint8_t>(index >> 8) ||
            sample.busNameHash != ipc::fnv1a32("vehicle") || sample.busIndex != 1) {
          ++wrongPayload;
        }
        sender.lastSequence = sample.sequence;
        sender.lastMonotonicNs = sample.monotonicNs;
        ++sender.received;
        ++total;
      }
    }
  }
  CHECK(first->wait(10s) == 0);
  CHECK(second->wait(10s) == 0);
  CHECK(total == 2 * FRAMES_PER_SENDER);
  REQUIRE(senders.size() == 2);
  for (const auto& [senderId, sender] : senders) {
    CHECK(sender.received == FRAMES_PER_SENDER);
    CHECK(sender.lastSequence == FRAMES_PER_SENDER);
  }
  CHECK(outOfOrder == 0);
  CHECK(missingTimestamps == 0);
  CHECK(wrongPayload == 0);
  CHECK_FALSE(sut.hasLostFrames());
  CHECK(sut.rejectedSamples() == 0);
}

TEST_CASE("a full subscriber queue drops the oldest frames and reports the loss") {
  if (!startRoudiAndRuntime()) return;
  constexpr std::uint32_t QUEUE_CAPACITY = 16;
  constexpr std::uint32_t PUBLISHED = 40;
  auto subscriberResult = ipc::FrameSubscriber::create({"test", "lossy", ipc::FrameStream::Sent},
                                                       ipc::FrameSubscriberOptions{.queueCapacity = QUEUE_CAPACITY});
  REQUIRE(subscriberResult.ok());
  auto publisherResult = ipc::FramePublisher::create({"test", "lossy", ipc::FrameStream::Sent});
  REQUIRE(publisherResult.ok());
  requireConnected(*publisherResult);

  for (std::uint32_t i = 0; i < PUBLISHED; ++i) REQUIRE(publisherResult->publish(sampleWithId(i)));

  std::vector<std::uint64_t> sequences;
  while (auto maybeSample = subscriberResult->take()) sequences.push_back(maybeSample->sequence);
  REQUIRE(sequences.size() == QUEUE_CAPACITY);
  CHECK(sequences.front() == PUBLISHED - QUEUE_CAPACITY + 1);
  CHECK(sequences.back() == PUBLISHED);
  CHECK(subscriberResult->hasLostFrames());
  CHECK_FALSE(subscriberResult->hasLostFrames());  // reported once
}

TEST_CASE("a loaned sample is written in place, stamped on publish and released when dropped") {
  if (!startRoudiAndRuntime()) return;
  auto subscriberResult = ipc::FrameSubscriber::create({"test", "loans", ipc::FrameStream::SendRequest});
  REQUIRE(subscriberResult.ok());
  auto publisherResult = ipc::FramePublisher::create({"test", "loans", ipc::FrameStream::SendRequest});
  REQUIRE(publisherResult.ok());
  ipc::FramePublisher& sut = *publisherResult;
  requireConnected(sut);

  {
    auto unpublished = sut.loan();
    REQUIRE(unpublished);
    (*unpublished)->frame.id = 0x7FF;
  }  // released: never delivered, sequence not consumed
  CHECK(sut.nextSequence() == 1);

  auto maybeLoan = sut.loan();
  REQUIRE(maybeLoan);
  maybeLoan->sample().frame.id = 0x18FEF100;
  maybeLoan->sample().frame.flags = openvcu::can::FLAG_EXTENDED;
  maybeLoan->sample().frame.length = 8;
  REQUIRE(sut.publish(std::move(*maybeLoan)));

  const auto received = subscriberResult->take();
  REQUIRE(received);
  CHECK(received->frame.id == 0x18FEF100);
  CHECK(received->frame.extended());
  CHECK(received->sequence == 1);
  CHECK(received->senderId == sut.senderId());
  CHECK(received->busNameHash == ipc::fnv1a32("loans"));
  CHECK(received->monotonicNs > 0);
  CHECK_FALSE(subscriberResult->take());
}

TEST_CASE("at most 8 loans are outstanding per publisher and a failed loan is not fatal") {
  if (!startRoudiAndRuntime()) return;
  auto publisherResult = ipc::FramePublisher::create({"test", "manyloans", ipc::FrameStream::Sent});
  REQUIRE(publisherResult.ok());
  std::vector<ipc::FrameLoan> loans;
  for (int i = 0; i < 8; ++i) {
    auto maybeLoan = publisherResult->loan();
    REQUIRE(maybeLoan);
    loans.push_back(std::move(*maybeLoan));
  }
  CHECK_FALSE(publisherResult->loan());
  loans.pop_back();
  CHECK(publisherResult->loan());
}

TEST_CASE("the waiter reports the subscriber that has data and times out when none has") {
  if (!startRoudiAndRuntime()) return;
  auto rx = ipc::FrameSubscriber::create({"test", "wait", ipc::FrameStream::Received});
  auto tx = ipc::FrameSubscriber::create({"test", "wait", ipc::FrameStream::Sent});
  auto rxPublisher = ipc::FramePublisher::create({"test", "wait", ipc::FrameStream::Received});
  REQUIRE((rx.ok() && tx.ok() && rxPublisher.ok()));
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  ipc::Waiter& sut = *waiterResult;
  REQUIRE(sut.attach(*rx, RX_ID).ok());
  REQUIRE(sut.attach(*tx, TX_ID).ok());
  CHECK_FALSE(sut.attach(*rx, RX_ID).ok());  // already attached
  requireConnected(*rxPublisher);

  const auto start = std::chrono::steady_clock::now();
  CHECK(sut.waitFor(50ms).empty());
  CHECK(std::chrono::steady_clock::now() - start >= 45ms);

  REQUIRE(rxPublisher->publish(sampleWithId(7)));
  const auto ready = sut.waitFor(5s);
  REQUIRE(ready.size() == 1);
  CHECK(ready[0] == RX_ID);
  CHECK(rx->take());
  CHECK(sut.waitFor(0ms).empty());  // drained: level-triggered state is gone

  sut.detach(*rx);
  REQUIRE(rxPublisher->publish(sampleWithId(8)));
  CHECK(sut.waitFor(20ms).empty());
}

TEST_CASE("wake() ends a wait early from another thread") {
  if (!startRoudiAndRuntime()) return;
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  ipc::Waiter& sut = *waiterResult;
  std::thread waker([&sut] {
    std::this_thread::sleep_for(20ms);  // usually lands while the wait blocks; an earlier wake is kept
    sut.wake();
  });
  const auto start = std::chrono::steady_clock::now();
  CHECK(sut.waitFor(10s).empty());
  CHECK(std::chrono::steady_clock::now() - start < 5s);
  waker.join();
}

TEST_CASE("one wait covers frame subscribers and the event bus fd together") {
  if (!startRoudiAndRuntime()) return;
  auto rx = ipc::FrameSubscriber::create({"test", "both", ipc::FrameStream::Received});
  auto rxPublisher = ipc::FramePublisher::create({"test", "both", ipc::FrameStream::Received});
  auto events = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, "test");
  REQUIRE((rx.ok() && rxPublisher.ok()));
  REQUIRE_MESSAGE(events.ok(), (events.ok() ? "" : events.error().toString()));
  int logs = 0;
  REQUIRE(events->onLog([&](const ipc::LogRecord&) { ++logs; }).ok());
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  ipc::Waiter& sut = *waiterResult;
  REQUIRE(sut.attach(*rx, RX_ID).ok());
  REQUIRE(sut.attachFd(events->fileno(), EVENTS_ID).ok());
  CHECK_FALSE(sut.attachFd(events->fileno(), EVENTS_ID).ok());  // duplicate
  requireConnected(*rxPublisher);

  REQUIRE(events->publish(ipc::LogRecord{0, "test", ipc::LogLevel::Info, "hello"}));  // loops back to us
  auto ready = sut.waitFor(5s);
  REQUIRE(ready.size() == 1);
  CHECK(ready[0] == EVENTS_ID);
  CHECK(events->handle(0ms) == ipc::HandleResult::Handled);
  CHECK(logs == 1);

  // Handled: the fd is quiet until the next message, frames are reported on their own.
  CHECK(sut.waitFor(20ms).empty());
  REQUIRE(rxPublisher->publish(sampleWithId(1)));
  ready = sut.waitFor(5s);
  REQUIRE(ready.size() == 1);
  CHECK(ready[0] == RX_ID);
  CHECK(rx->take());

  REQUIRE(events->publish(ipc::LogRecord{0, "test", ipc::LogLevel::Info, "again"}));
  ready = sut.waitFor(5s);
  REQUIRE(ready.size() == 1);
  CHECK(ready[0] == EVENTS_ID);
  CHECK(events->handle(0ms) == ipc::HandleResult::Handled);
  CHECK(logs == 2);
  sut.detachFd(events->fileno());
}

namespace {

/// Threads of this process (each is a /proc/self/task entry).
std::size_t threadCount() {
  std::size_t count = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator("/proc/self/task")) ++count;
  return count;
}

}  // namespace

TEST_CASE("a waiter without fds starts no watcher thread, and the first attachFd starts one") {
  if (!startRoudiAndRuntime()) return;
  auto rx = ipc::FrameSubscriber::create({"test", "threads", ipc::FrameStream::Received});
  REQUIRE(rx.ok());
  int pipeFds[2] = {-1, -1};
  REQUIRE(::pipe(pipeFds) == 0);
  const std::size_t before = threadCount();
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  ipc::Waiter& sut = *waiterResult;

  REQUIRE(sut.attach(*rx, RX_ID).ok());
  CHECK(sut.waitFor(1ms).empty());
  const std::size_t withSubscriber = threadCount();
  REQUIRE(sut.attachFd(pipeFds[0], EVENTS_ID).ok());
  const std::size_t withFd = threadCount();

  CHECK(withSubscriber == before);
  CHECK(withFd == before + 1);
  sut.detachFd(pipeFds[0]);
  ::close(pipeFds[0]);
  ::close(pipeFds[1]);
}

TEST_CASE("an fd left readable is reported again by the next wait, and a handled one is not (#27)") {
  if (!startRoudiAndRuntime()) return;
  int pipeFds[2] = {-1, -1};
  REQUIRE(::pipe(pipeFds) == 0);
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  ipc::Waiter& sut = *waiterResult;
  REQUIRE(sut.attachFd(pipeFds[0], EVENTS_ID).ok());
  const char byte = 'x';
  REQUIRE(::write(pipeFds[1], &byte, 1) == 1);

  const auto first = sut.waitFor(5s);
  REQUIRE(first.size() == 1);
  CHECK(first[0] == EVENTS_ID);
  const auto unhandled = sut.waitFor(5s);  // nothing read: re-armed, reported again
  REQUIRE(unhandled.size() == 1);
  CHECK(unhandled[0] == EVENTS_ID);
  char got = 0;
  REQUIRE(::read(pipeFds[0], &got, 1) == 1);
  const auto start = std::chrono::steady_clock::now();
  CHECK(sut.waitFor(30ms).empty());  // handled: quiet
  CHECK(std::chrono::steady_clock::now() - start >= 25ms);

  sut.detachFd(pipeFds[0]);
  REQUIRE(::write(pipeFds[1], &byte, 1) == 1);
  CHECK(sut.waitFor(20ms).empty());  // detached: never reported
  ::close(pipeFds[0]);
  ::close(pipeFds[1]);
}

// ---- the "req" topic: typed J1939 requests (issue 20) ------------------------------------

TEST_CASE("a J1939 request crosses the req topic typed and stamped, and wakes the waiter") {
  if (!startRoudiAndRuntime()) return;
  constexpr std::uint64_t REQ_ID = 4;
  constexpr std::uint32_t PGN_TIME_DATE = 0xFEE6;  // 65254
  constexpr std::uint8_t VIC_ADDRESS = 0xF3;
  auto subscriberResult = ipc::RequestSubscriber::create("test", "requests");
  REQUIRE(subscriberResult.ok());
  auto publisherResult = ipc::RequestPublisher::create("test", "requests");
  REQUIRE(publisherResult.ok());
  ipc::RequestPublisher& sut = *publisherResult;
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  REQUIRE(waiterResult->attach(*subscriberResult, REQ_ID).ok());
  const auto connectDeadline = std::chrono::steady_clock::now() + 5s;
  while (!sut.hasSubscribers() && std::chrono::steady_clock::now() < connectDeadline) std::this_thread::sleep_for(1ms);
  REQUIRE(sut.hasSubscribers());
  CHECK(sut.topic().toString() == "openvcu/test.requests/req");

  ipc::RequestSample sample{};
  sample.bus = 1;
  sample.pgn = PGN_TIME_DATE;
  sample.requester = VIC_ADDRESS;
  sample.global = true;
  REQUIRE(sut.publish(sample));

  const auto ready = waiterResult->waitFor(5s);
  REQUIRE(ready.size() == 1);
  CHECK(ready[0] == REQ_ID);
  const auto received = subscriberResult->take();
  REQUIRE(received);
  CHECK(received->bus == 1);
  CHECK(received->pgn == PGN_TIME_DATE);
  CHECK(received->requester == VIC_ADDRESS);
  CHECK(received->global);
  CHECK(received->sequence == 1);
  CHECK(received->busNameHash == ipc::fnv1a32("requests"));
  CHECK(received->monotonicNs > 0);
  CHECK_FALSE(subscriberResult->take());
}

TEST_CASE("a frame subscriber on the req topic rejects request samples instead of misreading them") {
  if (!startRoudiAndRuntime()) return;
  auto frames = ipc::FrameSubscriber::create({"test", "mixed", ipc::FrameStream::Request});
  REQUIRE(frames.ok());
  auto publisherResult = ipc::RequestPublisher::create("test", "mixed");
  REQUIRE(publisherResult.ok());
  const auto connectDeadline = std::chrono::steady_clock::now() + 5s;
  while (!publisherResult->hasSubscribers() && std::chrono::steady_clock::now() < connectDeadline) {
    std::this_thread::sleep_for(1ms);
  }
  REQUIRE(publisherResult->hasSubscribers());

  REQUIRE(publisherResult->publish(ipc::RequestSample{}));

  CHECK_FALSE(frames->take());
  CHECK(frames->rejectedSamples() == 1);
}

TEST_CASE("the waiter takes a link's wait handle whole: a subscriber source or an fd") {
  if (!startRoudiAndRuntime()) return;
  constexpr std::uint64_t LINK_ID = 5;
  constexpr std::uint64_t FD_ID = 6;
  auto subscriber = ipc::FrameSubscriber::create({"test", "handles", ipc::FrameStream::Received});
  auto publisher = ipc::FramePublisher::create({"test", "handles", ipc::FrameStream::Received});
  REQUIRE((subscriber.ok() && publisher.ok()));
  auto waiterResult = ipc::Waiter::create();
  REQUIRE(waiterResult.ok());
  ipc::Waiter& sut = *waiterResult;
  int pipeFds[2] = {-1, -1};
  REQUIRE(::pipe(pipeFds) == 0);

  REQUIRE(sut.attachLink(openvcu::can::WaitHandle{-1, &*subscriber}, LINK_ID).ok());
  REQUIRE(sut.attachLink(openvcu::can::WaitHandle{pipeFds[0], nullptr}, FD_ID).ok());
  CHECK_FALSE(sut.attachLink(openvcu::can::WaitHandle{}, FD_ID).ok());  // neither set
  requireConnected(*publisher);

  REQUIRE(publisher->publish(sampleWithId(1)));
  auto ready = sut.waitFor(5s);
  REQUIRE(ready.size() == 1);
  CHECK(ready[0] == LINK_ID);
  REQUIRE(subscriber->take());

  const char byte = 1;
  REQUIRE(::write(pipeFds[1], &byte, 1) == 1);
  ready = sut.waitFor(5s);
  REQUIRE(ready.size() == 1);
  CHECK(ready[0] == FD_ID);

  sut.detachLink(openvcu::can::WaitHandle{pipeFds[0], nullptr});
  sut.detachLink(openvcu::can::WaitHandle{-1, &*subscriber});
  ::close(pipeFds[0]);
  ::close(pipeFds[1]);
}
