// Integration test of the event plane between two processes over LCM's udpm multicast,
// inside the sandbox of run_isolated.sh (private network: lo only, multicast route on lo).

#include <doctest/doctest.h>

#include "skip.hpp"

#include <optional>

#include "ipc_test_support.hpp"
#include "openvcu/ipc/event_bus.hpp"

namespace ipc = openvcu::ipc;
namespace ipctest = openvcu::ipctest;
using namespace std::chrono_literals;

namespace {

const std::string PEER = OPENVCU_IPC_TEST_PEER;
constexpr std::int64_t SOME_TIME_NS = 1'700'000'000'000'000'001;
constexpr int ECHOED_KINDS = 6;  // every kind but Ack, which the peer sends as its answer

}  // namespace

TEST_CASE("every event type crosses from one process to another over udpm and back unchanged") {
  if (!ipctest::isolated()) {
    OPENVCU_SKIP(ipctest::NOT_ISOLATED_MESSAGE);
  }
  const std::string url(ipc::DEFAULT_EVENT_URL);
  auto peer = ipctest::ChildProcess::spawn({PEER, "echo-events", url, "test", "echo", std::to_string(ECHOED_KINDS)});
  REQUIRE(peer);
  std::string transcript;
  REQUIRE_MESSAGE(peer->readUntil("READY", ipctest::READY_TIMEOUT, &transcript), transcript);

  auto requests = ipc::EventBus::open(url, "test");
  auto echoes = ipc::EventBus::open(url, "echo");
  REQUIRE_MESSAGE(requests.ok(), (requests.ok() ? "" : requests.error().toString()));
  REQUIRE_MESSAGE(echoes.ok(), (echoes.ok() ? "" : echoes.error().toString()));

  std::optional<ipc::CommandAck> ack;
  std::optional<ipc::FsmTransition> transition;
  std::optional<ipc::FaultEvent> fault;
  std::optional<ipc::LogRecord> log;
  std::optional<ipc::Heartbeat> heartbeat;
  std::optional<ipc::SignalSnapshot> snapshot;
  REQUIRE(echoes->onAck([&](const ipc::CommandAck& m) { ack = m; }).ok());
  REQUIRE(echoes->onFsmTransition([&](const ipc::FsmTransition& m) { transition = m; }).ok());
  REQUIRE(echoes->onFault([&](const ipc::FaultEvent& m) { fault = m; }).ok());
  REQUIRE(echoes->onLog([&](const ipc::LogRecord& m) { log = m; }).ok());
  REQUIRE(echoes->onHeartbeat([&](const ipc::Heartbeat& m) { heartbeat = m; }).ok());
  REQUIRE(echoes->onSnapshot([&](const ipc::SignalSnapshot& m) { snapshot = m; }).ok());

  const ipc::CommandAck sentAck{SOME_TIME_NS, 7, "test_ipc", "vcu-fsm", false, "not in state Standby"};
  const ipc::FsmTransition sentTransition{SOME_TIME_NS, "Standby", "Precharge", "operator Start"};
  const ipc::FaultEvent sentFault{SOME_TIME_NS, "CAN_vehicle_BusOff", "vcu-can-rx", ipc::FaultSeverity::Error,
                                  false,        "bus recovered"};
  const ipc::LogRecord sentLog{SOME_TIME_NS, "vcu-can-tx", ipc::LogLevel::Error, "SHM/SDM pair late"};
  const ipc::Heartbeat sentHeartbeat{SOME_TIME_NS, "vcu-fsm", "test", 4242, 1000, {{"transitions", 12}}, "ok"};
  const ipc::SignalSnapshot sentSnapshot{
      SOME_TIME_NS, "vcu-can-rx", {{"BMS.SOC", 55.5, 1}, {"BMS.Voltage", 650.25, 1}}};
  REQUIRE(requests->publish(sentAck));
  REQUIRE(requests->publish(sentTransition));
  REQUIRE(requests->publish(sentFault));
  REQUIRE(requests->publish(sentLog));
  REQUIRE(requests->publish(sentHeartbeat));
  REQUIRE(requests->publish(sentSnapshot));

  const auto deadline = std::chrono::steady_clock::now() + 20s;
  auto complete = [&] { return ack && transition && fault && log && heartbeat && snapshot; };
  while (!complete() && std::chrono::steady_clock::now() < deadline) {
    echoes->handle(10ms);
    requests->handle(10ms);
  }
  CHECK(peer->wait(10s) == 0);
  REQUIRE_MESSAGE(complete(), "not every event came back; peer said: " << transcript << peer->pending());
  CHECK(*ack == sentAck);
  CHECK(*transition == sentTransition);
  CHECK(*fault == sentFault);
  CHECK(*log == sentLog);
  CHECK(*heartbeat == sentHeartbeat);
  CHECK(*snapshot == sentSnapshot);
  CHECK(echoes->decodeErrors() == 0);
}

TEST_CASE("opening udpm without a multicast route fails with a clear error") {
  // Outside the sandbox this host may have a route (or traffic could leave): only test inside,
  // in a fresh network namespace without the route.
  if (!ipctest::isolated()) {
    OPENVCU_SKIP(ipctest::NOT_ISOLATED_MESSAGE);
  }
  auto child = ipctest::ChildProcess::spawn({"unshare", "--net", "sh", "-c",
                                             std::string("ip link set lo up; exec ") + PEER + " echo-events '" +
                                                 std::string(ipc::DEFAULT_EVENT_URL) + "' test echo 1"});
  REQUIRE(child);
  std::string transcript;
  const auto answer = child->readUntil("ERROR", 20s, &transcript);
  CHECK(child->wait(10s) == 2);
  REQUIRE_MESSAGE(answer, transcript);
  CHECK(answer->find("multicast needs a route") != std::string::npos);
}
