// `vcu record` and `vcu replay` as processes on two simulated buses (a classic one and a
// CAN FD one), inside the sandbox with the real iox-roudi, LCM and lcm-logger:
//   - the test process sends known frames at known times; the recording holds exactly
//     those frames as candump -L lines (checked against hex written here, not by the
//     project's log writer), with the send times, and the LCM events of the fixture;
//   - the replay puts the same frames back on the buses with the recorded spacing
//     (measured from the sender stamps of an independent listener), twice as fast with
//     --speed 2;
//   - bad input: a missing folder, a malformed line, an unknown bus, an existing recording;
//   - the files stay readable by our own analysis: frames of two senders that reach the
//     recorder out of stamp order are written in time order (`vcu trace stats` sees no
//     step back), a recorder killed by SIGKILL leaves only whole lines, and a recorder
//     started with SIGTERM and SIGINT blocked (a child of vcu-hmi inherits that mask)
//     still ends cleanly on SIGTERM.
// The two-bus configuration is written into the sandbox's /tmp.

#include <doctest/doctest.h>
#include <time.h>

#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/can_links/sim_link.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::size_t VEHICLE_FRAMES = 20;
constexpr std::size_t BODY_FRAMES = 10;
constexpr auto VEHICLE_PERIOD = 20ms;
constexpr auto BODY_PERIOD = 37ms;
/// How far a replayed frame may be from its recorded offset (a shared 2-core machine).
constexpr std::int64_t REPLAY_TOLERANCE_NS = 10 * MS;

/// The test's two-bus configuration in the sandbox's /tmp; the fixture's instance and LCM URL.
fs::path writeConfig() {
  const fs::path folder = fs::temp_directory_path() / "record-config";
  fs::create_directories(folder);
  const fs::path path = folder / "vehicle.json";
  std::ofstream out(path);
  out << R"({"instance": "itest", "node": "VCU", "dbc": ")" << OPENVCU_SOURCE_DIR << R"(/tests/data/config/small.dbc",
  "buses": [
    {"name": "vehicle", "link": "sim:vehicle", "bitrate": 250000, "messages": "all"},
    {"name": "body", "link": "sim:body", "fd": true, "messages": []}
  ]})";
  return path;
}

std::int64_t realtimeNs() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

std::string hex(const can::Frame& frame) {
  static constexpr char DIGITS[] = "0123456789ABCDEF";
  std::string text;
  for (std::size_t i = 0; i < frame.length; ++i) {
    text += DIGITS[frame.data[i] >> 4];
    text += DIGITS[frame.data[i] & 0x0F];
  }
  return text;
}

/// What candump -L writes after "(time) bus ", from can-utils' rules (not the project's writer).
std::string candumpText(const can::Frame& frame) {
  char id[16];
  std::snprintf(id, sizeof id, frame.extended() ? "%08X" : "%03X", frame.id);
  if ((frame.flags & can::FLAG_RTR) != 0) return std::string(id) + "#R" + std::to_string(frame.length);
  if (frame.fd()) {
    const int flags = ((frame.flags & can::FLAG_BRS) != 0 ? 1 : 0) | ((frame.flags & can::FLAG_ESI) != 0 ? 2 : 0);
    return std::string(id) + "##" + std::to_string(flags) + hex(frame);
  }
  return std::string(id) + "#" + hex(frame);
}

can::Frame vehicleFrame(std::size_t i) {
  can::Frame frame{};
  if (i == 5) {
    frame.id = 0x7FF;
    frame.flags = can::FLAG_RTR;
    frame.length = 4;
    return frame;
  }
  if (i % 2 == 0) {
    frame.id = 0x18FEF121;
    frame.flags = can::FLAG_EXTENDED;
    frame.length = 8;
  } else {
    frame.id = 0x123;
    frame.length = static_cast<std::uint8_t>(i % 9);
  }
  for (std::size_t b = 0; b < frame.length; ++b) frame.data[b] = static_cast<std::uint8_t>(0x11 * b + i);
  return frame;
}

can::Frame bodyFrame(std::size_t i) {
  can::Frame frame{};
  if (i % 2 == 0) {
    frame.id = 0x456;
    frame.flags = can::FLAG_FD | can::FLAG_BRS;
    frame.length = 12;
  } else {
    frame.id = 0x1ABCDE00 + static_cast<std::uint32_t>(i);
    frame.flags = can::FLAG_EXTENDED | can::FLAG_FD;
    frame.length = 64;
  }
  for (std::size_t b = 0; b < frame.length; ++b) frame.data[b] = static_cast<std::uint8_t>(0xF0 - b - i);
  return frame;
}

struct Sent {
  std::string bus;
  can::Frame frame;
  std::int64_t beforeNs;  ///< CLOCK_REALTIME just before send()
  std::int64_t afterNs;   ///< and just after
};

/// The test's own node on both buses: it sends and listens.
struct Node {
  std::map<std::string, std::unique_ptr<can::Link>> links;
  Node() {
    if (!ipc::Runtime::initialized()) REQUIRE_STATUS(ipc::Runtime::init("test-record-node", 5s));
    auto vehicle = can::openSimLink("vehicle", can::LinkOptions{});
    REQUIRE_STATUS(vehicle);
    links["vehicle"] = std::move(*vehicle);
    can::LinkOptions fdOptions;
    fdOptions.fd = true;
    auto body = can::openSimLink("body", fdOptions);
    REQUIRE_STATUS(body);
    links["body"] = std::move(*body);
  }

  /// Sends the vehicle frames every 20 ms and the body frames every 37 ms, interleaved,
  /// from absolute deadlines; returns them in send order.
  std::vector<Sent> sendPattern() {
    std::vector<Sent> sent;
    const auto start = std::chrono::steady_clock::now();
    std::size_t vehicleIndex = 0;
    std::size_t bodyIndex = 0;
    while (vehicleIndex < VEHICLE_FRAMES || bodyIndex < BODY_FRAMES) {
      const auto vehicleDue = start + vehicleIndex * VEHICLE_PERIOD;
      const auto bodyDue = start + bodyIndex * BODY_PERIOD;
      const bool vehicleNext = bodyIndex >= BODY_FRAMES || (vehicleIndex < VEHICLE_FRAMES && vehicleDue <= bodyDue);
      std::this_thread::sleep_until(vehicleNext ? vehicleDue : bodyDue);
      const std::string bus = vehicleNext ? "vehicle" : "body";
      const can::Frame frame = vehicleNext ? vehicleFrame(vehicleIndex++) : bodyFrame(bodyIndex++);
      const std::int64_t before = realtimeNs();
      REQUIRE(links[bus]->send(frame) == can::SendStatus::Sent);
      sent.push_back(Sent{bus, frame, before, realtimeNs()});
    }
    return sent;
  }

  /// Everything other nodes sent since the last call: bus -> frames.
  std::map<std::string, std::vector<can::ReceivedFrame>> drain() {
    std::map<std::string, std::vector<can::ReceivedFrame>> heard;
    std::array<can::ReceivedFrame, 64> batch{};
    for (auto& [name, link] : links) {
      while (const std::size_t count = link->receive(batch)) {
        heard[name].insert(heard[name].end(), batch.begin(), batch.begin() + static_cast<std::ptrdiff_t>(count));
        if (count < batch.size()) break;
      }
      CHECK_MESSAGE(link->stats().receiveDropped == 0, ("the listener's queue overflowed on " + name));
    }
    return heard;
  }
};

std::vector<std::string> readLines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// "(1700000000.123456) bus TEXT" -> {time ns, bus, TEXT}; REQUIREs the shape.
struct LogLine {
  std::int64_t timeNs{};
  std::string bus;
  std::string text;
};
LogLine parseLine(const std::string& line) {
  INFO("line: ", line);
  REQUIRE(line.size() > 20);
  REQUIRE(line.front() == '(');
  const std::size_t dot = line.find('.');
  const std::size_t close = line.find(") ");
  REQUIRE(dot != std::string::npos);
  REQUIRE(close == dot + 7);  // exactly 6 decimals, as candump writes
  for (std::size_t i = 1; i < close; ++i) {
    if (i != dot) REQUIRE(std::isdigit(static_cast<unsigned char>(line[i])));
  }
  const std::size_t space = line.find(' ', close + 2);
  REQUIRE(space != std::string::npos);
  LogLine parsed;
  parsed.timeNs = std::stoll(line.substr(1, dot - 1)) * 1'000'000'000 + std::stoll(line.substr(dot + 1, 6)) * 1'000;
  parsed.bus = line.substr(close + 2, space - close - 2);
  parsed.text = line.substr(space + 1);
  return parsed;
}

harness::ProcessSpec recordSpec(const fs::path& folder, const fs::path& config, std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{VCU, "record", folder.string(), "--config", config.string()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return harness::ProcessSpec{.name = "record", .argv = argv, .captureOutput = true};
}

harness::CommandResult replay(harness::Harness& sut, const fs::path& folder, const fs::path& config,
                              std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{VCU, "replay", folder.string(), "--config", config.string()};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return sut.run(argv);
}

/// Polls (50 ms) until `path` contains `text`, up to `timeout`.
bool waitForFileText(const fs::path& path, const std::string& text, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (readFile(path).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(50ms);
  }
  return false;
}

/// The replayed frames (merged over both buses in send-stamp order) against the recording:
/// same frames, and every offset from the first frame equals the recorded one / speed.
void checkReplay(const std::vector<Sent>& sent, std::map<std::string, std::vector<can::ReceivedFrame>> heard,
                 double speed) {
  REQUIRE(heard["vehicle"].size() == VEHICLE_FRAMES);
  REQUIRE(heard["body"].size() == BODY_FRAMES);
  std::map<std::string, std::size_t> next;
  struct Pair {
    std::int64_t recordedNs;
    std::int64_t replayedNs;
  };
  std::vector<Pair> pairs;
  for (const Sent& item : sent) {
    const can::ReceivedFrame& got = heard[item.bus][next[item.bus]++];
    CHECK(got.frame.id == item.frame.id);
    CHECK(got.frame.flags == item.frame.flags);
    CHECK(got.frame.length == item.frame.length);
    CHECK(got.frame.data == item.frame.data);
    // the recording kept the sender's stamp rounded down to the microsecond
    pairs.push_back(Pair{item.beforeNs, got.monotonicNs});
  }
  std::int64_t worst = 0;
  for (const Pair& pair : pairs) {
    const auto expected =
        static_cast<std::int64_t>(static_cast<double>(pair.recordedNs - pairs.front().recordedNs) / speed);
    const std::int64_t actual = pair.replayedNs - pairs.front().replayedNs;
    worst = std::max(worst, std::abs(actual - expected));
  }
  CHECK_MESSAGE(worst < REPLAY_TOLERANCE_NS, ("worst timing error " + std::to_string(worst / 1000) + " us"));
  const std::int64_t recordedSpan = pairs.back().recordedNs - pairs.front().recordedNs;
  const std::int64_t replayedSpan = pairs.back().replayedNs - pairs.front().replayedNs;
  CHECK(static_cast<double>(replayedSpan) == doctest::Approx(static_cast<double>(recordedSpan) / speed).epsilon(0.05));
}

}  // namespace

TEST_CASE(
    "vcu record writes each bus's frames as candump -L lines plus the LCM events, and vcu replay plays them back with "
    "their timing") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);  // iox-roudi and the fixture, whose heartbeats are the LCM events
  const fs::path config = writeConfig();
  const fs::path folder = fs::temp_directory_path() / "drive1";
  Node node;

  auto started = sut.start(recordSpec(folder, config));
  REQUIRE_STATUS(started);
  harness::Process& recorder = **started;
  REQUIRE_MESSAGE(recorder.waitForLine("recording", 20s), recorder.output());
  const std::vector<Sent> sent = node.sendPattern();
  REQUIRE(waitForFileText(folder / "events.lcmlog", "OPENVCU_ITEST_HEARTBEAT", 5s));
  REQUIRE(recorder.signal(SIGINT));
  const auto exit = recorder.waitForExit(10s);
  REQUIRE(exit);
  while (recorder.readLine(1s)) {
  }  // the summary may still be in the pipe
  CHECK_MESSAGE((exit->exited && exit->code == 0), recorder.output());
  CHECK_MESSAGE(contains(recorder.output(), "vehicle: 20 frames"), recorder.output());
  CHECK_MESSAGE(contains(recorder.output(), "body: 10 frames"), recorder.output());
  CHECK(contains(recorder.output(), "events: " + std::to_string(fs::file_size(folder / "events.lcmlog")) + " bytes"));

  for (const std::string bus : {"vehicle", "body"}) {
    const std::vector<std::string> lines = readLines(folder / (bus + ".log"));
    std::vector<const Sent*> expected;
    for (const Sent& item : sent) {
      if (item.bus == bus) expected.push_back(&item);
    }
    REQUIRE(lines.size() == expected.size());
    std::int64_t previousNs = 0;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const LogLine line = parseLine(lines[i]);
      INFO(bus, " line ", i + 1, ": ", lines[i]);
      CHECK(line.bus == bus);
      CHECK(line.text == candumpText(expected[i]->frame));
      CHECK(line.timeNs > previousNs);
      CHECK(line.timeNs >= expected[i]->beforeNs - 1'000);  // the sim link stamps inside send()
      CHECK(line.timeNs <= expected[i]->afterNs);
      previousNs = line.timeNs;
    }
  }
  CHECK(contains(readLines(folder / "body.log").front(), ") body 456##1"));  // the FD syntax, BRS flag

  (void)node.drain();  // whatever else was on the buses
  const harness::CommandResult played = replay(sut, folder, config);
  REQUIRE_MESSAGE(played.exitCode() == 0, played.describe());
  CHECK_MESSAGE(contains(played.out, "vehicle: 20 frames"), played.describe());
  checkReplay(sent, node.drain(), 1.0);

  const harness::CommandResult fast = replay(sut, folder, config, {"--speed", "2"});
  REQUIRE_MESSAGE(fast.exitCode() == 0, fast.describe());
  checkReplay(sent, node.drain(), 2.0);
}

TEST_CASE("vcu record stops by itself after --for and keeps an earlier recording unless --force") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const fs::path config = writeConfig();
  const fs::path folder = fs::temp_directory_path() / "quiet";

  const auto start = std::chrono::steady_clock::now();
  const harness::CommandResult first =
      sut.run({VCU, "record", folder.string(), "--for", "1", "--config", config.string()});
  const auto took = std::chrono::steady_clock::now() - start;
  REQUIRE_MESSAGE(first.exitCode() == 0, first.describe());
  CHECK(took >= 1s);
  CHECK_MESSAGE(contains(first.out, "vehicle: 0 frames"), first.describe());
  CHECK(fs::exists(folder / "vehicle.log"));
  CHECK(fs::file_size(folder / "vehicle.log") == 0);
  CHECK(fs::exists(folder / "events.lcmlog"));

  const harness::CommandResult again =
      sut.run({VCU, "record", folder.string(), "--for", "1", "--config", config.string()});
  CHECK(again.exitCode() == 1);
  CHECK_MESSAGE(contains(again.err, "--force"), again.describe());
  const harness::CommandResult noLogger =
      sut.run({VCU, "record", folder.string(), "--for", "1", "--force", "--lcm-logger", "/nonexistent/lcm-logger",
               "--config", config.string()});
  CHECK(noLogger.exitCode() == 1);
  CHECK_MESSAGE(contains(noLogger.err, "cannot start /nonexistent/lcm-logger: No such file or directory"),
                noLogger.describe());
  const harness::CommandResult forced =
      sut.run({VCU, "record", folder.string(), "--for", "0.5", "--force", "--config", config.string()});
  CHECK_MESSAGE(forced.exitCode() == 0, forced.describe());
}

TEST_CASE(
    "vcu replay reports a missing folder, a malformed line with file:line, skips an unknown bus and loops until "
    "SIGTERM") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const fs::path config = writeConfig();

  const fs::path missing = fs::temp_directory_path() / "no-such-recording";
  const harness::CommandResult none = replay(sut, missing, config);
  CHECK(none.exitCode() == 1);
  CHECK_MESSAGE(contains(none.err, missing.string() + ": error: no such directory"), none.describe());

  const fs::path bad = fs::temp_directory_path() / "bad";
  fs::create_directories(bad);
  std::ofstream(bad / "vehicle.log") << "(1.000000) vehicle 123#11\n(1.010000) vehicle 123#1G\n";
  const harness::CommandResult malformed = replay(sut, bad, config);
  CHECK(malformed.exitCode() == 1);
  CHECK_MESSAGE(contains(malformed.err, (bad / "vehicle.log").string() + ":2:"), malformed.describe());
  CHECK_MESSAGE(contains(malformed.err, "nothing played"), malformed.describe());
  CHECK(!contains(malformed.out, "played"));

  const fs::path mixed = fs::temp_directory_path() / "mixed";
  fs::create_directories(mixed);
  std::ofstream(mixed / "vehicle.log")
      << "(1.000000) vehicle 123#11\n(1.010000) can7 321#22\n(1.020000) vehicle 123#33\n";
  Node node;
  const harness::CommandResult skipped = replay(sut, mixed, config);
  CHECK_MESSAGE(skipped.exitCode() == 0, skipped.describe());
  CHECK_MESSAGE(contains(skipped.err, "1 frame skipped: 'can7' is not a bus"), skipped.describe());
  CHECK_MESSAGE(contains(skipped.out, "vehicle: 2 frames"), skipped.describe());
  auto heard = node.drain();
  REQUIRE(heard["vehicle"].size() == 2);
  CHECK(heard["vehicle"][0].frame.data[0] == 0x11);
  CHECK(heard["vehicle"][1].frame.data[0] == 0x33);
  const std::int64_t gap = heard["vehicle"][1].monotonicNs - heard["vehicle"][0].monotonicNs;
  CHECK(gap >= 19 * MS);  // the 10 ms of the skipped frame's time do not count twice, but the 20 ms hold
  CHECK(gap < 20 * MS + REPLAY_TOLERANCE_NS);

  auto looping =
      sut.start(harness::ProcessSpec{.name = "replay-loop",
                                     .argv = {VCU, "replay", mixed.string(), "--loop", "--config", config.string()},
                                     .captureOutput = true});
  REQUIRE_STATUS(looping);
  harness::Process& player = **looping;
  REQUIRE_MESSAGE(player.waitForLine("replaying", 20s), player.output());
  std::size_t looped = 0;
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (looped < 7 && std::chrono::steady_clock::now() < end) {  // three passes and more
    std::this_thread::sleep_for(10ms);
    looped += node.drain()["vehicle"].size();
  }
  CHECK(looped >= 7);
  REQUIRE(player.signal(SIGTERM));
  const auto loopExit = player.waitForExit(10s);
  REQUIRE(loopExit);
  while (player.readLine(1s)) {
  }
  CHECK_MESSAGE((loopExit->exited && loopExit->code == 0), player.output());
  CHECK_MESSAGE(contains(player.output(), "passes)"), player.output());
}

namespace {

/// Long enough for the recorder to have taken and written everything published before.
constexpr auto RECORDER_CATCH_UP = 200ms;

/// A loaned sample on the sim bus `vehicle`, stamped now as a sim link stamps at send.
ipc::FrameLoan stampedLoan(ipc::FramePublisher& publisher, std::uint32_t id) {
  std::optional<ipc::FrameLoan> maybeLoan = publisher.loan();
  REQUIRE(maybeLoan);
  ipc::FrameSample& sample = maybeLoan->sample();
  sample.frame.id = id;
  sample.frame.length = 1;
  sample.frame.data[0] = static_cast<std::uint8_t>(id);
  sample.frame.timestampNs = realtimeNs();
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC, &now);
  sample.monotonicNs = static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
  return std::move(*maybeLoan);
}

ipc::FramePublisher vehicleSender() {
  if (!ipc::Runtime::initialized()) REQUIRE_STATUS(ipc::Runtime::init("test-record-node", 5s));
  auto publisher = ipc::FramePublisher::create(ipc::FrameTopic{"sim", "vehicle", ipc::FrameStream::SimWire});
  REQUIRE_STATUS(publisher);
  REQUIRE(publisher->waitForSubscribers(5000ms));
  return std::move(*publisher);
}

}  // namespace

TEST_CASE("vcu record writes frames of two senders in time order when a later-stamped frame reaches it first") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const fs::path config = writeConfig();
  const fs::path folder = fs::temp_directory_path() / "two-senders";
  auto started = sut.start(recordSpec(folder, config));
  REQUIRE_STATUS(started);
  harness::Process& recorder = **started;
  REQUIRE_MESSAGE(recorder.waitForLine("recording", 20s), recorder.output());
  ipc::FramePublisher first = vehicleSender();
  ipc::FramePublisher second = vehicleSender();

  // Two senders race: the first stamps its frame, the second stamps a later one and
  // publishes it before the first publishes. Once with the recorder taking the later
  // frame alone, once with both waiting in its queue together.
  ipc::FrameLoan early = stampedLoan(first, 0x101);
  std::this_thread::sleep_for(1ms);
  ipc::FrameLoan late = stampedLoan(second, 0x202);
  const std::int64_t earlyNs = early->frame.timestampNs;
  const std::int64_t lateNs = late->frame.timestampNs;
  REQUIRE(second.publish(std::move(late)));
  std::this_thread::sleep_for(RECORDER_CATCH_UP);
  REQUIRE(first.publish(std::move(early)));
  ipc::FrameLoan earlyAgain = stampedLoan(first, 0x103);
  std::this_thread::sleep_for(1ms);
  ipc::FrameLoan lateAgain = stampedLoan(second, 0x204);
  REQUIRE(second.publish(std::move(lateAgain)));
  REQUIRE(first.publish(std::move(earlyAgain)));
  std::this_thread::sleep_for(RECORDER_CATCH_UP);

  REQUIRE(recorder.signal(SIGINT));
  const auto exit = recorder.waitForExit(10s);
  REQUIRE(exit);
  while (recorder.readLine(1s)) {
  }
  REQUIRE_MESSAGE((exit->exited && exit->code == 0), recorder.output());
  CHECK_MESSAGE(contains(recorder.output(), "vehicle: 4 frames"), recorder.output());

  const std::vector<std::string> lines = readLines(folder / "vehicle.log");
  REQUIRE(lines.size() == 4);
  std::int64_t previousNs = 0;
  for (const std::string& text : lines) {
    const LogLine line = parseLine(text);
    INFO("line: ", text);
    CHECK(line.timeNs >= previousNs);
    previousNs = line.timeNs;
    if (contains(line.text, "101#")) {  // its own stamp or the later frame's, nothing else
      CHECK(line.timeNs >= earlyNs / 1000 * 1000);
      CHECK(line.timeNs <= lateNs);
      // taken alone after the later frame (the usual case): written at that frame's time,
      // and the summary says that a frame was written later than stamped
      if (line.timeNs > earlyNs) CHECK_MESSAGE(contains(recorder.output(), "later than stamped"), recorder.output());
    }
  }
  // our own analysis reads it without a step back or a malformed line
  const harness::CommandResult stats = sut.run({VCU, "trace", "stats", "--config", config.string(), folder.string()});
  CHECK_MESSAGE(stats.exitCode() == 0, stats.describe());
  CHECK_MESSAGE(!contains(stats.err, "backwards"), stats.describe());
  CHECK_MESSAGE(!contains(stats.err, "error"), stats.describe());
}

TEST_CASE("vcu record killed by SIGKILL while recording leaves only whole lines in its log") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const fs::path config = writeConfig();
  const fs::path folder = fs::temp_directory_path() / "killed";
  auto started = sut.start(recordSpec(folder, config));
  REQUIRE_STATUS(started);
  harness::Process& recorder = **started;
  REQUIRE_MESSAGE(recorder.waitForLine("recording", 20s), recorder.output());
  Node node;
  // 200 lines of 54 characters: several times any stdio buffer, fewer than the sim
  // link's receive queue holds
  constexpr std::size_t FRAMES = 200;
  for (std::size_t i = 0; i < FRAMES; ++i)
    REQUIRE(node.links["vehicle"]->send(vehicleFrame(0)) == can::SendStatus::Sent);
  const fs::path log = folder / "vehicle.log";
  const auto end = std::chrono::steady_clock::now() + 5s;
  std::error_code error;
  while (fs::file_size(log, error) == 0 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
  REQUIRE_MESSAGE(fs::file_size(log, error) > 0, "the recorder wrote nothing within 5 s");
  REQUIRE(recorder.signal(SIGKILL));  // what the HMI does to a recorder that does not stop
  REQUIRE(recorder.waitForExit(5s));

  const std::string text = readFile(log);
  REQUIRE(!text.empty());
  CHECK_MESSAGE(text.back() == '\n',
                "the log ends inside a line: ..." << text.substr(text.size() - std::min<std::size_t>(text.size(), 60)));
  const std::vector<std::string> lines = readLines(log);
  CHECK(lines.size() <= FRAMES);
  for (const std::string& line : lines) CHECK(parseLine(line).text == candumpText(vehicleFrame(0)));
}

TEST_CASE("vcu record started with SIGTERM and SIGINT blocked still ends cleanly on SIGTERM") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const fs::path config = writeConfig();
  const fs::path folder = fs::temp_directory_path() / "blocked";
  // coreutils' env blocks the signals and executes vcu in its place: the mask vcu-hmi's
  // children inherit (vcu-hmi reads SIGTERM and SIGINT through a signalfd)
  harness::ProcessSpec spec = recordSpec(folder, config);
  spec.argv.insert(spec.argv.begin(), {"/usr/bin/env", "--block-signal=TERM", "--block-signal=INT"});
  auto started = sut.start(spec);
  REQUIRE_STATUS(started);
  harness::Process& recorder = **started;
  REQUIRE_MESSAGE(recorder.waitForLine("recording", 20s), recorder.output());
  REQUIRE(recorder.signal(SIGTERM));
  const auto exit = recorder.waitForExit(5s);
  REQUIRE_MESSAGE(exit, "vcu record did not end within 5 s of SIGTERM: " << recorder.output());
  while (recorder.readLine(1s)) {
  }
  CHECK_MESSAGE((exit->exited && exit->code == 0), exit->toString() << ": " << recorder.output());
  CHECK_MESSAGE(contains(recorder.output(), "recorded "), recorder.output());
}
