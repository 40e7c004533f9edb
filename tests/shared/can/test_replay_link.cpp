// The replay:FILE link: order and content, timing (computed due times, the timerfd),
// speed, looping, the end of the log, channel selection, filters, open errors, and no
// allocation per frame.

#include <doctest/doctest.h>
#include <poll.h>
#include <stdlib.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <span>
#include <string>
#include <vector>

#include "openvcu/can/log_reader.hpp"
#include "openvcu/can/replay_link.hpp"

using namespace openvcu::can;

// ---- allocation counter for the whole test program ---------------------------------------

namespace {
std::atomic<std::uint64_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* memory = std::malloc(size == 0 ? 1 : size)) return memory;
  throw std::bad_alloc();
}
void operator delete(void* memory) noexcept {
  std::free(memory);
}
void operator delete(void* memory, std::size_t) noexcept {
  std::free(memory);
}

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t SPACING_NS = 20 * MS;
/// A correctness test on a shared machine, not a benchmark: how late a wake-up may be.
constexpr std::int64_t LATE_TOLERANCE_NS = 1000 * MS;
constexpr int POLL_TIMEOUT_MS = 3000;
const std::string LOG_DIR = OPENVCU_SOURCE_DIR "/tests/data/logs/";

std::int64_t monotonicNow() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

/// A fresh directory under $TMPDIR (or /tmp), removed with everything in it.
class TempDir {
 public:
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base != nullptr && *base != '\0' ? base : "/tmp") + "/replay-test-XXXXXX";
    if (mkdtemp(pattern.data()) != nullptr) m_path = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    if (!m_path.empty()) std::filesystem::remove_all(m_path, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  [[nodiscard]] bool ok() const { return !m_path.empty(); }
  /// Writes `text` to `name` in the directory; fails the test when the directory was not made.
  std::string write(const std::string& name, const std::string& text) const {
    REQUIRE(ok());
    const std::string path = m_path + "/" + name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }

 private:
  std::string m_path;
};

LinkOptions optionsAt(double speed, bool loop = false) {
  LinkOptions options;
  options.replaySpeed = speed;
  options.replayLoop = loop;
  return options;
}

std::unique_ptr<ReplayLink> openOrFail(const std::string& path, const LinkOptions& options) {
  auto openResult = ReplayLink::open(path, options);
  if (!openResult) FAIL(openResult.error().toString());
  return std::move(*openResult);
}

bool waitReadable(int fd, int timeoutMs) {
  pollfd entry{fd, POLLIN, 0};
  return poll(&entry, 1, timeoutMs) == 1 && (entry.revents & POLLIN) != 0;
}

/// Plays until `wanted` frames arrived or the link is down, waiting on the handle.
std::vector<ReceivedFrame> play(Link& sut, std::size_t wanted, std::size_t batchSize = 16) {
  std::vector<ReceivedFrame> frames;
  std::vector<ReceivedFrame> batch(batchSize);
  const std::int64_t deadline = monotonicNow() + 10'000 * MS;
  while (frames.size() < wanted && sut.up() && monotonicNow() < deadline) {
    waitReadable(sut.waitHandle().fd, POLL_TIMEOUT_MS);
    const std::size_t count = sut.receive(batch);
    frames.insert(frames.end(), batch.begin(), batch.begin() + static_cast<std::ptrdiff_t>(count));
  }
  return frames;
}

std::vector<BusEventKind> takeEvents(Link& sut) {
  std::vector<BusEventKind> kinds;
  while (auto maybeEvent = sut.nextEvent()) kinds.push_back(maybeEvent->kind);
  return kinds;
}

std::size_t countOf(const std::vector<BusEventKind>& kinds, BusEventKind kind) {
  std::size_t count = 0;
  for (const BusEventKind each : kinds) count += each == kind ? 1 : 0;
  return count;
}

/// candump -L lines, one frame every `spacingMs` from t = 1 s, ids 0x101, 0x102, ...
/// (wrapping within 11 bits), one data byte = the index.
std::string spacedLog(int frames, int spacingMs) {
  std::string text;
  for (int i = 0; i < frames; ++i) {
    const int ms = 1000 + i * spacingMs;
    char line[96];
    std::snprintf(line, sizeof line, "(%d.%03d000) can0 %03X#%02X\n", ms / 1000, ms % 1000, 0x101 + i % 0x600,
                  i & 0xFF);
    text += line;
  }
  return text;
}

}  // namespace

TEST_CASE("replay delivers the frames in log order with their logged time and data") {
  TempDir dir;
  const std::string path = dir.write("drive.log",
                                     "(1436509052.249713) can0 18FEF100#0102030405060708\n"
                                     "(1436509052.250000) can0 123#R\n"
                                     "(1436509052.250100) can0 456##1DEADBEEF\n");
  auto sut = openOrFail(path, optionsAt(0.0));
  std::vector<ReceivedFrame> batch(8);

  const std::size_t count = sut->receive(batch);

  REQUIRE(count == 3);
  CHECK(batch[0].frame.id == 0x18FEF100);
  CHECK(batch[0].frame.flags == FLAG_EXTENDED);
  CHECK(batch[0].frame.length == 8);
  CHECK(batch[0].frame.data[7] == 0x08);
  CHECK(batch[0].frame.timestampNs == 1436509052249713000);
  CHECK(batch[1].frame.flags == FLAG_RTR);
  CHECK(batch[2].frame.flags == (FLAG_FD | FLAG_BRS));
  CHECK(batch[2].frame.data[3] == 0xEF);
  CHECK(sut->stats().framesReceived == 3);
  CHECK(sut->kind() == LinkKind::Replay);
  CHECK(sut->name() == "replay:" + path);
}

TEST_CASE("frames 20 ms apart are due exactly 20 ms apart and not delivered before") {
  constexpr int FRAMES = 4;
  TempDir dir;
  auto sut = openOrFail(dir.write("spaced.log", spacedLog(FRAMES, 20)), optionsAt(1.0));
  const int fd = sut->waitHandle().fd;
  std::vector<ReceivedFrame> one(1);
  REQUIRE(waitReadable(fd, 0));  // the first frame is due at the first receive()

  REQUIRE(sut->receive(one) == 1);
  const std::int64_t startNs = one[0].monotonicNs;
  CHECK(one[0].frame.id == 0x101);

  for (int i = 1; i < FRAMES; ++i) {
    const std::int64_t dueNs = startNs + i * SPACING_NS;
    const std::size_t early = sut->receive(one);
    if (monotonicNow() < dueNs) CHECK(early == 0);  // asked before the due time: nothing

    REQUIRE(waitReadable(fd, POLL_TIMEOUT_MS));
    const std::int64_t wokeNs = monotonicNow();
    CHECK(wokeNs >= dueNs);  // a CLOCK_MONOTONIC timerfd never fires early
    CHECK(wokeNs - dueNs < LATE_TOLERANCE_NS);
    REQUIRE(sut->receive(one) == 1);
    CHECK(one[0].frame.id == static_cast<std::uint32_t>(0x101 + i));
    CHECK(one[0].monotonicNs == dueNs);  // computed, not measured
    CHECK(one[0].frame.timestampNs == 1'000'000'000 + i * SPACING_NS);
  }
}

TEST_CASE("speed 2 halves the spacing of the due times") {
  TempDir dir;
  auto sut = openOrFail(dir.write("spaced.log", spacedLog(3, 20)), optionsAt(2.0));

  const auto frames = play(*sut, 3);

  REQUIRE(frames.size() == 3);
  CHECK(frames[1].monotonicNs - frames[0].monotonicNs == SPACING_NS / 2);
  CHECK(frames[2].monotonicNs - frames[1].monotonicNs == SPACING_NS / 2);
}

TEST_CASE("speed 0 delivers everything at once and keeps the handle readable while frames remain") {
  TempDir dir;
  auto sut = openOrFail(dir.write("slow.log", spacedLog(10, 1000)), optionsAt(0.0));  // 1 s apart
  const int fd = sut->waitHandle().fd;
  std::vector<ReceivedFrame> batch(4);
  const std::int64_t beginNs = monotonicNow();

  CHECK(sut->receive(batch) == 4);
  CHECK(waitReadable(fd, 0));
  CHECK(sut->receive(batch) == 4);
  CHECK(waitReadable(fd, 0));
  CHECK(sut->receive(batch) == 2);
  CHECK(batch[1].frame.id == 0x10A);
  CHECK(monotonicNow() - beginNs < LATE_TOLERANCE_NS);  // no waiting for the 9 s of log
  CHECK_FALSE(sut->up());
  CHECK_FALSE(waitReadable(fd, 0));
}

TEST_CASE("a looping replay emits ReplayRestarted and plays the log again") {
  TempDir dir;
  auto sut = openOrFail(dir.write("loop.log", spacedLog(3, 1)), optionsAt(0.0, true));

  const auto frames = play(*sut, 9, 4);

  REQUIRE(frames.size() >= 9);
  for (std::size_t i = 0; i < 9; ++i) CHECK(frames[i].frame.id == 0x101 + i % 3);
  const auto events = takeEvents(*sut);
  CHECK(countOf(events, BusEventKind::ReplayRestarted) >= 2);
  CHECK(countOf(events, BusEventKind::ReplayFinished) == 0);
  CHECK(sut->restarts() >= 2);
  CHECK(sut->up());
}

TEST_CASE("each pass of a looping replay gets a new time base without a catch-up burst") {
  TempDir dir;
  auto sut = openOrFail(dir.write("loop.log", spacedLog(2, 20)), optionsAt(1.0, true));

  const auto frames = play(*sut, 4, 1);

  REQUIRE(frames.size() == 4);
  CHECK(frames[1].monotonicNs - frames[0].monotonicNs == SPACING_NS);
  CHECK(frames[2].monotonicNs >= frames[1].monotonicNs);  // the second pass starts after the first
  CHECK(frames[3].monotonicNs - frames[2].monotonicNs == SPACING_NS);
  CHECK(frames[2].frame.id == 0x101);
}

TEST_CASE("a looping replay whose file has gone finishes with the reason kept") {
  TempDir dir;
  const std::string path = dir.write("gone.log", spacedLog(2, 1));
  auto sut = openOrFail(path, optionsAt(0.0, true));
  std::filesystem::remove(path);  // the open reader keeps reading the unlinked file

  const auto frames = play(*sut, 10);

  CHECK(frames.size() == 2);
  CHECK_FALSE(sut->up());
  const auto events = takeEvents(*sut);
  CHECK(countOf(events, BusEventKind::ReplayRestarted) == 1);
  CHECK(countOf(events, BusEventKind::ReplayFinished) == 1);
  const auto maybeError = sut->lastLogError();
  REQUIRE(maybeError.has_value());
  CHECK(maybeError->toString().find("cannot open log") != std::string::npos);
}

TEST_CASE("the end of the log emits ReplayFinished once, up() turns false and the handle goes quiet") {
  TempDir dir;
  auto sut = openOrFail(dir.write("end.log", spacedLog(2, 1)), optionsAt(1.0));
  CHECK(sut->up());

  const auto frames = play(*sut, 2);

  REQUIRE(frames.size() == 2);
  CHECK_FALSE(sut->up());
  const auto events = takeEvents(*sut);
  REQUIRE(events.size() == 1);
  CHECK(events[0] == BusEventKind::ReplayFinished);
  CHECK_FALSE(waitReadable(sut->waitHandle().fd, 50));
  std::vector<ReceivedFrame> batch(4);
  CHECK(sut->receive(batch) == 0);
  CHECK_FALSE(sut->nextEvent().has_value());
}

TEST_CASE("only records of the selected channel are played") {
  TempDir dir;
  const std::string path = dir.write("two.log",
                                     "(1.000000) can0 101#01\n"
                                     "(1.001000) can1 201#02\n"
                                     "(1.002000) can0 102#03\n"
                                     "(1.003000) can1 202#04\n");
  LinkOptions options = optionsAt(0.0);
  options.replayChannel = "can1";
  auto sut = openOrFail(path, options);

  const auto frames = play(*sut, 4);

  REQUIRE(frames.size() == 2);
  CHECK(frames[0].frame.id == 0x201);
  CHECK(frames[1].frame.id == 0x202);
}

TEST_CASE("skipping many records of other channels returns to the caller with the handle readable") {
  constexpr int OTHER_RECORDS = 3 * static_cast<int>(ReplayLink::SKIP_BUDGET);
  TempDir dir;
  std::string text = "(1.000000) can1 201#01\n";
  for (int i = 0; i < OTHER_RECORDS; ++i) text += "(1.000000) can0 101#00\n";
  text += "(1.000000) can1 202#02\n";
  LinkOptions options = optionsAt(0.0);
  options.replayChannel = "can1";
  auto sut = openOrFail(dir.write("sparse.log", text), options);
  std::vector<ReceivedFrame> batch(8);

  CHECK(sut->receive(batch) == 1);  // both are due, but the skipping stops at the budget
  CHECK(waitReadable(sut->waitHandle().fd, 0));
  const auto rest = play(*sut, 1);

  REQUIRE(rest.size() == 1);
  CHECK(rest[0].frame.id == 0x202);
  CHECK_FALSE(sut->up());
}

TEST_CASE("filters drop frames in user space and count them") {
  TempDir dir;
  LinkOptions options = optionsAt(0.0);
  options.filters.push_back(IdFilter{0x102, 0x7FF, false});
  auto sut = openOrFail(dir.write("spaced.log", spacedLog(4, 1)), options);

  const auto frames = play(*sut, 4);

  REQUIRE(frames.size() == 1);
  CHECK(frames[0].frame.id == 0x102);
  CHECK(sut->stats().filteredOut == 3);
  CHECK(sut->stats().framesReceived == 1);
}

TEST_CASE("a missing file fails to open with the file and the reason") {
  const std::string path = "/nonexistent/openvcu/drive.log";

  auto openResult = openReplayLink(path, optionsAt(1.0));

  REQUIRE_FALSE(openResult.ok());
  const std::string text = openResult.error().toString();
  CHECK(text.find(path) != std::string::npos);
  CHECK(text.find("No such file or directory") != std::string::npos);
}

TEST_CASE("a log without any frame fails to open") {
  TempDir dir;
  const std::string path = dir.write("empty.log", "# nothing recorded\n\n// still nothing\n");

  auto openResult = ReplayLink::open(path, optionsAt(1.0));

  REQUIRE_FALSE(openResult.ok());
  CHECK(openResult.error().toString() == "replay:" + path + ": no CAN frame in the log");
}

TEST_CASE("a log without frames of the selected channel fails to open naming the channel") {
  TempDir dir;
  const std::string path = dir.write("can0.log", "(1.000000) can0 101#01\n(1.000000) can0 102#0\n");
  LinkOptions options = optionsAt(1.0);
  options.replayChannel = "can3";

  auto openResult = ReplayLink::open(path, options);

  REQUIRE_FALSE(openResult.ok());
  const std::string text = openResult.error().toString();
  CHECK(text.find("no CAN frame of channel 'can3' in the log") != std::string::npos);
  CHECK(text.find("1 malformed line") != std::string::npos);  // "0": odd number of hex digits
  CHECK(text.find(path + ":2:") != std::string::npos);
}

TEST_CASE("a negative or NaN replay speed is refused") {
  TempDir dir;
  const std::string path = dir.write("spaced.log", spacedLog(2, 20));

  CHECK_FALSE(ReplayLink::open(path, optionsAt(-1.0)).ok());
  CHECK_FALSE(ReplayLink::open(path, optionsAt(std::numeric_limits<double>::quiet_NaN())).ok());
}

TEST_CASE("malformed lines are skipped, counted and reading carries on") {
  TempDir dir;
  const std::string path = dir.write("bad.log",
                                     "(1.000000) can0 101#01\n"
                                     "(1.001000) can0 102#0\n"
                                     "(1.002000) can0 800#03\n"
                                     "(1.003000) can0 104#04\n");
  auto sut = openOrFail(path, optionsAt(0.0));

  const auto frames = play(*sut, 4);

  REQUIRE(frames.size() == 2);
  CHECK(frames[1].frame.id == 0x104);
  CHECK(sut->malformedLines() == 2);
  const auto maybeError = sut->lastLogError();
  REQUIRE(maybeError.has_value());
  CHECK(maybeError->location.line == 3);
}

TEST_CASE("frames without a timestamp play at once after the previous frame") {
  TempDir dir;
  const std::string path = dir.write("console.log",
                                     "  can0  101   [1]  01\n"
                                     "  can0  102   [2]  02 03\n"
                                     "  can0  103   [0]\n");
  auto sut = openOrFail(path, optionsAt(1.0));
  std::vector<ReceivedFrame> batch(8);

  REQUIRE(sut->receive(batch) == 3);

  CHECK(batch[1].frame.data[1] == 0x03);
  CHECK(batch[1].monotonicNs == batch[0].monotonicNs);
  CHECK(batch[2].monotonicNs == batch[0].monotonicNs);
  CHECK_FALSE(sut->up());
}

TEST_CASE("the candump console format with timestamps plays with its timing") {
  TempDir dir;
  const std::string path = dir.write("console.log",
                                     " (1436509052.249713)  can0  123   [2]  11 22\n"
                                     " (1436509052.269713)  can0  124   [1]  33\n");
  auto sut = openOrFail(path, optionsAt(1.0));

  const auto frames = play(*sut, 2);

  REQUIRE(frames.size() == 2);
  CHECK(frames[1].monotonicNs - frames[0].monotonicNs == SPACING_NS);
  CHECK(frames[1].frame.data[0] == 0x33);
}

TEST_CASE("a Vector ASC log plays with its timing and its channel numbers") {
  TempDir dir;
  const std::string path = dir.write("drive.asc",
                                     "date Fri Mar 1 00:00:00.000 2024\n"
                                     "base hex  timestamps absolute\n"
                                     "Begin Triggerblock Fri Mar 1 00:00:00.000 2024\n"
                                     "   0.010000 1  123             Rx   d 2 AA BB\n"
                                     "   0.015000 2  200             Rx   d 1 01\n"
                                     "   0.030000 1  124             Rx   d 1 CC\n"
                                     "End TriggerBlock\n");
  LinkOptions options = optionsAt(1.0);
  options.replayChannel = "1";
  auto sut = openOrFail(path, options);

  const auto frames = play(*sut, 2);

  REQUIRE(frames.size() == 2);
  CHECK(frames[0].frame.id == 0x123);
  CHECK(frames[1].frame.id == 0x124);
  CHECK(frames[1].monotonicNs - frames[0].monotonicNs == SPACING_NS);
}

TEST_CASE("the ASC and candump fixtures play every frame the log reader reads") {
  for (const char* name : {"vector.asc", "candump_l.log", "candump_console.log"}) {
    INFO(name);
    auto readerResult = LogReader::open(LOG_DIR + name);
    REQUIRE(readerResult.ok());
    std::size_t expected = 0;
    while (readerResult->next()) ++expected;
    auto sut = openOrFail(LOG_DIR + name, optionsAt(0.0));

    const auto frames = play(*sut, expected + 1);

    CHECK(frames.size() == expected);
    CHECK_FALSE(sut->up());
  }
}

namespace {

/// A log of four frames played at speed 1, one frame per receive, and the link that played it.
struct PlayedFour {
  std::unique_ptr<ReplayLink> sut;
  std::vector<ReceivedFrame> frames;
};

PlayedFour playFour(const std::string& name, const std::string& text) {
  TempDir dir;
  PlayedFour played;
  played.sut = openOrFail(dir.write(name, text), optionsAt(1.0));
  played.frames = play(*played.sut, 4, 1);
  return played;
}

}  // namespace

TEST_CASE("timestamps that go back play at once and are counted") {
  const auto [sut, frames] = playFour("jitter.log",
                                      "(1.000000) can0 101#01\n"
                                      "(1.020000) can0 102#02\n"
                                      "(1.010000) can0 103#03\n"
                                      "(1.030000) can0 104#04\n");

  REQUIRE(frames.size() == 4);
  const std::int64_t startNs = frames[0].monotonicNs;
  CHECK(frames[1].monotonicNs == startNs + 20 * MS);
  CHECK(frames[2].monotonicNs == startNs + 20 * MS);  // at once after the previous frame
  CHECK(frames[3].monotonicNs == startNs + 30 * MS);  // the schedule keeps its anchor
  CHECK(sut->backwardTimestamps() == 1);
}

TEST_CASE("a step back of more than a second starts a new time base") {
  const auto [sut, frames] = playFour("joined.log",
                                      "(5.000000) can0 101#01\n"
                                      "(5.020000) can0 102#02\n"
                                      "(1.000000) can0 103#03\n"
                                      "(1.010000) can0 104#04\n");

  REQUIRE(frames.size() == 4);
  const std::int64_t startNs = frames[0].monotonicNs;
  CHECK(frames[2].monotonicNs == startNs + 20 * MS);
  CHECK(frames[3].monotonicNs == startNs + 30 * MS);  // its own 10 ms spacing, not a burst
  CHECK(sut->backwardTimestamps() == 1);
}

TEST_CASE("send is not supported by a replay and is counted as a failure") {
  TempDir dir;
  auto sut = openOrFail(dir.write("spaced.log", spacedLog(1, 1)), optionsAt(1.0));

  CHECK(sut->send(Frame{}) == SendStatus::NotSupported);
  CHECK(sut->stats().sendFailures == 1);
}

TEST_CASE("receive allocates nothing per frame once the replay is open") {
  constexpr int FRAMES = 3000;  // ~80 KiB: more than one fill of the reader's buffer
  TempDir dir;
  auto sut = openOrFail(dir.write("big.log", spacedLog(FRAMES, 1)), optionsAt(0.0));
  std::vector<ReceivedFrame> batch(64);
  std::size_t received = 0;

  const std::uint64_t before = g_allocations.load();
  while (sut->up()) received += sut->receive(batch);
  const std::uint64_t allocations = g_allocations.load() - before;

  CHECK(received == FRAMES);
  CHECK(allocations == 0);
}

TEST_CASE("receive into an empty span does nothing and keeps the frame") {
  TempDir dir;
  auto sut = openOrFail(dir.write("spaced.log", spacedLog(1, 1)), optionsAt(1.0));
  std::vector<ReceivedFrame> batch(1);

  CHECK(sut->receive(std::span<ReceivedFrame>{}) == 0);
  CHECK(waitReadable(sut->waitHandle().fd, 0));
  CHECK(sut->receive(batch) == 1);
}
