// vcu-ecu-sim's frame-fault engine on a fake clock: the SimFault keys it takes and refuses,
// the delay line, replay from the history, and the babbling node's rate.

#include <doctest/doctest.h>

#include <vector>

#include "frame_faults.hpp"
#include "openvcu/can/wire_time.hpp"

using namespace openvcu;
using ecusim::FrameFaultKind;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::uint32_t BITRATE = 500'000;
constexpr std::uint32_t PDU_ID = 0x18FF4040u;

struct Sent {
  std::int64_t atNs;
  can::Frame frame;
};

can::Frame pduFrame(std::uint8_t first) {
  can::Frame frame;
  frame.id = PDU_ID;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = 8;
  frame.data[0] = first;
  return frame;
}

ecusim::FrameFaultRequest parsed(const std::string& key, bool on = true) {
  auto result = ecusim::parseFrameFault(key, on);
  REQUIRE(result);
  REQUIRE_MESSAGE(*result, (*result ? "" : result->error().message));
  return **result;
}

std::string refusal(const std::string& key) {
  auto result = ecusim::parseFrameFault(key, true);
  REQUIRE(result);
  REQUIRE_FALSE(*result);
  return result->error().message;
}

}  // namespace

TEST_CASE("frame fault keys parse their kind, target and parameter, and bad ones are refused with the reason") {
  CHECK_FALSE(ecusim::parseFrameFault("battery", true));  // a model fault, not a frame fault
  CHECK_FALSE(ecusim::parseFrameFault("isolation.x", true));
  CHECK(parsed("delay.VIC=300").delayNs == 300 * MS);
  CHECK(parsed("delay.VIC", false).name() == "delay.VIC");
  CHECK(parsed("claim.0x21").address == 0x21);
  CHECK(parsed("spoof.PDU=48").address == 48);
  CHECK(parsed("babble.vehicle=30").load == doctest::Approx(0.3));
  const auto corrupt = parsed("corrupt.PDU_Tx_1=FF01");
  CHECK(corrupt.maskLength == 2);
  CHECK(corrupt.mask[1] == 0x01);
  CHECK(parsed("corrupt.PDU_Tx_1").maskLength == can::MAX_DATA_LENGTH);
  CHECK(refusal("delay.VIC") == "delay.VIC: the time must be 1..10000 ms, not ''");
  CHECK(refusal("delay.VIC=20000") == "delay.VIC=20000: the time must be 1..10000 ms, not '20000'");
  CHECK(refusal("claim.254") == "claim.254: the address must be 0..253 (33 or 0x21), not '254'");
  CHECK(refusal("corrupt.X=F") == "corrupt.X=F: the XOR mask must be whole hex bytes (e.g. FF01), not 'F'");
  CHECK(parsed("babble.vehicle=12.5").load == doctest::Approx(0.125));
  CHECK(refusal("babble.vehicle=0") == "babble.vehicle=0: the load must be above 0 and at most 100 %, not '0'");
  CHECK(refusal("silent.") == "silent.: no target after 'silent.'");
}

TEST_CASE("the frame-fault engine delays, replays from its history and babbles at the asked load") {
  ecusim::FrameFaults sut({ecusim::FaultBus{"vehicle", BITRATE, BITRATE, std::nullopt}});
  std::vector<Sent> wire;
  std::int64_t now = 0;
  const auto out = [&](std::size_t, const can::Frame& frame) { wire.push_back(Sent{now, frame}); };
  const std::vector<ecusim::FrameTarget> pdu{{0, PDU_ID, true}};
  const auto cycle = [&](std::int64_t until, std::uint8_t first) {
    for (; now < until; now += 10 * MS) {
      sut.send(0, pduFrame(first), now, out);
      sut.step(now, out);
    }
  };

  cycle(100 * MS, 1);  // frames with byte 0 = 1 for 100 ms
  CHECK(wire.size() == 10);
  REQUIRE_FALSE(sut.apply(parsed("delay.PDU=35"), true, pdu, now));
  wire.clear();
  cycle(200 * MS, 2);
  REQUIRE_FALSE(wire.empty());
  CHECK(wire.front().atNs == 140 * MS);  // the first delayed frame (sent at 100 ms), due at 135 ms
  REQUIRE_FALSE(sut.apply(parsed("delay.PDU", false), false, {}, now));

  // replay: the frame that went out 150 ms ago had byte 0 = 1
  REQUIRE_FALSE(sut.apply(parsed("replay.PDU=150"), true, pdu, now));
  wire.clear();
  cycle(250 * MS, 3);
  REQUIRE_FALSE(wire.empty());
  for (const Sent& s : wire) CHECK((s.frame.data[0] == 1 || s.frame.data[0] == 2));  // delayed 2s, then replayed 1s
  CHECK(wire.back().frame.data[0] == 1);
  CHECK(sut.apply(parsed("replay.PDU=10000"), true, pdu, now) ==
        std::optional<std::string>(
            "no frame of PDU was sent 10000 ms ago or earlier (the history holds the last 16384 frames)"));
  REQUIRE_FALSE(sut.apply(parsed("replay.PDU", false), false, {}, now));

  // babble at 25 %: one frame per 4 wire times
  REQUIRE_FALSE(sut.apply(parsed("babble.vehicle=25"), true, {}, now));
  std::size_t babble = 0;
  const std::int64_t start = now;
  for (; now < start + 100 * MS; now += MS) {
    wire.clear();
    sut.step(now, out);
    for (const Sent& s : wire) babble += s.frame.id == ecusim::BABBLE_CAN_ID ? 1 : 0;
  }
  can::Frame sample;
  sample.id = ecusim::BABBLE_CAN_ID;
  sample.flags = can::FLAG_EXTENDED;
  sample.length = 8;
  sample.data.fill(0x55);
  const double expected = 100.0 * MS * 0.25 / static_cast<double>(can::wireTimeNs(sample, BITRATE, BITRATE));
  CHECK(static_cast<double>(babble) == doctest::Approx(expected).epsilon(0.02));
  CHECK(sut.apply(parsed("babble.can2=10"), true, {}, now) ==
        std::optional<std::string>("no bus 'can2' (buses: vehicle)"));
  CHECK(sut.apply(parsed("claim.33"), true, {}, now) ==
        std::optional<std::string>("no bus has a \"j1939\" object: there is no VCU NAME to outrank"));
}
