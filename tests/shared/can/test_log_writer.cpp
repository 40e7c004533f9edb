// formatCandumpL, and reader(writer(frame)) == frame for every kind of frame.

#include <doctest/doctest.h>

#include <array>
#include <random>
#include <sstream>

#include "log_test_support.hpp"
#include "openvcu/can/log_writer.hpp"

using namespace openvcu::can;

namespace {

Frame makeFrame(std::uint32_t id, std::uint8_t flags, std::initializer_list<std::uint8_t> bytes,
                std::int64_t timestampNs = 1436509052249713000) {
  Frame frame;
  frame.id = id;
  frame.flags = flags;
  frame.timestampNs = timestampNs;
  frame.length = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), frame.data.begin());
  return frame;
}

bool sameFrame(const Frame& a, const Frame& b) {
  return a.id == b.id && a.flags == b.flags && a.length == b.length && a.data == b.data &&
         a.timestampNs == b.timestampNs;
}

}  // namespace

TEST_CASE("writer formats an extended data frame like candump -L") {
  const Frame frame = makeFrame(0x18FEF100, FLAG_EXTENDED, {1, 2, 3, 4, 5, 6, 7, 8});

  CHECK(formatCandumpL(frame, "can0") == "(1436509052.249713) can0 18FEF100#0102030405060708");
}

TEST_CASE("writer formats standard, FD, remote and error frames") {
  CHECK(formatCandumpL(makeFrame(0x7B, 0, {}, 0), "vcan0") == "(0.000000) vcan0 07B#");
  CHECK(formatCandumpL(makeFrame(0x123, FLAG_FD | FLAG_BRS, {0xDE, 0xAD, 0xBE, 0xEF}, 5), "can1") ==
        "(0.000000) can1 123##1DEADBEEF");
  CHECK(formatCandumpL(makeFrame(0x123, FLAG_FD | FLAG_ESI, {}, 1'000'000'001), "can1") == "(1.000000) can1 123##2");
  Frame remote = makeFrame(0x123, FLAG_RTR, {}, 2'500'000'000);
  remote.length = 5;
  CHECK(formatCandumpL(remote, "can0") == "(2.500000) can0 123#R5");
  CHECK(formatCandumpL(makeFrame(0x4, FLAG_ERROR, {0, 4, 0, 0, 0, 0, 0, 0}, 0), "can0") ==
        "(0.000000) can0 20000004#0004000000000000");
}

TEST_CASE("writer appends the direction and rounds negative times down") {
  CHECK(formatCandumpL(makeFrame(0x1, 0, {0xAA}, -1), "can0", 'T') == "(-0.000001) can0 001#AA T");
  CHECK(formatCandumpL(makeFrame(0x1, 0, {0xAA}, -1'500'000'000), "can0", 'R') == "(-1.500000) can0 001#AA R");
}

TEST_CASE("writer refuses a buffer shorter than the longest line") {
  std::array<char, 16> tooSmall{};

  CHECK(formatCandumpL(makeFrame(0x1, 0, {}), "can0", tooSmall) == 0);
}

TEST_CASE("writer output fits candumpLMaxLength for the largest frame") {
  Frame largest = makeFrame(EXTENDED_ID_MASK, FLAG_EXTENDED | FLAG_FD | FLAG_BRS | FLAG_ESI, {},
                            std::numeric_limits<std::int64_t>::min());
  largest.length = MAX_DATA_LENGTH;

  const std::string line = formatCandumpL(largest, "can0", 'R');

  CHECK(line.size() <= candumpLMaxLength(4));
  CHECK(line.substr(0, 22) == "(-9223372036.854776) c");
}

TEST_CASE("reader reads back exactly what the writer wrote for every kind of frame") {
  Frame remote = makeFrame(0x7FF, FLAG_RTR, {});
  remote.length = 8;
  Frame fd64 = makeFrame(0x1ABCDEF0, FLAG_EXTENDED | FLAG_FD | FLAG_BRS, {});
  fd64.length = MAX_DATA_LENGTH;
  for (std::size_t i = 0; i < MAX_DATA_LENGTH; ++i) fd64.data[i] = static_cast<std::uint8_t>(i * 3);
  const std::vector<Frame> frames = {
      makeFrame(0x18FEF100, FLAG_EXTENDED, {1, 2, 3, 4, 5, 6, 7, 8}),
      makeFrame(0x000, 0, {}),
      makeFrame(0x123, FLAG_FD | FLAG_ESI, {9, 8, 7, 6, 5, 4, 3, 2, 1, 0, 0xFF, 0xFE}),
      makeFrame(0x4, FLAG_ERROR, {0, 4, 0, 0, 0, 0, 0, 0}),
      makeFrame(0x42, 0, {0x42}, -2'000'000),
      remote,
      fd64,
  };
  std::string text;
  for (const Frame& frame : frames) text += formatCandumpL(frame, "can0", 'T') + "\n";

  const auto result = openvcu::can::test::readText(text);

  CHECK(result.errorCount == 0);
  REQUIRE(result.records.size() == frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    INFO("frame " << i << ": " << formatCandumpL(frames[i], "can0"));
    CHECK(sameFrame(result.records[i].frame, frames[i]));
    CHECK(result.records[i].channel == "can0");
    CHECK(result.records[i].direction == 'T');
  }
}

TEST_CASE("random frames survive a write and read round trip") {
  constexpr int FRAME_COUNT = 2000;
  constexpr std::uint32_t SEED = 1939;
  std::mt19937 random(SEED);
  std::vector<Frame> frames;
  std::ostringstream text;
  for (int i = 0; i < FRAME_COUNT; ++i) {
    Frame frame;
    frame.timestampNs =
        static_cast<std::int64_t>(random() % 2'000'000'000u) * 1'000'000 + (random() % 1'000'000) * 1000;
    const bool extended = (random() & 1) != 0;
    const bool fd = (random() % 3) == 0;
    frame.id = extended ? random() & EXTENDED_ID_MASK : random() & STANDARD_ID_MASK;
    frame.flags = static_cast<std::uint8_t>((extended ? FLAG_EXTENDED : 0) | (fd ? FLAG_FD : 0));
    if (fd && (random() & 1) != 0) frame.flags |= FLAG_BRS;
    frame.length = fd ? dlcToLength(static_cast<std::uint8_t>(random() % 16)) : static_cast<std::uint8_t>(random() % 9);
    for (std::size_t b = 0; b < frame.length; ++b) frame.data[b] = static_cast<std::uint8_t>(random());
    frames.push_back(frame);
    text << formatCandumpL(frame, "vcan0") << '\n';
  }

  const auto result = openvcu::can::test::readText(text.str());

  CHECK(result.errorCount == 0);
  REQUIRE(result.records.size() == frames.size());
  int mismatches = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) mismatches += sameFrame(result.records[i].frame, frames[i]) ? 0 : 1;
  CHECK(mismatches == 0);
}
