// readEventLog: an LCM log written through LCM's own file:// provider (no network), read
// back into FSM transitions and faults; a file that is no LCM log fails with its path.

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <unistd.h>
#include <fstream>
#include <string>

#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/ipc/event_log.hpp"

namespace ipc = openvcu::ipc;

namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("openvcu_test_" + std::to_string(::getpid()) + "_" + name)).string();
}

}  // namespace

TEST_CASE("readEventLog: FSM transitions and faults of a logged session, other channels skipped") {
  const std::string path = tempPath("events.lcmlog");
  {
    auto busResult = ipc::EventBus::open("file://" + path + "?mode=w", "hhea");
    REQUIRE_MESSAGE(busResult.ok(), (busResult.ok() ? "" : busResult.error().toString()));
    ipc::EventBus& bus = *busResult;
    CHECK(bus.publish(ipc::FsmTransition{1'700'000'000'000'000'000, "", "Off", "initial"}));
    CHECK(bus.publish(ipc::LogRecord{1'700'000'000'500'000'000, "vcu-fsm", ipc::LogLevel::Info, "hello"}));
    CHECK(bus.publish(ipc::FsmTransition{1'700'000'001'000'000'000, "Off", "KeepAlive", "operator.StartStop == 1"}));
    CHECK(bus.publish(ipc::FaultEvent{1'700'000'002'000'000'000, "BMS_Isolation", "0x21", ipc::FaultSeverity::Critical,
                                      true, "isolation low"}));
  }
  auto eventsResult = ipc::readEventLog(path);
  REQUIRE_MESSAGE(eventsResult.ok(), (eventsResult.ok() ? "" : eventsResult.error().toString()));
  CHECK(eventsResult->events == 4);
  CHECK(eventsResult->undecodable == 0);
  REQUIRE(eventsResult->transitions.size() == 2);
  CHECK(eventsResult->transitions[1].fromState == "Off");
  CHECK(eventsResult->transitions[1].toState == "KeepAlive");
  CHECK(eventsResult->transitions[1].timestampNs == 1'700'000'001'000'000'000);
  REQUIRE(eventsResult->faults.size() == 1);
  CHECK(eventsResult->faults[0].name == "BMS_Isolation");
  CHECK(eventsResult->faults[0].active);

  auto cappedResult = ipc::readEventLog(path, 1);
  REQUIRE(cappedResult.ok());
  CHECK(cappedResult->transitions.size() == 1);
  CHECK(cappedResult->dropped == 1);
  std::filesystem::remove(path);
}

TEST_CASE("readEventLog: a missing file and a file that is no LCM log fail with the path") {
  auto missing = ipc::readEventLog("/nonexistent/events.lcmlog");
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().toString().find("/nonexistent/events.lcmlog") != std::string::npos);

  const std::string path = tempPath("not_lcm.lcmlog");
  std::ofstream(path) << "(1700000000.000000) vehicle 18FEF121#0102\n";
  auto notLcm = ipc::readEventLog(path);
  REQUIRE_FALSE(notLcm.ok());
  CHECK(notLcm.error().toString().find(path) != std::string::npos);
  std::filesystem::remove(path);
}
