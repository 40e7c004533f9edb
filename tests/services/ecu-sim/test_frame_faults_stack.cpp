// `vcu inject` frame faults applied by vcu-ecu-sim, as a process beside iox-roudi on a copy
// of config/hhea, seen by the test as one more node on sim:vehicle: each fault changes the
// simulated nodes' frames as asked (silenced, delayed, corrupted, replayed, spoofed, a
// hostile Address Claimed, a babbling priority-0 node at the asked load), is acknowledged
// with time stamps around the moment it took effect, and `--off` ends it. And `vcu inject
// gpio`: an input of the simulated GPIO chip held stuck through vcu-gpio.

#include <algorithm>
#include <array>
#include <optional>
#include <thread>

#include "integration_support.hpp"
#include "openvcu/can/wire_time.hpp"
#include "openvcu/can_links/sim_link.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/ipc/waiter.hpp"

namespace {

constexpr std::uint32_t EXTENDED_MASK = 0x1FFFFFFFu;
constexpr std::uint8_t SPOOFED_ADDRESS = 0x30;
constexpr std::uint8_t VCU_ADDRESS = 0x21;
constexpr std::uint32_t BABBLE_ID = 0x00EFFFFDu;  // priority 0, PGN 0xEF00 (Proprietary A) to global, from 0xFD
constexpr std::uint64_t LINK_ID = 1;              // the node's link in its ipc::Waiter

struct Received {
  std::int64_t atNs{};  ///< the sender's CLOCK_MONOTONIC
  can::Frame frame;
};

/// The test's node on sim:vehicle.
struct Node {
  std::unique_ptr<can::Link> link;
  std::optional<ipc::Waiter> waiter;  ///< wakes when the link has frames; declared after it

  /// Opens sim:vehicle and a waiter on its wait handle (needs an initialised ipc::Runtime).
  void open() {
    auto opened = can::openSimLink("vehicle", can::LinkOptions{});
    REQUIRE_STATUS(opened);
    link = std::move(*opened);
    auto created = ipc::Waiter::create();
    REQUIRE_STATUS(created);
    waiter.emplace(std::move(*created));
    const Status attached = waiter->attachLink(link->waitHandle(), LINK_ID);
    REQUIRE_STATUS(attached);
  }

  /// Every frame for `duration`: blocks on the link's wait handle between frames.
  std::vector<Received> record(std::chrono::milliseconds duration) {
    std::vector<Received> frames;
    std::array<can::ReceivedFrame, 64> batch{};
    const auto end = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < end) {
      waiter->waitUntil(end);
      while (const std::size_t count = link->receive(batch)) {
        for (std::size_t i = 0; i < count; ++i) frames.push_back(Received{batch[i].monotonicNs, batch[i].frame});
        if (count < batch.size()) break;
      }
    }
    return frames;
  }
  /// Forgets what arrived so far.
  void drain() {
    std::array<can::ReceivedFrame, 64> batch{};
    while (link->receive(batch) > 0) {
    }
  }
};

std::vector<Received> withId(const std::vector<Received>& frames, std::uint32_t id) {
  std::vector<Received> out;
  for (const Received& r : frames) {
    if ((r.frame.id & EXTENDED_MASK) == (id & EXTENDED_MASK)) out.push_back(r);
  }
  return out;
}

struct Injected {
  std::int64_t requestedNs{};
  std::int64_t acknowledgedNs{};
};

/// `vcu inject ARGS --json`, which must be accepted; its time stamps.
Injected inject(ConfiguredStack& s, std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), "inject");
  arguments.emplace_back("--json");
  const auto result = s.vcu(arguments);
  REQUIRE_MESSAGE(result.exitCode() == 0, result.describe());
  const auto answer = nlohmann::json::parse(result.out);
  REQUIRE(answer["accepted"] == true);
  Injected stamps{answer["requestedMonotonicNs"].get<std::int64_t>(),
                  answer["acknowledgedMonotonicNs"].get<std::int64_t>()};
  CHECK(stamps.requestedNs <= stamps.acknowledgedNs);
  CHECK(answer["requestedRealtimeNs"].get<std::int64_t>() > 0);
  return stamps;
}

std::uint32_t messageId(const ConfiguredStack& s, const std::string& name) {
  const dbc::Message* message = s.vehicle->database.findMessage(name);
  REQUIRE_MESSAGE(message, name);
  return message->id & EXTENDED_MASK;
}

/// iox-roudi, vcu-ecu-sim on a copy of config/hhea, and the test's node on sim:vehicle, with
/// PDU_Tx_1 (PDU, 100 ms) seen before any fault.
struct InjectStack {
  ConfiguredStack s{copyHheaConfig(fs::temp_directory_path() / "hhea-inject")};
  harness::Process* sim{};
  Node node;
  std::uint32_t pdu1{};
  std::uint32_t pdu2{};
  can::Frame clean;  ///< PDU_Tx_1 as the PDU sends it

  InjectStack() {
    REQUIRE_STATUS(s.sut.startRoudi());
    sim = &s.startService("ecu-sim", ECU_SIM_BINARY);
    if (!ipc::Runtime::initialized()) REQUIRE_STATUS(ipc::Runtime::init("test-frame-faults", 5s));
    node.open();
    pdu1 = messageId(s, "PDU_Tx_1");
    pdu2 = messageId(s, "PDU_Tx_2");
    const auto before = withId(node.record(300ms), pdu1);
    REQUIRE_MESSAGE(before.size() >= 2, sim->output());
    clean = before.back().frame;
  }
};

}  // namespace

TEST_CASE("vcu inject refuses a frame fault for a target the simulated vehicle does not have") {
  SKIP_UNLESS_ISOLATED();
  InjectStack f;
  const auto unknown = f.s.vcu({"inject", "delay", "NoSuchNode", "--ms", "100"});
  CHECK(unknown.exitCode() == 1);
  CHECK_MESSAGE(contains(unknown.out, "refused: no DBC message or simulated node 'NoSuchNode'"), unknown.describe());
  const auto bus = f.s.vcu({"inject", "babble", "nobus", "--load", "10"});
  CHECK(bus.exitCode() == 1);
  CHECK_MESSAGE(contains(bus.out, "refused: no bus 'nobus' (buses: vehicle)"), bus.describe());
}

TEST_CASE("vcu inject corrupt flips the asked bits, replay sends an old frame again, spoof moves the source address") {
  SKIP_UNLESS_ISOLATED();
  InjectStack f;
  ConfiguredStack& s = f.s;
  Node& node = f.node;
  const std::uint32_t pdu1 = f.pdu1;
  const std::uint32_t pdu2 = f.pdu2;
  const can::Frame clean = f.clean;
  const Injected corrupted = inject(s, {"corrupt", "PDU_Tx_1", "--xor", "FF01"});
  const auto during = withId(node.record(300ms), pdu1);
  REQUIRE(during.size() >= 2);
  for (const Received& r : during) {
    if (r.atNs <= corrupted.acknowledgedNs) continue;
    CHECK(r.frame.data[0] == (clean.data[0] ^ 0xFF));
    CHECK(r.frame.data[1] == (clean.data[1] ^ 0x01));
    CHECK(std::equal(r.frame.data.begin() + 2, r.frame.data.begin() + 8, clean.data.begin() + 2));
  }
  inject(s, {"corrupt", "PDU_Tx_1", "--off"});
  // The corrupted frames were sent 150..450 ms ago: replayed, they come back in place of
  // the clean ones.
  std::this_thread::sleep_for(150ms);
  const Injected replayed = inject(s, {"replay", "PDU_Tx_1", "--age", "300"});
  const auto replay = withId(node.record(300ms), pdu1);
  std::size_t old = 0;
  for (const Received& r : replay) {
    if (r.atNs > replayed.acknowledgedNs) old += r.frame.data[0] == (clean.data[0] ^ 0xFF) ? 1 : 0;
  }
  CHECK(old >= 2);
  inject(s, {"replay", "PDU_Tx_1", "--off"});
  const auto live = withId(node.record(200ms), pdu1);
  REQUIRE_FALSE(live.empty());
  CHECK(live.back().frame.data == clean.data);

  const Injected spoofed = inject(s, {"spoof", "PDU", "--from", "0x30"});
  const auto moved = node.record(300ms);
  const std::uint32_t pdu1Spoofed = (pdu1 & ~0xFFu) | SPOOFED_ADDRESS;
  std::size_t fromOriginal = 0;
  for (const Received& r : withId(moved, pdu1)) fromOriginal += r.atNs > spoofed.acknowledgedNs ? 1 : 0;
  CHECK(fromOriginal == 0);
  CHECK(withId(moved, pdu1Spoofed).size() >= 2);
  CHECK(withId(moved, (pdu2 & ~0xFFu) | SPOOFED_ADDRESS).size() >= 2);  // the node's other message too
  inject(s, {"spoof", "PDU", "--off"});
  node.drain();
  CHECK(withId(node.record(200ms), pdu1).size() >= 1);
}

TEST_CASE("vcu inject silence and delay hold back a message's frames from inside the stamped window") {
  SKIP_UNLESS_ISOLATED();
  InjectStack f;
  ConfiguredStack& s = f.s;
  Node& node = f.node;
  const std::uint32_t pdu1 = f.pdu1;
  const std::uint32_t pdu2 = f.pdu2;
  const Injected silenced = inject(s, {"silence", "PDU_Tx_1"});
  const auto quiet = node.record(300ms);
  for (const Received& r : withId(quiet, pdu1)) CHECK(r.atNs <= silenced.acknowledgedNs);
  CHECK(withId(quiet, pdu2).size() >= 2);  // the node's other message goes on
  inject(s, {"silence", "PDU_Tx_1", "--off"});
  CHECK(withId(node.record(200ms), pdu1).size() >= 1);

  const auto cycle = withId(node.record(300ms), pdu2);
  REQUIRE(cycle.size() >= 2);
  const Injected delayed = inject(s, {"delay", "PDU_Tx_2", "--ms", "400"});
  const auto late = withId(node.record(700ms), pdu2);
  // nothing between the acknowledgement and 400 ms after the request, then the cycle again
  std::size_t inGap = 0;
  std::size_t afterGap = 0;
  for (const Received& r : late) {
    if (r.atNs > delayed.acknowledgedNs && r.atNs < delayed.requestedNs + 390'000'000) ++inGap;
    if (r.atNs >= delayed.requestedNs + 400'000'000) ++afterGap;
  }
  CHECK(inGap <= 1);  // one frame may have left just before the fault took effect
  CHECK(afterGap >= 2);
  inject(s, {"delay", "PDU_Tx_2", "--off"});
}

TEST_CASE("vcu inject claim sends a NAME one below the VCU's, babble fills the asked share of the bus") {
  SKIP_UNLESS_ISOLATED();
  InjectStack f;
  ConfiguredStack& s = f.s;
  Node& node = f.node;
  const std::uint64_t vcuName = s.vehicle->buses.at(0).j1939->name.toValue();
  const Injected claimed = inject(s, {"claim", "0x21"});
  const auto claims = withId(node.record(200ms), 0x18EEFF00u | VCU_ADDRESS);
  REQUIRE(claims.size() == 1);
  std::uint64_t name = 0;
  for (std::size_t i = 0; i < 8; ++i) name |= static_cast<std::uint64_t>(claims[0].frame.data[i]) << (8 * i);
  CHECK(name == vcuName - 1);
  CHECK(claims[0].atNs >= claimed.requestedNs);
  CHECK(claims[0].atNs <= claimed.acknowledgedNs);

  constexpr double LOAD = 0.2;
  inject(s, {"babble", "vehicle", "--load", "20"});
  node.drain();
  const auto babble = withId(node.record(500ms), BABBLE_ID);
  inject(s, {"babble", "vehicle", "--off"});
  REQUIRE(babble.size() >= 2);
  const std::uint32_t bitrate = s.vehicle->buses.at(0).bitrate;
  const std::int64_t busyNs =
      static_cast<std::int64_t>(babble.size() - 1) * can::wireTimeNs(babble[0].frame, bitrate, bitrate);
  const double load = static_cast<double>(busyNs) / static_cast<double>(babble.back().atNs - babble.front().atNs);
  MESSAGE("babble: " << babble.size() << " frames, load " << load * 100 << " %");
  CHECK(load == doctest::Approx(LOAD).epsilon(0.25));
  node.drain();
  std::this_thread::sleep_for(50ms);
  const auto after = withId(node.record(200ms), BABBLE_ID);
  CHECK(after.empty());
}

TEST_CASE("vcu inject gpio holds an input of the simulated chip stuck until --off, and refuses outputs") {
  SKIP_UNLESS_ISOLATED();
  ConfiguredStack s(copyHheaConfig(fs::temp_directory_path() / "hhea-inject-gpio"));
  REQUIRE_STATUS(s.sut.startRoudi());
  s.startService("gpio", GPIO_BINARY);
  s.openTable();
  const signals::SignalIndex level = s.index("internal.gpio.ContactorFault");
  REQUIRE(waitForBus(*s.table, level, 0, 3s));

  const Injected stuck = inject(s, {"gpio", "ContactorFault", "--level", "1"});
  REQUIRE(waitForBus(*s.table, level, 1, 3s));
  const std::int64_t seenNs = std::chrono::steady_clock::now().time_since_epoch().count();  // CLOCK_MONOTONIC
  MESSAGE("ContactorFault read as 1 at most " << (seenNs - stuck.requestedNs) / 1'000'000 << " ms after the request");
  inject(s, {"gpio", "ContactorFault", "--off"});
  CHECK(waitForBus(*s.table, level, 0, 3s));

  const auto output = s.vcu({"inject", "gpio", "Cl15", "--level", "0"});
  CHECK(output.exitCode() == 1);
  CHECK_MESSAGE(contains(output.err, "line Cl15 is an output"), output.describe());
  const auto unknown = s.vcu({"inject", "gpio", "Horn", "--level", "1"});
  CHECK(unknown.exitCode() == 1);
  CHECK_MESSAGE(contains(unknown.err, "no GPIO line 'Horn' (lines: Cl15, ContactorFault)"), unknown.describe());
}
