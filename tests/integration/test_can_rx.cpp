// vcu-can-rx as a process, inside the sandbox with the real iox-roudi and LCM:
//   - a J1939 log replayed through it yields, signal for signal, the canmatrix oracle's
//     last decoded values (team kit: tools/gen-j1939-log.py and tools/dbc-oracle.py);
//   - a silent ECU is flagged stale within its timeout and recovers (LCM fault events);
//   - a multi-packet DM1 (BAM) becomes DTC fault events and DM1 slots;
//   - a J1939-76 pair with a bad CRC is refused with a fault.
// The logs are written by the test into the sandbox's private /tmp.

#include <doctest/doctest.h>

#include "skip.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "integration_support.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/signals/table.hpp"

namespace {

const std::string CAN_RX = CAN_RX_BINARY;
const std::string KIT = OPENVCU_TEAM_KIT;
const std::string RX_DBC = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/can-rx/rx.dbc";

void writeFile(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

/// A candump -L line.
std::string line(double seconds, std::uint32_t id, const std::vector<std::uint8_t>& data, bool extended = true) {
  char head[64];
  std::snprintf(head, sizeof head, extended ? "(%.6f) can0 %08X#" : "(%.6f) can0 %03X#", seconds, id);
  std::string text = head;
  for (const std::uint8_t byte : data) {
    char hex[3];
    std::snprintf(hex, sizeof hex, "%02X", byte);
    text += hex;
  }
  return text + "\n";
}

/// vehicle.json for rx.dbc with one replayed bus.
std::string rxVehicle(const std::string& instance, const fs::path& log, const std::string& receive = {}) {
  std::string json = R"({"instance": ")" + instance + R"(", "node": "VCU", "dbc": ")" + RX_DBC + R"(",)";
  if (!receive.empty()) json += R"("receive": ")" + receive + R"(",)";
  json += R"("buses": [{"name": "a", "link": "replay:)" + log.string() +
          R"(", "filter": "all", "messages": "all"}]})";
  return json;
}

harness::Process& startCanRx(harness::Harness& sut, const fs::path& config) {
  auto process = sut.start({.name = "can-rx",
                            .argv = {CAN_RX, "--config", config.string()},
                            .notifyReadiness = true,
                            .captureOutput = true});
  REQUIRE_STATUS(process);
  return **process;
}

std::optional<signals::SignalTable> attachTable(const fs::path& config, signals::Catalog& catalog) {
  auto vehicle = config::loadVehicleConfig(config.string());
  REQUIRE_MESSAGE(vehicle, (vehicle ? "" : vehicle.error().toString()));
  auto catalogResult = config::buildCatalog(*vehicle);
  REQUIRE(catalogResult);
  catalog = std::move(*catalogResult);
  auto table = signals::SignalTable::open(catalog, vehicle->instance, signals::OpenMode::AttachOnly);
  REQUIRE_MESSAGE(table, (table ? "" : table.error().toString()));
  return std::move(*table);
}

/// Collects fault events from LCM while `waitFor` runs.
struct FaultListener {
  std::optional<ipc::EventBus> bus;
  std::vector<ipc::FaultEvent> faults;
  explicit FaultListener(const std::string& instance) {
    auto opened = ipc::EventBus::open(ipc::DEFAULT_EVENT_URL, instance);
    REQUIRE_MESSAGE(opened, (opened ? "" : opened.error().toString()));
    bus.emplace(std::move(*opened));
    REQUIRE(bus->onFault([this](const ipc::FaultEvent& event) { faults.push_back(event); }));
  }
  /// Handles LCM traffic until `done()` or the timeout.
  template <typename Done>
  bool waitFor(Done done, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!done()) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      (void)bus->handle(50ms);
    }
    return true;
  }
  [[nodiscard]] const ipc::FaultEvent* find(const std::string& name, bool active) const {
    for (const ipc::FaultEvent& event : faults) {
      if (event.name == name && event.active == active) return &event;
    }
    return nullptr;
  }
};

}  // namespace

TEST_CASE("a J1939 log replayed through vcu-can-rx leaves the canmatrix oracle's values in the table") {
  SKIP_UNLESS_ISOLATED();
  if (!fs::exists(KIT + "/tools/dbc-oracle.py")) {
    OPENVCU_SKIP("skipped: the team kit (tools/dbc-oracle.py, gen-j1939-log.py) is not beside the repository");
  }
  harness::Harness sut;
  const fs::path dir = fs::temp_directory_path() / "can-rx-oracle";
  fs::create_directories(dir);
  const auto generated = sut.run({"/usr/bin/python3", KIT + "/tools/gen-j1939-log.py", "--frames", "10000",
                                  "--out-dir", dir.string()},
                                 120s);
  REQUIRE_MESSAGE(generated.exitCode() == 0, generated.describe());
  const fs::path dbc = dir / "synthetic_j1939.dbc";
  const fs::path log = dir / "synthetic_j1939.log";
  const fs::path config = dir / "vehicle.json";
  writeFile(config, R"({"instance": "oracle", "node": "ECU_X", "dbc": ")" + dbc.string() +
                        R"(", "buses": [{"name": "can0", "link": "replay:)" + log.string() +
                        R"(", "filter": "all", "replay": {"speed": 0}, "messages": "all"}]})");

  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& canRx = startCanRx(sut, config);
  REQUIRE_MESSAGE(canRx.waitForLine("ReplayFinished", 120s), canRx.output());

  const auto oracle = sut.run({"/usr/bin/python3", KIT + "/tools/dbc-oracle.py", "decode", dbc.string(), log.string()},
                              300s);
  REQUIRE_MESSAGE(oracle.exitCode() == 0, oracle.describe());
  // The oracle's last value of every signal (multiplexed signals: when last active).
  std::map<std::string, double> expected;
  std::size_t decodedFrames = 0;
  std::istringstream lines(oracle.out);
  for (std::string text; std::getline(lines, text);) {
    const auto json = nlohmann::json::parse(text, nullptr, false);
    if (json.is_discarded() || !json.contains("msg") || !json["msg"].is_string() || !json.contains("signals")) continue;
    ++decodedFrames;
    for (const auto& [name, value] : json["signals"].items()) {
      if (value.is_number()) expected["Vector__XXX." + json["msg"].get<std::string>() + "." + name] = value.get<double>();
    }
  }
  REQUIRE(decodedFrames > 9000);
  signals::Catalog catalog;
  auto table = attachTable(config, catalog);
  std::size_t compared = 0;
  for (const auto& [key, value] : expected) {
    CAPTURE(key);
    const auto index = catalog.indexOf(key);
    REQUIRE(index);
    const auto bus = table->readBus(*index);
    REQUIRE(bus);
    CHECK(bus->quality != signals::Quality::NeverReceived);
    CHECK(bus->value == doctest::Approx(value).epsilon(1e-12));
    ++compared;
  }
  MESSAGE("compared " << compared << " signals after " << decodedFrames << " frames decoded by the oracle");
  CHECK(compared > 100);
}

TEST_CASE("a silent ECU is flagged stale within its timeout and recovers when it speaks again") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  const fs::path dir = fs::temp_directory_path() / "can-rx-stale";
  fs::create_directories(dir);
  // ECU1_Status (cycle 20 ms, timeout 3 x 20 = 60 ms): every 20 ms for 0.5 s, silent for
  // 0.4 s, then again. The log starts 1 s in so that can-rx is ready before frames flow.
  std::string text;
  for (int i = 0; i <= 25; ++i) text += line(1.0 + i * 0.02, 0x18FF1010, {static_cast<std::uint8_t>(i), 0, 1, 0, 0, 0, 0, 0});
  for (int i = 0; i <= 25; ++i) text += line(1.9 + i * 0.02, 0x18FF1010, {static_cast<std::uint8_t>(i), 1, 1, 0, 0, 0, 0, 0});
  writeFile(dir / "stale.log", text);
  writeFile(dir / "receive.json", R"({"messages": {"ECU1_Big": {"timeoutMs": 0}, "BMS_Safe": {"timeoutMs": 0},
                                      "Std_Msg": {"timeoutMs": 0}}})");
  writeFile(dir / "vehicle.json", rxVehicle("stale", dir / "stale.log", (dir / "receive.json").string()));
  FaultListener listener("stale");
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& canRx = startCanRx(sut, dir / "vehicle.json");

  const std::string fault = "rx_timeout.a.ECU1_Status";
  const bool recovered = listener.waitFor(
      [&] {
        const ipc::FaultEvent* raised = listener.find(fault, true);
        return raised != nullptr && raised->text.find("not received") != std::string::npos &&
               listener.find(fault, false) != nullptr;
      },
      20s);
  REQUIRE_MESSAGE(recovered, canRx.output());
  // The first raise may be "never received" (before the first frame, 1 s into the log);
  // the one that matters is the raise after the silence and the clear that follows it.
  const ipc::FaultEvent* raised = nullptr;
  const ipc::FaultEvent* cleared = nullptr;
  for (const ipc::FaultEvent& event : listener.faults) {
    if (event.name != fault) continue;
    if (event.active && event.text.find("not received for 60 ms") != std::string::npos) raised = &event;
    if (!event.active && raised != nullptr && cleared == nullptr) cleared = &event;
  }
  REQUIRE(raised != nullptr);
  REQUIRE(cleared != nullptr);
  // Last frame at 1.50 s, stale after 1.56 s (+ one tick of 15 ms), next frame at 1.90 s:
  // the clear follows the raise by 0.34 s minus up to a tick.
  const double betweenMs = static_cast<double>(cleared->timestampNs - raised->timestampNs) / 1e6;
  CHECK_MESSAGE(betweenMs > 250.0, betweenMs);
  CHECK_MESSAGE(betweenMs < 400.0, betweenMs);
  CHECK(canRx.waitForLine("fault raised: " + fault, 5s));
}

TEST_CASE("a multi-packet DM1 from the battery appears as DTC faults and in the DM1 slots") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  const fs::path dir = fs::temp_directory_path() / "can-rx-dm1";
  fs::create_directories(dir);
  // BMS (SA 0xF3) DM1 over BAM: amber lamp on, 3 DTCs (SPN 100 FMI 1, SPN 10000 FMI 2, SPN 524287 FMI 4).
  const std::vector<std::uint8_t> dm1{0x04, 0xFF, 100, 0, 1, 1, 0x10, 0x27, 0x02, 2, 0xFF, 0xFF, 0xE4, 7};
  std::string text = line(1.00, 0x1CECFFF3, {0x20, 14, 0, 2, 0xFF, 0xCA, 0xFE, 0x00});
  std::vector<std::uint8_t> first{1};
  first.insert(first.end(), dm1.begin(), dm1.begin() + 7);
  std::vector<std::uint8_t> second{2};
  second.insert(second.end(), dm1.begin() + 7, dm1.end());
  text += line(1.05, 0x1CEBFFF3, first) + line(1.10, 0x1CEBFFF3, second);
  writeFile(dir / "dm1.log", text);
  writeFile(dir / "vehicle.json", rxVehicle("dm1", dir / "dm1.log"));
  FaultListener listener("dm1");
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& canRx = startCanRx(sut, dir / "vehicle.json");

  const std::vector<std::string> names{"dm1.BMS.spn100.fmi1", "dm1.BMS.spn10000.fmi2", "dm1.BMS.spn524287.fmi4"};
  const bool all = listener.waitFor(
      [&] {
        for (const std::string& name : names) {
          if (listener.find(name, true) == nullptr) return false;
        }
        return true;
      },
      20s);
  REQUIRE_MESSAGE(all, canRx.output());
  signals::Catalog catalog;
  auto table = attachTable(dir / "vehicle.json", catalog);
  CHECK(table->readBus(*catalog.indexOf("internal.dm1.BMS.activeDtcs"))->value == 3.0);
  CHECK(table->readBus(*catalog.indexOf("internal.dm1.BMS.amberWarningLamp"))->value == 1.0);
  CHECK(table->readBus(*catalog.indexOf("internal.dm1.BMS.firstSpn"))->value == 100.0);
}

TEST_CASE("a J1939-76 pair with a bad CRC is refused with a fault, good pairs are used") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  const fs::path dir = fs::temp_directory_path() / "can-rx-safety";
  fs::create_directories(dir);
  constexpr std::uint32_t SDM = 0x0CFF50F3;
  j1939::SafetyPairBuilder builder(SDM);
  std::string text;
  for (std::uint8_t n = 1; n <= 4; ++n) {
    const std::array<std::uint8_t, 8> data{n, 0x10, 0x27, 0, 0, 0, 0, 0};
    const auto header = builder.nextHeader(j1939::SafetyDataView(data));
    std::vector<std::uint8_t> sdm(data.begin(), data.end());
    if (n == 4) sdm[0] = 9;  // changed after the CRC: must be refused
    text += line(1.0 + n * 0.05, builder.headerCanId(), {header.begin(), header.end()});
    text += line(1.0 + n * 0.05 + 0.002, SDM, sdm);
  }
  writeFile(dir / "safety.log", text);
  writeFile(dir / "receive.json", R"({"safety": [{"message": "BMS_Safe", "maxDelayMs": 10, "headerCycleMs": 100}]})");
  writeFile(dir / "vehicle.json", rxVehicle("safety", dir / "safety.log", (dir / "receive.json").string()));
  FaultListener listener("safety");
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& canRx = startCanRx(sut, dir / "vehicle.json");

  REQUIRE_MESSAGE(listener.waitFor([&] { return listener.find("j1939_76.BMS_Safe", true) != nullptr; }, 20s),
                  canRx.output());
  CHECK(contains(listener.find("j1939_76.BMS_Safe", true)->text, "CrcMismatch"));
  signals::Catalog catalog;
  auto table = attachTable(dir / "vehicle.json", catalog);
  CHECK(table->readBus(*catalog.indexOf("BMS.BMS_Safe.ContactorState"))->value == 3.0);  // pair 3, not 9
}

TEST_CASE("a frame sent on a sim bus is decoded by vcu-can-rx and forwarded to the other bus's send stream") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  const fs::path dir = fs::temp_directory_path() / "can-rx-forward";
  fs::create_directories(dir);
  writeFile(dir / "receive.json",
            R"({"forward": [{"from": "a", "to": "b", "id": "0x18FF1010", "rewriteId": "0x18FF1011"}]})");
  writeFile(dir / "vehicle.json", R"({"instance": "fwd", "node": "VCU", "dbc": ")" + RX_DBC + R"(",
    "receive": ")" + (dir / "receive.json").string() + R"(",
    "buses": [{"name": "a", "link": "sim:fwda", "messages": ["ECU1_Status", "ECU1_Big", "BMS_Safe", "VCU_Cmd", "Std_Msg"]},
              {"name": "b", "link": "sim:fwdb", "messages": ["GW_Info"]}]})");
  const std::string config = (dir / "vehicle.json").string();
  REQUIRE_STATUS(sut.startRoudi());
  harness::Process& canRx = startCanRx(sut, dir / "vehicle.json");
  auto dump = sut.start({.name = "dump",
                         .argv = {VCU, "dump", "b", "--stream", "send", "--count", "1", "--timeout", "20", "--config",
                                  config},
                         .captureOutput = true});
  REQUIRE_STATUS(dump);
  REQUIRE_MESSAGE((*dump)->waitForLine("listening", 20s), (*dump)->output());

  const auto sent = sut.run({VCU, "send", "--direct", "a", "18FF1010#E803020000000000", "--config", config});
  REQUIRE_MESSAGE(sent.exitCode() == 0, sent.describe());

  const auto forwarded = (*dump)->waitForLine("18FF1011#", 20s);
  REQUIRE_MESSAGE(forwarded, ((*dump)->output() + "\n" + canRx.output()));
  CHECK(contains(*forwarded, " b 18FF1011#E803020000000000"));
  signals::Catalog catalog;
  auto table = attachTable(dir / "vehicle.json", catalog);
  const auto speed = table->readBus(*catalog.indexOf("ECU1.ECU1_Status.Speed"));
  REQUIRE(speed);
  CHECK(speed->value == doctest::Approx(100.0));
  CHECK(speed->quality == signals::Quality::Valid);
}
