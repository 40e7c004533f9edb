// A hostile Address Claimed on HHEA's simulated vehicle bus. vcu-can-rx and vcu-can-tx run
// on a copy of config/hhea with the keep-alive group on, so the VCU sends its J1939-76 pairs
// (S1_ES, HVESSC1, ...) from 0x21. The test, a node on sim:vehicle, claims 0x21 with a NAME
// one below the VCU's (it wins the contest) and records every frame for 1.5 s, then claims
// again and again. J1939-81 and docs/design/j1939-address-claim.md ("Safety networks"):
//   - the loss is the fault j1939_address_lost.vehicle within 1 s, its text naming the bus,
//     0x21 and the claimant's NAME;
//   - no SHM and no SDM leaves from any address but 0x21, and the VCU does not move: with
//     HHEA's fixed NAME it sends Cannot Claim and nothing else, however often the claim comes.

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/can_links/sim_link.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace {

constexpr std::uint8_t VCU_ADDRESS = 0x21;
constexpr std::uint8_t NULL_ADDRESS = 0xFE;
constexpr std::uint32_t PGN_ADDRESS_CLAIMED = 0xEE00;  // SAE J1939-81 PGN 60928
constexpr std::uint8_t SHM_PDU_FORMAT = 0x0E;          // SAE J1939-76 SHM PGN 0x0E00 (3584)
constexpr std::uint32_t S1_ES_SHM = 0x0C0EF321;        // the SHM of HHEA's ignition SDM, from 0x21
const std::string FAULT = "j1939_address_lost.vehicle";

can::Frame claimFrame(std::uint8_t address, std::uint64_t name) {
  can::Frame frame;
  frame.id = 0x18EEFF00u | address;  // priority 6, PGN 0xEE00, to global
  frame.flags = can::FLAG_EXTENDED;
  frame.length = 8;
  for (std::size_t i = 0; i < 8; ++i) frame.data[i] = static_cast<std::uint8_t>(name >> (8 * i));
  return frame;
}

std::uint64_t nameOf(const can::Frame& frame) {
  std::uint64_t name = 0;
  for (std::size_t i = 0; i < 8; ++i) name |= static_cast<std::uint64_t>(frame.data[i]) << (8 * i);
  return name;
}

std::string hexName(std::uint64_t name) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%016llX", static_cast<unsigned long long>(name));
  return text;
}

std::uint32_t pduFormat(std::uint32_t id) {
  return (id >> 16) & 0xFFu;
}
std::uint32_t pgnOf(std::uint32_t id) {
  const std::uint32_t pgn = (id >> 8) & 0x3FFFFu;
  return pduFormat(id) < 0xF0 ? pgn & 0x3FF00u : pgn;
}

/// What the VCU sent while the test listened.
struct Recording {
  std::set<std::uint8_t> vcuClaimAddresses;  ///< source addresses of claims with the VCU's NAME (0xFE: Cannot Claim)
  std::size_t pairsFromVcuAddress{};         ///< SHMs from 0x21
  std::size_t safetyFramesElsewhere{};       ///< SHMs or declared SDMs from any other address
  std::size_t framesFromVcuAfterLoss{};      ///< anything from 0x21 later than 50 ms after the claim
  std::vector<std::string> elsewhere;        ///< the first few of them, for the message
};

struct Listener {
  std::unique_ptr<can::Link> link;
  std::optional<ipc::EventBus> events;
  std::vector<ipc::FaultEvent> faults;
  std::vector<std::chrono::steady_clock::time_point> faultTimes;
  std::vector<std::uint32_t> sdms;  ///< the schedule's SDM CAN IDs (from 0x21)
  std::uint64_t vcuName{};

  /// Frames and events for `duration`; `lossAt`: frames from 0x21 after it plus 50 ms count.
  void record(Recording& out, std::chrono::milliseconds duration,
              std::optional<std::chrono::steady_clock::time_point> lossAt) {
    std::array<can::ReceivedFrame, 64> batch{};
    const auto end = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < end) {
      while (events->handle(std::chrono::milliseconds(0)) == ipc::HandleResult::Handled) {
      }
      const std::size_t count = link->receive(batch);
      const auto now = std::chrono::steady_clock::now();
      for (std::size_t i = 0; i < count; ++i) {
        const can::Frame& frame = batch[i].frame;
        if (!frame.extended()) continue;
        const std::uint32_t id = frame.id & 0x1FFFFFFFu;
        const auto source = static_cast<std::uint8_t>(id & 0xFFu);
        if (pgnOf(id) == PGN_ADDRESS_CLAIMED && frame.length == 8 && nameOf(frame) == vcuName) {
          out.vcuClaimAddresses.insert(source);
          continue;
        }
        bool safety = pduFormat(id) == SHM_PDU_FORMAT;
        for (const std::uint32_t sdm : sdms) safety |= (id & ~0xFFu) == (sdm & ~0xFFu);
        if (safety && source == VCU_ADDRESS && pduFormat(id) == SHM_PDU_FORMAT) ++out.pairsFromVcuAddress;
        if (safety && source != VCU_ADDRESS) {
          ++out.safetyFramesElsewhere;
          char text[16];
          std::snprintf(text, sizeof text, "%08X", static_cast<unsigned>(id));
          if (out.elsewhere.size() < 5) out.elsewhere.emplace_back(text);
        }
        if (lossAt && source == VCU_ADDRESS && now > *lossAt + std::chrono::milliseconds(50)) {
          ++out.framesFromVcuAfterLoss;
        }
      }
      if (count == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
};

}  // namespace

TEST_CASE("a hostile claim of 0x21 with a NAME one below the VCU's is a fault within 1 s and no J1939-76 pair moves") {
  SKIP_UNLESS_ISOLATED();
  ConfiguredStack s(copyHheaConfig(fs::temp_directory_path() / "hhea-claim"));
  REQUIRE_STATUS(s.sut.startRoudi());
  Listener l;
  auto bus = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, "hhea");
  REQUIRE_STATUS(bus);
  l.events.emplace(std::move(*bus));
  REQUIRE(l.events->onFault([&l](const ipc::FaultEvent& event) {
    l.faults.push_back(event);
    l.faultTimes.push_back(std::chrono::steady_clock::now());
  }));
  s.startService("can-rx", CAN_RX_BINARY);
  harness::Process& canTx = s.startService("can-tx", CAN_TX_BINARY);
  s.set("internal.tx.keepAlive", "1");

  const config::BusConfig& vehicleBus = s.vehicle->buses.at(0);
  REQUIRE(vehicleBus.j1939);
  l.vcuName = vehicleBus.j1939->name.toValue();
  const std::uint64_t hostileName = l.vcuName - 1;  // numerically lower: it wins the contest
  for (const dbc::Message& message : s.vehicle->database.messages) {
    if (message.extended && (message.id & 0xFFu) == VCU_ADDRESS && message.name.starts_with("S1_ES")) {
      l.sdms.push_back(message.id);
    }
  }
  REQUIRE_FALSE(l.sdms.empty());

  if (!ipc::Runtime::initialized()) REQUIRE_STATUS(ipc::Runtime::init("test-j1939-address-loss", 5s));
  auto opened = can::openSimLink("vehicle", can::LinkOptions{});
  REQUIRE_STATUS(opened);
  l.link = std::move(*opened);

  // The pairs run from 0x21 before the contest.
  Recording before;
  l.record(before, 1000ms, std::nullopt);
  REQUIRE_MESSAGE(before.pairsFromVcuAddress >= 10, canTx.output());
  REQUIRE(before.safetyFramesElsewhere == 0);

  // One hostile Address Claimed for 0x21.
  const auto claimedAt = std::chrono::steady_clock::now();
  REQUIRE(l.link->send(claimFrame(VCU_ADDRESS, hostileName)) == can::SendStatus::Sent);
  Recording after;
  l.record(after, 1500ms, claimedAt);

  std::string addresses;
  for (const std::uint8_t address : after.vcuClaimAddresses) addresses += " " + std::to_string(address);
  INFO("the VCU's claims came from:" << addresses << "; J1939-76 frames from elsewhere: " << after.safetyFramesElsewhere
                                     << " (first " << (after.elsewhere.empty() ? "-" : after.elsewhere.front()) << ")");
  // The VCU did not move: its only claim after the contest is Cannot Claim (from 0xFE).
  CHECK(after.vcuClaimAddresses == std::set<std::uint8_t>{NULL_ADDRESS});
  CHECK(after.safetyFramesElsewhere == 0);
  CHECK(after.framesFromVcuAfterLoss == 0);

  // The fault, within 1 s, names the bus, the address and the claimant's NAME.
  const ipc::FaultEvent* lost = nullptr;
  std::chrono::milliseconds latency{};
  for (std::size_t i = 0; i < l.faults.size(); ++i) {
    if (l.faults[i].name != FAULT || !l.faults[i].active) continue;
    lost = &l.faults[i];
    latency = std::chrono::duration_cast<std::chrono::milliseconds>(l.faultTimes[i] - claimedAt);
    break;
  }
  REQUIRE_MESSAGE(lost != nullptr, "no active fault " << FAULT << " among " << l.faults.size() << " fault events");
  MESSAGE("fault after " << latency.count() << " ms: " << lost->text);
  CHECK(latency < 1000ms);
  CHECK(lost->severity == ipc::FaultSeverity::Critical);
  CHECK(lost->source == "vcu-can-tx");
  CHECK(contains(lost->text, "bus 'vehicle'"));
  CHECK(contains(lost->text, "address 0x21 (33)"));
  CHECK(contains(lost->text, hexName(hostileName)));
  CHECK(contains(lost->text, "Cannot Claim"));

  // The claim again and again: the VCU stays silent, no second fault (it lost nothing new).
  const auto lossFaults = [&l] {
    return std::count_if(l.faults.begin(), l.faults.end(), [](const ipc::FaultEvent& e) { return e.name == FAULT; });
  };
  const auto faultsBefore = lossFaults();
  for (int i = 0; i < 5; ++i) REQUIRE(l.link->send(claimFrame(VCU_ADDRESS, hostileName)) == can::SendStatus::Sent);
  Recording repeated;
  l.record(repeated, 500ms, claimedAt);
  CHECK(repeated.vcuClaimAddresses.empty());
  CHECK(repeated.safetyFramesElsewhere == 0);
  CHECK(repeated.framesFromVcuAfterLoss == 0);
  CHECK(lossFaults() == faultsBefore);
}
