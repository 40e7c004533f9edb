// vcu-telemetry's sender against a real mosquitto in the sandbox (issue 25, docs/design/telemetry.md,
// "Store and forward"): a backlog is handed out with pump() called only when wakeFd() turns
// readable (no periodic pump: the broker's PUBACKs pace it), in order, with far fewer wake-ups
// than records; the PUBACKs of records that all fit the window wake nobody (a periodic pump()
// acks them, as vcu-telemetry's 10 ms one does).
// Runs inside tests/harness/run_isolated.sh only (loopback); skipped without mosquitto.

#include <doctest/doctest.h>
#include <poll.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "broker_fixture.hpp"
#include "disk_queue.hpp"
#include "harness/harness.hpp"
#include "openvcu/config/telemetry.hpp"
#include "sender.hpp"
#include "skip.hpp"

namespace {

using namespace openvcu;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

constexpr int PORT = 1883;
constexpr const char* VEHICLE = "drain-01";
constexpr std::size_t BACKLOG = 400;
constexpr std::size_t WINDOW = 20;
constexpr std::size_t STEADY = 5;  ///< fewer than the window: all handed in one pump()

/// true when `fd` turned readable within `timeout`.
bool readable(int fd, std::chrono::milliseconds timeout) {
  pollfd entry{.fd = fd, .events = POLLIN, .revents = 0};
  return ::poll(&entry, 1, static_cast<int>(timeout.count())) == 1 && (entry.revents & POLLIN) != 0;
}

/// `count` records "signals\n{"n":i}" (i from `first`) as one batch.
void append(telemetry::DiskQueue& queue, std::size_t first, std::size_t count) {
  std::vector<std::string> records;
  for (std::size_t i = first; i < first + count; ++i) records.push_back("signals\n{\"n\":" + std::to_string(i) + "}");
  const std::vector<std::string_view> views(records.begin(), records.end());
  REQUIRE(queue.appendBatch(views));
}

}  // namespace

TEST_CASE(
    "vcu-telemetry's sender (#25): the drain is paced by the broker's PUBACKs through wakeFd, in order, "
    "no wake-up while nothing waits") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  if (!fs::exists("/usr/sbin/mosquitto"))
    OPENVCU_SKIP("skipped: needs mosquitto (Debian's mosquitto package; scripts/install-deps.sh)");
  harness::Harness sut;
  const fs::path work = fs::temp_directory_path() / "telemetry-sender";  // the sandbox's own /tmp
  fs::remove_all(work);
  fs::create_directories(work / "broker");
  telemetry_test::writeFile(work / "broker/mosquitto.conf", "listener " + std::to_string(PORT) +
                                                                " 127.0.0.1\nallow_anonymous true\nmax_queued_messages "
                                                                "0\nuser root\nlog_dest stdout\n");
  auto broker = sut.start(
      {.name = "mosquitto", .argv = {"/usr/sbin/mosquitto", "-c", (work / "broker/mosquitto.conf").string()}});
  REQUIRE(broker);
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (!telemetry_test::listening(PORT) && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(50ms);
  REQUIRE(telemetry_test::listening(PORT));
  telemetry_test::Subscriber watcher("drain-watcher", false);
  REQUIRE(watcher.connect());
  REQUIRE(watcher.waitSubscribed(5s));  // its subscription confirmed before the first record

  auto queue = telemetry::DiskQueue::open({.folder = (work / "queue").string(), .maxBytes = 8u << 20});
  REQUIRE(queue);
  append(*queue, 0, BACKLOG);
  config::TelemetryConfig settings;
  settings.vehicleId = VEHICLE;
  settings.brokerUrl = "mqtt://127.0.0.1:" + std::to_string(PORT);
  auto address = config::parseBrokerUrl(settings.brokerUrl);
  REQUIRE(address);
  settings.broker = *address;
  telemetry::SenderOptions options;
  options.maxInFlight = WINDOW;
  auto sender = telemetry::Sender::create(settings, options);
  REQUIRE(sender);
  REQUIRE((*sender)->start());

  // the backlog: pump() only when wakeFd() is readable (the connect, then every half window),
  // until every record is handed
  std::size_t pumps = 0;
  while (queue->stats().pendingRecords > (*sender)->inFlight()) {
    REQUIRE_MESSAGE(readable((*sender)->wakeFd(), 5s),
                    "no wake-up for 5 s with " << queue->stats().pendingRecords << " record(s) waiting");
    REQUIRE((*sender)->pump(*queue));
    ++pumps;
    REQUIRE(pumps <= BACKLOG);
  }
  const std::uint64_t drainWakeUps = (*sender)->wakeUps();
  MESSAGE("drained " << BACKLOG << " records in " << pumps << " pump(s), " << drainWakeUps << " wake-up(s)");
  CHECK(drainWakeUps <= BACKLOG / (WINDOW / 4));  // about one a half window, never one a record
  // the last window's PUBACKs wake nobody (nothing waits behind it); the periodic pump() acks them
  CHECK_FALSE(readable((*sender)->wakeFd(), 1000ms));
  CHECK((*sender)->wakeUps() == drainWakeUps);
  REQUIRE((*sender)->pump(*queue));
  CHECK(queue->stats().pendingRecords == 0);
  CHECK((*sender)->inFlight() == 0);

  // steady state: a batch that fits the window is handed at once; its PUBACKs wake nobody
  append(*queue, BACKLOG, STEADY);
  REQUIRE((*sender)->pump(*queue));
  CHECK((*sender)->inFlight() == STEADY);
  CHECK_FALSE(readable((*sender)->wakeFd(), 1000ms));
  CHECK((*sender)->wakeUps() == drainWakeUps);
  REQUIRE((*sender)->pump(*queue));
  CHECK(queue->stats().pendingRecords == 0);
  CHECK((*sender)->inFlight() == 0);

  // every record arrived once, in order
  const std::string topic = std::string("openvcu/") + VEHICLE + "/signals";
  const auto records = [&](const std::vector<telemetry_test::Message>& messages) {
    std::vector<std::size_t> numbers;
    for (const auto& message : messages) {
      if (message.topic == topic) numbers.push_back(message.body["n"].get<std::size_t>());
    }
    return numbers;
  };
  REQUIRE(watcher.waitFor([&](const auto& messages) { return records(messages).size() >= BACKLOG + STEADY; }, 10s));
  const std::vector<std::size_t> numbers = records(watcher.messages());
  REQUIRE(numbers.size() == BACKLOG + STEADY);
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    if (numbers[i] != i) FAIL("record " << i << " arrived as " << numbers[i]);
  }
}
