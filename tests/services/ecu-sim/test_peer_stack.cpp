// Issue 24 on the simulated bus: vcu-ecu-sim's scripted J1939 peer (tests/data/j1939-peer/
// simulation.json over a copy of config/hhea) beside iox-roudi, vcu-can-rx and vcu-can-tx.
// The peer requests DM1, SOFT and ECU ID (both longer than 8 bytes: RTS/CTS to the peer)
// and DM2 from the VCU, then claims 0x21 with a NAME of higher priority. HHEA's own NAME is
// fixed (it sends J1939-76 pairs from 0x21); this copy makes it arbitrary address capable,
// so the VCU must move into 128..247, send its schedule from there except the J1939-76
// pairs (they leave only from 0x21) and answer DM1 at its new address.

#include <regex>

#include "integration_support.hpp"

namespace {

const fs::path PEER_SIMULATION = fs::path(OPENVCU_SOURCE_DIR) / "tests" / "data" / "j1939-peer" / "simulation.json";
constexpr std::uint64_t PEER_NAME = 0x3002800000000007u;

/// The counter `name=` of vcu-ecu-sim's line in `vcu status`, or empty.
std::optional<long long> counter(const std::string& status, const std::string& name) {
  std::istringstream lines(status);
  for (std::string line; std::getline(lines, line);) {
    if (!contains(line, "vcu-ecu-sim")) continue;
    std::smatch match;
    if (std::regex_search(
            line, match, std::regex("(^|[ ,])" + std::regex_replace(name, std::regex("\\."), "\\.") + "=(-?[0-9]+)"))) {
      return std::stoll(match[2].str());
    }
  }
  return std::nullopt;
}

}  // namespace

TEST_CASE("#24 a scripted J1939 peer gets DM1, DM2 and identification from the VCU, takes 0x21 and the VCU moves") {
  SKIP_UNLESS_ISOLATED();
  const fs::path vehicle = copyHheaConfig(fs::temp_directory_path() / "hhea-peer");
  fs::copy_file(PEER_SIMULATION, vehicle.parent_path() / "simulation.json", fs::copy_options::overwrite_existing);
  {
    std::ifstream in(vehicle);
    nlohmann::json document = nlohmann::json::parse(in);
    document["buses"][0]["j1939"]["name"]["arbitraryAddressCapable"] = true;
    std::ofstream(vehicle) << document.dump(2);
  }
  ConfiguredStack s(vehicle);
  REQUIRE_STATUS(s.sut.startRoudi());
  s.startService("can-rx", CAN_RX_BINARY);
  s.startService("can-tx", CAN_TX_BINARY);
  s.openTable();
  s.set("internal.tx.keepAlive", "1");  // the VCU's keep-alive schedule runs (no FSM here)
  harness::Process& sim = s.startService("ecu-sim", ECU_SIM_BINARY);

  // The peer's global Request for Address Claimed finds the VCU at its preferred 0x21.
  REQUIRE_MESSAGE(sim.waitForLine("j1939 peer: the VCU claimed 0x21", 3s), sim.output());
  // SOFT and ECU ID come by RTS/CTS to the peer (logged with their text), DM1/DM2 decoded.
  CHECK_MESSAGE(sim.waitForLine("j1939 peer: answer PGN 65226 from 0x21", 3s), sim.output());
  CHECK_MESSAGE(sim.waitForLine("j1939 peer: answer PGN 65242 from 0x21", 3s), sim.output());
  CHECK_MESSAGE(sim.waitForLine("j1939 peer: answer PGN 64965 from 0x21", 3s), sim.output());
  CHECK_MESSAGE(sim.waitForLine("j1939 peer: answer PGN 65227 from 0x21", 3s), sim.output());
  // The contest: the peer's NAME is lower, the VCU moves to a free address of 128..247.
  const auto moved = sim.waitForLine("j1939 peer: the VCU claimed 0x", 4s);
  REQUIRE_MESSAGE(moved, sim.output());
  const int address = std::stoi(moved->substr(moved->find("claimed 0x") + 8), nullptr, 16);
  CHECK(address >= 128);
  CHECK(address <= 247);
  const std::string again = "j1939 peer: answer PGN 65226 from " + moved->substr(moved->find("claimed 0x") + 8);
  CHECK_MESSAGE(sim.waitForLine(again, 3s), sim.output());

  // The counters, as the heartbeat carries them.
  const auto status = s.vcu({"status"});
  INFO(status.describe());
  CHECK(counter(status.out, "peer_vcu_address") == address);
  CHECK(counter(status.out, "peer_address") == 0x21);
  CHECK(counter(status.out, "peer_answers.65226") == 2);
  CHECK(counter(status.out, "peer_answers.65242") == 1);
  CHECK(counter(status.out, "peer_answers.64965") == 1);
  CHECK(counter(status.out, "peer_answers.65227") == 1);
  CHECK(counter(status.out, "peer_tp_completed") >= 2);
  CHECK(counter(status.out, "peer_dm1_dtcs") >= 0);

  // can-tx's view: the VCU claimed its new address, the peer's NAME is known at 0x21.
  const auto view = s.vcu({"j1939", "--json", "--timeout", "3"});
  REQUIRE_MESSAGE(view.exitCode() == 0, view.describe());
  const nlohmann::json document = nlohmann::json::parse(view.out.substr(view.out.find('{')));
  REQUIRE(document["buses"].size() == 1);
  const nlohmann::json& bus = document["buses"][0];
  CHECK(bus["claimState"] == "claimed");
  CHECK(bus["address"] == address);
  bool peerListed = false;
  char peerName[32];
  std::snprintf(peerName, sizeof peerName, "0x%016llX", static_cast<unsigned long long>(PEER_NAME));
  for (const nlohmann::json& node : bus["nodes"]) peerListed |= node["address"] == 0x21 && node["name"] == peerName;
  CHECK_MESSAGE(peerListed, bus.dump());

  // The schedule now comes from the new address: PropA_C4 (PGN 0xEF00 to 0xF3) on the wire;
  // the J1939-76 pairs (S1_ES 0x0CEFF321 and its SHM 0x0C0EF321) from neither address.
  const auto wire = s.vcu({"dump", "vehicle", "--stream", "wire", "-n", "200", "--timeout", "2"});
  char propA[16];
  std::snprintf(propA, sizeof propA, "18EFF3%02X#", address);
  CHECK_MESSAGE(contains(wire.out, propA), wire.describe());
  CHECK_MESSAGE(!contains(wire.out, "18EFF321#"), wire.describe());
  char s1Es[16];
  char s1EsShm[16];
  std::snprintf(s1Es, sizeof s1Es, "0CEFF3%02X#", address);
  std::snprintf(s1EsShm, sizeof s1EsShm, "0C0EF3%02X#", address);
  CHECK_MESSAGE(!contains(wire.out, s1Es), wire.describe());
  CHECK_MESSAGE(!contains(wire.out, s1EsShm), wire.describe());
  CHECK_MESSAGE(!contains(wire.out, "0C0EF321#"), wire.describe());
}
