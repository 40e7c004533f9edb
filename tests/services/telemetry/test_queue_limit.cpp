// vcu-telemetry's disk queue at its limit with a real mosquitto (issue 25: "the disk queue at
// its limit drops oldest first and says so"), inside tests/harness/run_isolated.sh:
//   1. broker up, the real vcu-telemetry with maxQueueMB 1 (1 MiB, segments of 64 KiB) and
//      20 signals the test writes at 50 Hz (10 Hz each in telemetry.json): a subscriber sees
//      the first records live;
//   2. the writer pauses, vcu-telemetry is stopped (SIGTERM) once its last records were
//      confirmed, the broker is stopped: the outage begins;
//   3. the queue is filled to just below its limit with backlog records (the test appends
//      them through DiskQueue, as the bridge would during a long outage: with maxQueueMB 1 a
//      tick's batch must fit one 64 KiB segment, so vcu-telemetry alone would need about 20 s
//      of outage to fill 1 MiB, and its reconnect backoff up to 16 s more after it);
//   4. vcu-telemetry starts again on that queue with the broker still down and the writer
//      going on: its ticks take the queue past the limit, so whole segments go, oldest first;
//      it logs the dropped range;
//   5. the broker comes back: the subscriber sees a gap in seq exactly where the dropped
//      records were (from the one after the last it saw to the last dropped), health carries
//      the same ranges, and every record after the gap arrives in order, without another gap.
#include <doctest/doctest.h>
#include <mosquitto.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <thread>

#include "broker_fixture.hpp"
#include "disk_queue.hpp"
#include "harness/harness.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/signals/table.hpp"
#include "skip.hpp"

namespace {

using namespace openvcu;
using namespace std::chrono_literals;
using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr int PORT = 1883;
constexpr const char* VEHICLE = "hhea-limit";
constexpr int MAX_QUEUE_MB = 1;
constexpr std::uint64_t MAX_QUEUE_BYTES = std::uint64_t{MAX_QUEUE_MB} << 20;
constexpr std::size_t SIGNAL_COUNT = 20;
constexpr auto WRITE_PERIOD = 20ms;
/// Backlog records: about 1 KiB each, appended 16 to a batch, up to this far below the limit.
constexpr std::size_t BACKLOG_RECORD_BYTES = 1000;
constexpr std::size_t BACKLOG_BATCH = 16;
constexpr std::uint64_t BACKLOG_MARGIN = 2048;

using telemetry_test::Message;
using telemetry_test::Subscriber;
using telemetry_test::writeFile;

/// A record of the stream: not a retained copy given again at a (re)subscription.
bool hasSeq(const Message& message) {
  return !message.retained && message.body.is_object() && message.body.contains("seq");
}

std::uint64_t maxSeq(const std::vector<Message>& messages) {
  std::uint64_t max = 0;
  for (const Message& message : messages) {
    if (hasSeq(message)) max = std::max(max, message.body["seq"].get<std::uint64_t>());
  }
  return max;
}

/// The drop ranges the health messages report: first -> last.
std::map<std::uint64_t, std::uint64_t> reportedDrops(const std::vector<Message>& messages) {
  std::map<std::uint64_t, std::uint64_t> drops;
  for (const Message& message : messages) {
    if (!message.topic.ends_with("/health")) continue;
    for (const Json& drop : message.body["queue"]["drops"]) {
      drops[drop["first"].get<std::uint64_t>()] = drop["last"].get<std::uint64_t>();
      CHECK(drop["records"].get<std::uint64_t>() ==
            drop["last"].get<std::uint64_t>() - drop["first"].get<std::uint64_t>() + 1);
    }
  }
  return drops;
}

}  // namespace

TEST_CASE(
    "vcu-telemetry's queue at its limit (#25): oldest records dropped first, reported in health and the log, the "
    "consumer sees exactly that gap and everything after in order") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  const std::string bin = OPENVCU_BINARY_DIR "/bin";
  if (!fs::exists("/usr/sbin/mosquitto"))
    OPENVCU_SKIP("skipped: needs mosquitto (Debian's mosquitto package; scripts/install-deps.sh)");
  harness::Harness sut;
  const fs::path work = fs::temp_directory_path() / "telemetry-queue-limit";  // the sandbox's own /tmp
  fs::remove_all(work);
  fs::create_directories(work / "vehicle");
  fs::create_directories(work / "broker");
  const fs::path queueFolder = work / "queue";

  // the broker: anonymous on loopback; persistence keeps the subscriber's session over the outage;
  // no limit on the messages it holds for that session (the drain is larger than the default 1000)
  writeFile(work / "broker/mosquitto.conf",
            "listener " + std::to_string(PORT) +
                " 127.0.0.1\nallow_anonymous true\npersistence true\npersistence_location " +
                (work / "broker").string() + "/\nmax_queued_messages 0\nuser root\nlog_dest stdout\n");
  const harness::ProcessSpec brokerSpec{
      .name = "mosquitto", .argv = {"/usr/sbin/mosquitto", "-c", (work / "broker/mosquitto.conf").string()}};

  // the vehicle: a copy of config/hhea, telemetry.json with a 1 MiB queue and 20 signals
  for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config/hhea")) {
    if (entry.is_regular_file()) fs::copy_file(entry.path(), work / "vehicle" / entry.path().filename());
  }
  const std::string vehiclePath = (work / "vehicle/vehicle.json").string();
  auto vehicle = config::loadVehicleConfig(vehiclePath);
  REQUIRE_STATUS(vehicle);
  auto catalog = config::buildCatalog(*vehicle);
  REQUIRE_STATUS(catalog);
  std::vector<signals::SignalIndex> written;
  Json signalList = Json::array();
  for (signals::SignalIndex i = 0; i < catalog->size() && written.size() < SIGNAL_COUNT; ++i) {
    const signals::SignalInfo& info = (*catalog)[i];
    if (info.kind != signals::SignalKind::Bus || info.direction != signals::SignalDirection::Received ||
        info.maximum - info.minimum < 1)
      continue;
    written.push_back(i);
    signalList.push_back({{"name", info.key}, {"maxRateHz", 10}, {"deadband", 0}});
  }
  REQUIRE(written.size() == SIGNAL_COUNT);
  writeFile(work / "vehicle/telemetry.json", Json{{"broker", "mqtt://127.0.0.1:" + std::to_string(PORT)},
                                                  {"vehicleId", VEHICLE},
                                                  {"queueFolder", queueFolder.string()},
                                                  {"maxQueueMB", MAX_QUEUE_MB},
                                                  {"signals", signalList}}
                                                 .dump(2));
  auto table = signals::SignalTable::open(*catalog, vehicle->instance);
  REQUIRE_STATUS(table);

  // the writer: every signal a new value every 20 ms, unless paused
  std::atomic<bool> paused{false};
  telemetry_test::PeriodicWriter writer(WRITE_PERIOD, [&](int step) {
    if (!paused) {
      const std::int64_t now = clock::monotonicNs();
      for (std::size_t i = 0; i < written.size(); ++i) {
        table->writeBus(written[i], static_cast<double>((step + static_cast<int>(i)) % 100), now, 0xF3,
                        signals::Quality::Valid);
      }
    }
  });

  // 1. live: the first records reach the subscriber
  auto broker = sut.start(brokerSpec);
  REQUIRE_STATUS(broker);
  Subscriber watcher("telemetry-limit-watcher", true, nullptr, nullptr, PORT);
  bool connected = false;
  for (int attempt = 0; attempt < 50 && !(connected = watcher.connect()); ++attempt) std::this_thread::sleep_for(100ms);
  REQUIRE_MESSAGE(connected, "the broker did not accept the watcher");
  const harness::ProcessSpec bridgeSpec{
      .name = "vcu-telemetry", .argv = {bin + "/vcu-telemetry", "--config", vehiclePath}, .notifyReadiness = true};
  auto bridge = sut.start(bridgeSpec);
  REQUIRE_STATUS(bridge);
  REQUIRE(watcher.waitFor([](const std::vector<Message>& messages) { return maxSeq(messages) >= 3; }, 10s));

  // 2. quiet, so every record made is confirmed before the stop; then the outage
  paused = true;
  std::this_thread::sleep_for(1500ms);  // the last tick with samples goes out and is acknowledged
  REQUIRE(sut.stop(**bridge).has_value());
  const std::uint64_t lastBefore = maxSeq(watcher.messages());
  REQUIRE(sut.stop(**broker).has_value());  // SIGTERM: the broker saves the subscriber's session

  // 3. the backlog of the outage, up to just below the limit
  std::uint64_t backlogFirst = 0;
  std::uint64_t backlogLast = 0;
  {
    auto queue = telemetry::DiskQueue::open({.folder = queueFolder.string(), .maxBytes = MAX_QUEUE_BYTES});
    REQUIRE_STATUS(queue);
    MESSAGE("after the live part: " << queue->stats().pendingRecords
                                    << " record(s) pending, the subscriber saw up to seq " << lastBefore);
    backlogFirst = queue->stats().nextSequence;
    const std::int64_t t = clock::realtimeNs() / 1'000'000;
    for (;;) {
      const telemetry::QueueStats stats = queue->stats();
      if (stats.diskBytes + BACKLOG_MARGIN >= MAX_QUEUE_BYTES) break;
      const std::uint64_t room = MAX_QUEUE_BYTES - BACKLOG_MARGIN - stats.diskBytes;
      const std::size_t count = std::min<std::uint64_t>(BACKLOG_BATCH, room / (BACKLOG_RECORD_BYTES + 64));
      if (count == 0) break;
      std::vector<std::string> batch;
      for (std::size_t i = 0; i < count; ++i) {
        std::string record = "signals\n{\"v\":1,\"seq\":" + std::to_string(stats.nextSequence + i) +
                             ",\"t\":" + std::to_string(t) + ",\"backlog\":\"";
        record.append(BACKLOG_RECORD_BYTES - record.size(), 'x');
        record += "\"}";
        batch.push_back(std::move(record));
      }
      const std::vector<std::string_view> views(batch.begin(), batch.end());
      REQUIRE_STATUS(queue->appendBatch(views));
    }
    REQUIRE(queue->stats().droppedRecords == 0);
    backlogLast = queue->stats().nextSequence - 1;
    MESSAGE("backlog: seq " << backlogFirst << ".." << backlogLast << ", " << queue->stats().diskBytes << " of "
                            << MAX_QUEUE_BYTES << " bytes");
  }

  // 4. the bridge again, the broker still down: its ticks pass the limit
  paused = false;
  auto bridgeAgain = sut.start(bridgeSpec);
  REQUIRE_STATUS(bridgeAgain);
  std::string dropLine;
  for (int attempt = 0; attempt < 100 && dropLine.empty(); ++attempt) {
    std::this_thread::sleep_for(100ms);
    const std::string output = (*bridgeAgain)->output();
    if (const auto at = output.find("telemetry queue full: dropped records "); at != std::string::npos) {
      dropLine = output.substr(at, output.find('\n', at) - at);
    }
  }
  REQUIRE_MESSAGE(!dropLine.empty(), (*bridgeAgain)->output());
  std::smatch logged;
  REQUIRE(std::regex_search(dropLine, logged, std::regex("dropped records ([0-9]+)\\.\\.([0-9]+)")));
  const std::uint64_t loggedFirst = std::stoull(logged[1]);
  const std::uint64_t loggedLast = std::stoull(logged[2]);
  MESSAGE("log: " << dropLine);
  CHECK_MESSAGE(loggedFirst == lastBefore + 1, "the oldest record the subscriber had not seen goes first");
  CHECK(loggedLast < backlogLast);      // whole oldest segments, not the newest records
  std::this_thread::sleep_for(1200ms);  // the next tick's health carries the drop

  // 5. the broker back
  const std::int64_t backMs = clock::realtimeNs() / 1'000'000;
  auto brokerAgain = sut.start(brokerSpec);
  REQUIRE_STATUS(brokerAgain);
  // until a record made after the broker returned arrives (the drain is done by then: it is in order)
  REQUIRE(watcher.waitFor(
      [&](const std::vector<Message>& messages) {
        return std::any_of(messages.begin(), messages.end(), [&](const Message& m) {
          return hasSeq(m) && m.body["t"].get<std::int64_t>() > backMs + 1000;
        });
      },
      20s));
  const auto messages = watcher.messages();

  // health: the drops as ranges, the first one where the log says
  const auto drops = reportedDrops(messages);
  REQUIRE(!drops.empty());
  CHECK(drops.begin()->first == loggedFirst);
  CHECK(drops.at(loggedFirst) == loggedLast);
  std::uint64_t droppedLast = 0;
  std::uint64_t expectedFirst = drops.begin()->first;
  for (const auto& [first, last] : drops) {
    CHECK_MESSAGE(first == expectedFirst,
                  "the drops are contiguous, oldest first: " << first << " after " << expectedFirst - 1);
    expectedFirst = last + 1;
    droppedLast = last;
  }
  const auto health =
      std::find_if(messages.rbegin(), messages.rend(), [](const Message& m) { return m.topic.ends_with("/health"); });
  REQUIRE(health != messages.rend());
  CHECK(health->body["queue"]["dropped"].get<std::uint64_t>() >= loggedLast - loggedFirst + 1);

  // the consumer's view: first arrivals in order; the one gap is exactly the dropped range
  std::vector<std::uint64_t> firstArrivals;
  std::set<std::uint64_t> distinct;
  for (const Message& message : messages) {
    if (!hasSeq(message)) continue;
    const std::uint64_t seq = message.body["seq"].get<std::uint64_t>();
    if (distinct.insert(seq).second) firstArrivals.push_back(seq);
  }
  CHECK(std::is_sorted(firstArrivals.begin(), firstArrivals.end()));
  std::vector<std::pair<std::uint64_t, std::uint64_t>> gaps;  // missing first..last
  for (auto it = std::next(distinct.begin()); it != distinct.end(); ++it) {
    if (*it != *std::prev(it) + 1) gaps.emplace_back(*std::prev(it) + 1, *it - 1);
  }
  REQUIRE_MESSAGE(gaps.size() == 1, "one gap in seq, found " << gaps.size());
  CHECK(gaps.front().first == drops.begin()->first);
  CHECK(gaps.front().second == droppedLast);
  CHECK(*distinct.begin() == 1);            // nothing lost before the outage
  CHECK(*distinct.rbegin() > backlogLast);  // the backlog's newest and the live records after it
  for (std::uint64_t seq = droppedLast + 1; seq <= backlogLast; ++seq) {
    CHECK_MESSAGE(distinct.count(seq) == 1, "backlog record " << seq << " after the drop arrived");
  }
  MESSAGE("seen 1.." << lastBefore << " live, dropped " << drops.begin()->first << ".." << droppedLast << " ("
                     << drops.size() << " range(s) in health), then " << droppedLast + 1 << ".." << *distinct.rbegin()
                     << " in order");
}
