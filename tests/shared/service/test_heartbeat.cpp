// The heartbeat message: program, instance, pid, uptime, counters in order, status.
// (The table half is tested in test_service_runtime, inside the sandbox.)

#include <doctest/doctest.h>
#include <unistd.h>
#include <string>

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

TEST_CASE("a heartbeat always fits one datagram: what does not fit goes to the statistics (#19)") {
  service::HeartbeatPublisher sut("vcu-can-rx", "hhea", nullptr, nullptr, std::nullopt, 7);
  sut.addCounter("frames_rx").set(9);
  for (int i = 0; i < 150; ++i) {
    sut.addCounterSource("service_counter_with_a_long_name_" + std::to_string(i), [i] { return std::int64_t{i}; });
  }
  sut.addStatSource("rx.EEC1_PGN61444.frames", [] { return std::int64_t{77}; });
  // a status of 300 bytes of two-byte characters: cut at a character boundary
  std::string status;
  for (int i = 0; i < 150; ++i) status += "\xc3\xa4";
  sut.setStatus(status);

  const openvcu::ipc::Heartbeat heartbeat = sut.message();
  const std::size_t limit =
      openvcu::ipc::datagramPayloadLimit(openvcu::ipc::channelName("hhea", openvcu::ipc::EventKind::Heartbeat));
  CHECK(openvcu::ipc::encodedSize(heartbeat) <= limit);
  CHECK(heartbeat.status.size() <= service::HeartbeatPublisher::MAX_STATUS_BYTES);
  CHECK(heartbeat.status.ends_with("..."));
  CHECK(heartbeat.status.size() % 2 == 1);  // whole two-byte characters, then "..."
  REQUIRE(heartbeat.counters.size() > 10);
  REQUIRE(heartbeat.counters.size() < 151);
  CHECK(heartbeat.counters[0] == openvcu::ipc::Counter{"frames_rx", 9});

  const openvcu::ipc::Stats stats = sut.statsMessage();
  REQUIRE(!stats.counters.empty());
  CHECK(stats.counters[0] == openvcu::ipc::Counter{"rx.EEC1_PGN61444.frames", 77});
  CHECK(stats.service == "vcu-can-rx");
  CHECK(stats.pid == heartbeat.pid);
  // every counter once: in the heartbeat while it fits, in the statistics after
  CHECK(heartbeat.counters.size() + stats.counters.size() == 1 + 150 + 1);
  const std::size_t firstMoved = heartbeat.counters.size() - 1;  // sources after frames_rx
  CHECK(stats.counters[1].name == "service_counter_with_a_long_name_" + std::to_string(firstMoved));
  CHECK(stats.counters.back().name == "service_counter_with_a_long_name_149");
}

TEST_CASE("a small heartbeat keeps every counter and sends no statistics") {
  service::HeartbeatPublisher sut("vcu-fsm", "hhea", nullptr, nullptr, std::nullopt, 7);
  sut.addCounter("transitions");
  sut.addCounterSource("commands_accepted", [] { return std::int64_t{1}; });
  CHECK(sut.message().counters.size() == 2);
  CHECK(sut.statsMessage().counters.empty());
}
