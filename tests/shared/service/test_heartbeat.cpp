// The heartbeat message: program, instance, pid, uptime, counters in order, status.
// (The table half is tested in test_service_runtime, inside the sandbox.)

#include <doctest/doctest.h>
#include <unistd.h>

#include "openvcu/service/heartbeat.hpp"

namespace service = openvcu::service;

TEST_CASE("the heartbeat message names the program, instance and pid and lists the counters in order") {
  service::HeartbeatPublisher sut("vcu-demo", "itest", nullptr, nullptr, std::nullopt, 7);
  service::CounterRef frames = sut.addCounter("frames_rx");
  std::int64_t external = 41;
  sut.addCounterSource("decode_errors", [&] { return external; });
  service::CounterRef commands = sut.addCounter("commands");

  frames.increment();
  frames.increment(2);
  commands.set(5);
  external = 42;
  const openvcu::ipc::Heartbeat message = sut.message();

  CHECK(message.service == "vcu-demo");
  CHECK(message.instance == "itest");
  CHECK(message.pid == static_cast<std::int32_t>(::getpid()));
  CHECK(message.uptimeMs >= 0);
  REQUIRE(message.counters.size() == 3);
  CHECK(message.counters[0] == openvcu::ipc::Counter{"frames_rx", 3});
  CHECK(message.counters[1] == openvcu::ipc::Counter{"commands", 5});
  CHECK(message.counters[2] == openvcu::ipc::Counter{"decode_errors", 42});
  CHECK(message.status == "starting");
}

TEST_CASE("the status line is the service's until it sets another") {
  service::HeartbeatPublisher sut("vcu-demo", "itest", nullptr, nullptr, std::nullopt, 7);

  sut.setStatus("bus vehicle: bus-off");

  CHECK(sut.message().status == "bus vehicle: bus-off");
}

TEST_CASE("a beat without bus or table only counts") {
  service::HeartbeatPublisher sut("vcu-demo", "itest", nullptr, nullptr, std::nullopt, 7);

  sut.beat();
  sut.beat();

  CHECK(sut.beats() == 2);
}

TEST_CASE("a default counter reference counts nothing and reads 0") {
  service::CounterRef sut;

  sut.increment();

  CHECK(sut.value() == 0);
}

TEST_CASE("the heartbeat slot of a service is internal.service.<name>.heartbeat") {
  CHECK(service::heartbeatKey("can-rx") == "internal.service.can-rx.heartbeat");
}
