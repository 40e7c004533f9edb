// `vcu fleet watch|get` against a real mosquitto and real vcu-telemetry processes (issue 25),
// inside the sandbox of tests/harness/run_isolated.sh (loopback only): three vehicles of one
// HHEA configuration as separate instances (--instance, --vehicle-id, --queue-folder), this
// test writing their SOC into each signal table and publishing FSM transitions on each
// instance's events. Checked:
//   - a broker that is not there: a clear error naming it, exit 1;
//   - `vcu fleet watch` in a pipe prints one line per change: both vehicles online with the
//     state of their transition and their SOC; the third, SIGKILLed, turns offline (its will);
//   - `vcu fleet watch --once` lists all three, online/offline right, within its wait;
//   - `vcu fleet get`: status, a signal, a state sent while it waits; an unknown vehicle and a
//     key never told exit 1 with a message.
#include <doctest/doctest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <thread>

#include "broker_fixture.hpp"
#include "harness/harness.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/signals/table.hpp"
#include "skip.hpp"

namespace {

using namespace openvcu;
using namespace std::chrono_literals;
using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr int PORT = 1883;
constexpr const char* BROKER = "mqtt://127.0.0.1:1883";
constexpr const char* SOC_KEY = "VIC.HVESSD2_PGN61585.HS_FastUpdSOC";

using telemetry_test::listening;
using telemetry_test::writeFile;

/// One simulated vehicle: its instance's table and events (the vcu-telemetry runs apart).
struct Vehicle {
  std::string id;
  std::string instance;
  double soc{};
  std::optional<signals::SignalTable> table;
  std::optional<ipc::EventBus> events;
};

}  // namespace

TEST_CASE(
    "vcu fleet watch and get show the vehicles of a real mosquitto: online, offline by the last will, state, SOC") {
  if (!harness::isolated()) OPENVCU_SKIP(harness::NOT_ISOLATED);
  const std::string bin = OPENVCU_BINARY_DIR "/bin";
  if (!fs::exists("/usr/sbin/mosquitto"))
    OPENVCU_SKIP("skipped: needs mosquitto (Debian's mosquitto package; scripts/install-deps.sh)");
  harness::Harness sut;
  const fs::path work = fs::temp_directory_path() / "fleet-watch";  // the sandbox's own /tmp
  fs::remove_all(work);
  fs::create_directories(work / "vehicle");
  const std::string vcu = bin + "/vcu";

  // no broker yet: a clear error, exit 1
  const auto absent = sut.run({vcu, "fleet", "watch", "--once", "--broker", BROKER});
  CHECK_MESSAGE(absent.exitCode() == 1, absent.describe());
  CHECK_MESSAGE(
      absent.err.find("cannot reach the broker mqtt://127.0.0.1:1883: Connection refused") != std::string::npos,
      absent.describe());

  writeFile(work / "mosquitto.conf", "listener " + std::to_string(PORT) +
                                         " 127.0.0.1\nallow_anonymous true\n"
                                         "persistence false\nuser root\nlog_dest stdout\n");
  REQUIRE_STATUS(
      sut.start({.name = "mosquitto", .argv = {"/usr/sbin/mosquitto", "-c", (work / "mosquitto.conf").string()}}));
  bool up = false;
  for (int attempt = 0; attempt < 100 && !(up = listening(PORT)); ++attempt) std::this_thread::sleep_for(50ms);
  REQUIRE_MESSAGE(up, "mosquitto does not listen on 127.0.0.1:1883");

  // the vehicles: a copy of config/hhea, its telemetry.json sending the SOC (10 Hz, no deadband)
  for (const auto& entry : fs::directory_iterator(fs::path(OPENVCU_SOURCE_DIR) / "config/hhea")) {
    if (entry.is_regular_file()) fs::copy_file(entry.path(), work / "vehicle" / entry.path().filename());
  }
  writeFile(work / "vehicle/telemetry.json",
            Json{{"broker", BROKER},
                 {"vehicleId", "unused"},
                 {"queueFolder", (work / "queue").string()},
                 {"signals", {{{"name", SOC_KEY}, {"maxRateHz", 10}, {"deadband", 0}}}}}
                .dump(2));
  const std::string vehiclePath = (work / "vehicle/vehicle.json").string();
  auto config = config::loadVehicleConfig(vehiclePath);
  REQUIRE_STATUS(config);
  auto catalog = config::buildCatalog(*config);
  REQUIRE_STATUS(catalog);
  const auto soc = *catalog->indexOf(SOC_KEY);

  std::vector<Vehicle> vehicles(3);
  vehicles[0].id = "veh-a", vehicles[0].instance = "fleet-a", vehicles[0].soc = 81.5;
  vehicles[1].id = "veh-b", vehicles[1].instance = "fleet-b", vehicles[1].soc = 42;
  vehicles[2].id = "veh-c", vehicles[2].instance = "fleet-c", vehicles[2].soc = 10;
  std::vector<harness::Process*> bridges;
  for (Vehicle& vehicle : vehicles) {
    auto table = signals::SignalTable::open(*catalog, vehicle.instance);
    REQUIRE_STATUS(table);
    vehicle.table.emplace(std::move(*table));
    auto events = ipc::EventBus::open(config->lcmUrl, vehicle.instance);
    REQUIRE_STATUS(events);
    vehicle.events.emplace(std::move(*events));
    auto bridge =
        sut.start({.name = "vcu-telemetry-" + vehicle.id,
                   .argv = {bin + "/vcu-telemetry", "--config", vehiclePath, "--instance", vehicle.instance,
                            "--vehicle-id", vehicle.id, "--queue-folder", (work / ("queue-" + vehicle.id)).string()},
                   .notifyReadiness = true});
    REQUIRE_STATUS(bridge);
    bridges.push_back(*bridge);
  }
  // the SOC moves by 0.1 around each vehicle's value every 50 ms: a signals message every second
  telemetry_test::PeriodicWriter writer(50ms, [&](int step) {
    for (Vehicle& vehicle : vehicles) {
      vehicle.table->writeBus(soc, vehicle.soc + (step % 2) * 0.1, clock::monotonicNs(), 0xF3, signals::Quality::Valid);
    }
  });

  // live in a pipe: one line per change
  auto watch = sut.start({.name = "vcu-fleet-watch",
                          .argv = {vcu, "fleet", "watch", "--broker", BROKER, "--for", "30"},
                          .captureOutput = true});
  REQUIRE_STATUS(watch);
  REQUIRE((*watch)->waitForLine("veh-c online", 10s));  // subscribed and the vehicles are up
  vehicles[0].events->publish(
      ipc::FsmTransition{.timestampNs = 0, .fromState = "Standby", .toState = "Ready", .cause = "test"});
  vehicles[1].events->publish(
      ipc::FsmTransition{.timestampNs = 0, .fromState = "Ready", .toState = "Driving", .cause = "test"});
  CHECK_MESSAGE((*watch)->waitForLine("veh-a online Ready", 10s).has_value(), (*watch)->output());
  CHECK_MESSAGE((*watch)->waitForLine("veh-b online Driving", 10s).has_value(), (*watch)->output());
  REQUIRE(bridges[2]->signal(SIGKILL));
  CHECK_MESSAGE((*watch)->waitForLine("veh-c offline", 30s).has_value(), (*watch)->output());  // keepalive 10 s x 1.5
  // the SOC with the birth's unit (it moves between x and x.1, which comes back through the
  // DBC's scaling, e.g. as 42.0975), once each vehicle's first signals batch has arrived
  const auto shows = [&](const std::regex& pattern) {
    for (int attempt = 0; attempt < 100; ++attempt) {
      if (std::regex_search((*watch)->output(), pattern)) return true;
      std::this_thread::sleep_for(100ms);
    }
    return false;
  };
  CHECK_MESSAGE(shows(std::regex(R"(veh-a .* 81\.[56][0-9]* %)")), (*watch)->output());
  CHECK_MESSAGE(shows(std::regex(R"(veh-b .* 42(\.[01][0-9]*)? %)")), (*watch)->output());

  // --once: the table of all three, the offline one included (its retained status)
  const auto startOnce = std::chrono::steady_clock::now();
  const auto once = sut.run({vcu, "fleet", "watch", "--once", "--broker", BROKER});
  const double onceSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - startOnce).count();
  MESSAGE("vcu fleet watch --once took " << onceSeconds << " s:\n" << once.out);
  REQUIRE_MESSAGE(once.exitCode() == 0, once.describe());
  CHECK(onceSeconds < 5);
  const auto lineOf = [&](const std::string& id) {
    const auto at = once.out.find("\n" + id + " ");
    return at == std::string::npos ? std::string() : once.out.substr(at + 1, once.out.find('\n', at + 1) - at - 1);
  };
  // the state is retained: a watcher that came later sees it
  CHECK_MESSAGE(lineOf("veh-a").find(" online ") != std::string::npos, once.out);
  CHECK_MESSAGE(lineOf("veh-a").find(" Ready ") != std::string::npos, once.out);
  CHECK_MESSAGE(lineOf("veh-b").find(" online ") != std::string::npos, once.out);
  CHECK_MESSAGE(lineOf("veh-b").find(" Driving ") != std::string::npos, once.out);
  CHECK_MESSAGE(lineOf("veh-c").find(" offline ") != std::string::npos, once.out);
  CHECK_MESSAGE(once.out.find("3 vehicle(s)") != std::string::npos, once.out);
  CHECK_MESSAGE(once.out.find(std::string("SOC: ") + SOC_KEY) != std::string::npos, once.out);

  // get: the retained status, a live signal, the retained state
  const auto status = sut.run({vcu, "fleet", "get", "veh-c", "status", "--broker", BROKER});
  CHECK_MESSAGE(status.exitCode() == 0, status.describe());
  CHECK(status.out == "offline\n");
  const auto value = sut.run({vcu, "fleet", "get", "veh-b", SOC_KEY, "--broker", BROKER});
  CHECK_MESSAGE(value.exitCode() == 0, value.describe());
  CHECK_MESSAGE((value.out == "42\n" || value.out == "42.1\n"), value.describe());
  auto getState = sut.start({.name = "vcu-fleet-get-state",
                             .argv = {vcu, "fleet", "get", "veh-a", "state", "--broker", BROKER, "--wait", "10"},
                             .captureOutput = true});
  REQUIRE_STATUS(getState);
  // the retained state at once
  const std::optional<harness::ExitStatus> ended = (*getState)->waitForExit(5s);
  REQUIRE(ended.has_value());
  CHECK(ended->exited);
  CHECK(ended->code == 0);
  CHECK_MESSAGE((*getState)->output() == "Ready\n", (*getState)->output());
  const auto unknown = sut.run({vcu, "fleet", "get", "veh-zz", "status", "--broker", BROKER, "--wait", "1"});
  CHECK(unknown.exitCode() == 1);
  CHECK_MESSAGE(
      unknown.err.find("vehicle 'veh-zz' is not on the broker mqtt://127.0.0.1:1883 (known: veh-a, veh-b, veh-c)") !=
          std::string::npos,
      unknown.describe());
  const auto untold = sut.run({vcu, "fleet", "get", "veh-c", "state", "--broker", BROKER, "--wait", "1"});
  CHECK(untold.exitCode() == 1);
  CHECK_MESSAGE(untold.err.find("vehicle 'veh-c' has not told 'state'") != std::string::npos, untold.describe());
  writer.stop();
}
