// Issue 18: J1939-76 safety pairs must be unambiguous on the wire. A J1939-76 receiver takes
// the first frame after an SHM that has the PGN, source and destination address the SHM
// names as its SDM; the priority is not compared. vcu-can-tx runs on the HHEA configuration
// (S1_ES_PGN61427 0x0CEFF321, an SDM, and PropA_C4_PGN61184 0x18EFF321 share PGN 0xEF00,
// SA 0x21, DA 0xF3), its keep-alive group on; every frame it sends on sim:vehicle is
// recorded and passed through the checker below, written here from the J1939-76 rules (its
// own identifier math and CRC-32, not can-tx's or shared/j1939's code). It must find no
// ambiguity (the frame taken as SDM is another message) and no CRC or sequence fault.
// The checker's own case (no sandbox needed) shows it catches the old ordering.

#include <doctest/doctest.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/can_links/sim_link.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/ipc/runtime.hpp"

namespace {

const std::string CAN_TX = CAN_TX_BINARY;

constexpr std::uint32_t S1_ES = 0x0CEFF321;     ///< SDM, priority 3, PGN 0xEF00, SA 0x21, DA 0xF3
constexpr std::uint32_t PROPA_C4 = 0x18EFF321;  ///< not an SDM: priority 6, the same PGN, SA and DA
constexpr std::uint32_t S1_ES_SHM = 0x0C0EF321;
constexpr std::uint8_t SHM_PDU_FORMAT = 0x0E;  ///< SAE J1939-76 SHM PGN 0x0E00 (3584), PDU1

/// J1939-76 CRC-32 bit by bit: polynomial 0x6938392D, initial 0xFFFFFFFF, not reflected,
/// final XOR 0 (EF FF FF FF FF FF FF FF -> 0x8100EFA3, the thesis' example).
std::uint32_t crc32(const std::uint8_t* data, std::size_t length) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < length; ++i) {
    crc ^= static_cast<std::uint32_t>(data[i]) << 24;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 0x80000000u) != 0 ? (crc << 1) ^ 0x6938392Du : crc << 1;
  }
  return crc;
}

/// A J1939-76 receiver for every SDM of the recording. `sdmIds` are the identifiers the
/// schedule declares as SDMs; they only tell an ambiguity (the frame taken is another
/// message) from a mere CRC fault, and an SDM without its SHM.
class J1939_76Checker {
 public:
  struct Verdicts {
    std::size_t pairs{};           ///< SDMs taken after their SHM
    std::size_t ambiguities{};     ///< the frame taken as the SDM was not the declared SDM
    std::size_t crcFaults{};       ///< CRC in the SHM differs from the CRC of the frame taken
    std::size_t sequenceFaults{};  ///< sequence number not previous + 1 mod 32
    std::size_t headerFaults{};    ///< SHM not 8 bytes, or its SA / DA disagree with the SDM it names
    std::size_t lostSdms{};        ///< an SHM replaced by the next SHM for the same SDM
    std::size_t sdmsWithoutShm{};  ///< a declared SDM identifier with no SHM waiting
  };

  explicit J1939_76Checker(std::vector<std::uint32_t> sdmIds) : m_sdmIds(std::move(sdmIds)) {}

  void onFrame(const can::Frame& frame) {
    if (!frame.extended()) return;
    const std::uint32_t id = frame.id & 0x1FFFFFFFu;
    const auto pduFormat = static_cast<std::uint8_t>(id >> 16);
    if (pduFormat == SHM_PDU_FORMAT && ((id >> 24) & 3u) == 0) {
      onHeader(id, frame);
      return;
    }
    // identity = EDP, DP, PF, PS, SA: the PGN, DA and SA; the priority bits are dropped
    const std::uint32_t identity = id & 0x03FFFFFFu;
    const auto waiting = m_waiting.find(identity);
    if (waiting == m_waiting.end()) {
      for (const std::uint32_t sdm : m_sdmIds) {
        if (id == sdm && m_started) ++m_verdicts.sdmsWithoutShm;
      }
      return;
    }
    const Header header = waiting->second;
    m_waiting.erase(waiting);
    ++m_verdicts.pairs;
    if (!isDeclaredSdm(id)) ++m_verdicts.ambiguities;
    if (frame.length != 8 || crc32(frame.data.data(), 8) != header.crc) ++m_verdicts.crcFaults;
    const auto last = m_lastSequence.find(identity);
    if (last != m_lastSequence.end() && header.sequence != (last->second + 1) % 32) ++m_verdicts.sequenceFaults;
    m_lastSequence[identity] = header.sequence;
  }

  [[nodiscard]] const Verdicts& verdicts() const { return m_verdicts; }

 private:
  struct Header {
    std::uint8_t sequence{};
    std::uint32_t crc{};
  };

  void onHeader(std::uint32_t id, const can::Frame& frame) {
    m_started = true;
    if (frame.length != 8) {
      ++m_verdicts.headerFaults;
      return;
    }
    const std::uint8_t* d = frame.data.data();
    // byte 0: sequence << 3 | reserved | ~EDP << 1 | ~DP; bytes 1..3: ~SA, ~PS, ~PF; 4..7 CRC LSB first
    const std::uint32_t edp = (~d[0] >> 1) & 1u;
    const std::uint32_t dp = ~d[0] & 1u;
    const auto sa = static_cast<std::uint8_t>(~d[1]);
    const auto ps = static_cast<std::uint8_t>(~d[2]);
    const auto pf = static_cast<std::uint8_t>(~d[3]);
    const std::uint32_t identity =
        edp << 25 | dp << 24 | static_cast<std::uint32_t>(pf) << 16 | static_cast<std::uint32_t>(ps) << 8 | sa;
    const auto shmSource = static_cast<std::uint8_t>(id);
    const auto shmDestination = static_cast<std::uint8_t>(id >> 8);
    const std::uint8_t sdmDestination = pf < 0xF0 ? ps : 0xFF;
    if (shmSource != sa || shmDestination != sdmDestination) ++m_verdicts.headerFaults;
    if (m_waiting.count(identity) != 0) ++m_verdicts.lostSdms;
    m_waiting[identity] = Header{static_cast<std::uint8_t>(d[0] >> 3),
                                 static_cast<std::uint32_t>(d[4]) | static_cast<std::uint32_t>(d[5]) << 8 |
                                     static_cast<std::uint32_t>(d[6]) << 16 | static_cast<std::uint32_t>(d[7]) << 24};
  }

  [[nodiscard]] bool isDeclaredSdm(std::uint32_t id) const {
    for (const std::uint32_t sdm : m_sdmIds) {
      if (id == sdm) return true;
    }
    return false;
  }

  std::vector<std::uint32_t> m_sdmIds;
  std::map<std::uint32_t, Header> m_waiting;  ///< by SDM identity: the SHM waiting for its SDM
  std::map<std::uint32_t, std::uint8_t> m_lastSequence;
  Verdicts m_verdicts;
  bool m_started{};  ///< an SHM was seen: an SDM before the first one lost its SHM to the recording's start
};

can::Frame frameOf(std::uint32_t id, std::array<std::uint8_t, 8> data) {
  can::Frame frame;
  frame.id = id;
  frame.flags = can::FLAG_EXTENDED;
  frame.length = 8;
  std::copy(data.begin(), data.end(), frame.data.begin());
  return frame;
}

/// The SDM identifiers the schedule file of `vehicle` declares ("safety" entries).
std::vector<std::uint32_t> declaredSdms(const fs::path& vehicleFile) {
  auto loaded = config::loadVehicleConfig(vehicleFile.string());
  REQUIRE_STATUS(loaded);
  std::ifstream in(vehicleFile.parent_path() / "schedule.json");
  const nlohmann::json schedule = nlohmann::json::parse(in);
  std::vector<std::uint32_t> ids;
  for (const auto& [name, entry] : schedule["messages"].items()) {
    if (!entry.contains("safety")) continue;
    const dbc::Message* message = loaded->database.findMessage(name);
    REQUIRE_MESSAGE(message, name);
    ids.push_back(message->id);
  }
  return ids;
}

std::string describe(const J1939_76Checker::Verdicts& v) {
  return "pairs " + std::to_string(v.pairs) + ", ambiguities " + std::to_string(v.ambiguities) + ", CRC faults " +
         std::to_string(v.crcFaults) + ", sequence faults " + std::to_string(v.sequenceFaults) + ", header faults " +
         std::to_string(v.headerFaults) + ", lost SDMs " + std::to_string(v.lostSdms) + ", SDMs without SHM " +
         std::to_string(v.sdmsWithoutShm);
}

}  // namespace

TEST_CASE("the independent J1939-76 checker finds the ambiguity of issue 18 and accepts the pair sent back to back") {
  // the thesis' pair, sequence 15: SDM EF FF .. FF, SHM 7F DE 0C 10 A3 EF 00 81
  const can::Frame shm = frameOf(S1_ES_SHM, {0x7F, 0xDE, 0x0C, 0x10, 0xA3, 0xEF, 0x00, 0x81});
  const can::Frame sdm = frameOf(S1_ES, {0xEF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF});
  const can::Frame propA = frameOf(PROPA_C4, {0xFF, 0x0F, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF});
  REQUIRE(crc32(sdm.data.data(), 8) == 0x8100EFA3u);

  J1939_76Checker oldOrder({S1_ES});  // the recording of issue 18: PropA_C4 between SHM and SDM
  for (const can::Frame& frame : {shm, propA, sdm}) oldOrder.onFrame(frame);
  CHECK(oldOrder.verdicts().pairs == 1);
  CHECK(oldOrder.verdicts().ambiguities == 1);
  CHECK(oldOrder.verdicts().crcFaults == 1);
  CHECK(oldOrder.verdicts().sdmsWithoutShm == 1);

  J1939_76Checker newOrder({S1_ES});
  for (const can::Frame& frame : {shm, sdm, propA}) newOrder.onFrame(frame);
  CHECK(newOrder.verdicts().pairs == 1);
  CHECK(newOrder.verdicts().ambiguities == 0);
  CHECK(newOrder.verdicts().crcFaults == 0);
  CHECK(newOrder.verdicts().sdmsWithoutShm == 0);

  // the next pair must carry sequence 16; a repeated 15 is a sequence fault
  newOrder.onFrame(shm);
  newOrder.onFrame(sdm);
  CHECK(newOrder.verdicts().sequenceFaults == 1);
}

TEST_CASE("issue 18: every frame vcu-can-tx sends on HHEA passes a J1939-76 receiver: no ambiguity, no CRC fault") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  REQUIRE_STATUS(sut.startRoudi());
  const fs::path config = copyHheaConfig(fs::temp_directory_path() / "hhea");
  const std::vector<std::uint32_t> sdms = declaredSdms(config);
  REQUIRE(std::find(sdms.begin(), sdms.end(), S1_ES) != sdms.end());

  auto canTx = sut.start(harness::ProcessSpec{
      .name = "can-tx", .argv = {CAN_TX, "--config", config.string()}, .notifyReadiness = true, .captureOutput = true});
  REQUIRE_STATUS(canTx);
  if (!ipc::Runtime::initialized()) REQUIRE_STATUS(ipc::Runtime::init("test-j1939-76-wire", 5s));
  auto opened = can::openSimLink("vehicle", can::LinkOptions{});
  REQUIRE_STATUS(opened);
  std::unique_ptr<can::Link> link = std::move(*opened);

  std::vector<std::string> argv{VCU, "signal", "set", "internal.tx.keepAlive", "1", "--config", config.string()};
  const auto keepAlive = sut.run(argv);
  REQUIRE_MESSAGE(contains(keepAlive.out, "accepted"), keepAlive.describe());

  // 3 s of everything on the bus (can-tx is the only sender): ~150 S1_ES pairs and as many PropA_C4
  J1939_76Checker checker(sdms);
  std::size_t s1Frames = 0;
  std::size_t propAFrames = 0;
  std::array<can::ReceivedFrame, 64> batch{};
  const auto end = std::chrono::steady_clock::now() + 3s;
  while (std::chrono::steady_clock::now() < end) {
    const std::size_t count = link->receive(batch);
    for (std::size_t i = 0; i < count; ++i) {
      checker.onFrame(batch[i].frame);
      s1Frames += batch[i].frame.id == S1_ES ? 1 : 0;
      propAFrames += batch[i].frame.id == PROPA_C4 ? 1 : 0;
    }
    if (count == 0) std::this_thread::sleep_for(1ms);
  }
  CHECK_MESSAGE(link->stats().receiveDropped == 0, "the recorder's queue overflowed");

  const J1939_76Checker::Verdicts& verdicts = checker.verdicts();
  MESSAGE("J1939-76 receiver over 3 s of vcu-can-tx on HHEA: " << describe(verdicts) << "; S1_ES frames " << s1Frames
                                                               << ", PropA_C4 frames " << propAFrames);
  CHECK(verdicts.pairs >= 140 + 2 * 25);  // S1_ES every 20 ms, HVESSC1 and CCVS1 every 100 ms, CN, AMB
  CHECK(verdicts.ambiguities == 0);
  CHECK(verdicts.crcFaults == 0);
  CHECK(verdicts.sequenceFaults == 0);
  CHECK(verdicts.headerFaults == 0);
  CHECK(verdicts.lostSdms == 0);
  CHECK(verdicts.sdmsWithoutShm == 0);
  CHECK(propAFrames >= 140);  // held behind the SDM, never dropped
  CHECK(s1Frames >= 140);

  // the start-up warning names both messages
  REQUIRE(sut.stop(**canTx));
  const std::string output = (*canTx)->output();
  CHECK_MESSAGE(contains(output, "S1_ES_PGN61427 (0x0CEFF321, J1939-76 SDM) and PropA_C4_PGN61184 (0x18EFF321)"),
                output);
}
