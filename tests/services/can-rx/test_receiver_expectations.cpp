// canrx::Receiver with receive.json "expectedWhen": a sender that is not expected (its wake
// condition does not hold) raises no receive-timeout fault while its data still go stale;
// once it is expected, its timeout counts from then plus the start grace and fires as
// before; the fault clears when the condition ends. Tests/data/can-rx (ECU1_Status: 20 ms
// cycle x 3 = 60 ms); the condition is the built-in status slot internal.fsm.state.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <string>
#include <vector>

#include "receiver.hpp"
#include "vehicle_fixture.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START = 1'000 * MS;
constexpr std::size_t BUS_A = 0;
constexpr std::int64_t TIMEOUT = 60 * MS;      // ECU1_Status
constexpr std::int64_t WAKE_GRACE = 100 * MS;  // startMs of the condition
constexpr double AWAKE = 1.0;
constexpr double ASLEEP = 0.0;
const std::string CONFIG = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/can-rx/vehicle.json";
const std::string CONDITION = "internal.fsm.state";
const std::string FAULT = "rx_timeout.a.ECU1_Status";

struct Recorder final : canrx::ReceiverOutputs {
  std::vector<ipc::FaultEvent> faults;
  void received(std::size_t, const can::ReceivedFrame&) noexcept override {}
  void request(std::size_t, const j1939::Request&, std::int64_t) noexcept override {}
  void network(std::size_t, const can::ReceivedFrame&) noexcept override {}
  void forward(std::size_t, const can::Frame&) noexcept override {}
  bool transmit(std::size_t, const can::Frame&) noexcept override { return true; }
  void fault(const ipc::FaultEvent& event) override { faults.push_back(event); }
  void dm1(const ipc::NodeDm1&) override {}

  [[nodiscard]] const ipc::FaultEvent* lastFault(std::string_view name) const {
    for (auto it = faults.rbegin(); it != faults.rend(); ++it) {
      if (it->name == name) return &*it;
    }
    return nullptr;
  }
  [[nodiscard]] std::size_t count(std::string_view name) const {
    return static_cast<std::size_t>(
        std::count_if(faults.begin(), faults.end(), [&](const ipc::FaultEvent& e) { return e.name == name; }));
  }
};

can::ReceivedFrame ecu1Status(std::int64_t atNs) {
  can::ReceivedFrame received;
  received.frame.id = 0x18FF1010;
  received.frame.flags = can::FLAG_EXTENDED;
  received.frame.length = 8;
  received.frame.data[0] = 1;
  received.monotonicNs = atNs;
  return received;
}

/// ECU1_Status expected while internal.fsm.state = 1, from 100 ms after it became 1.
struct Fixture : openvcu::testing::VehicleTable {
  Recorder outputs;
  std::optional<canrx::Receiver> sut;

  Fixture() : VehicleTable(CONFIG, "rxexpect-" + std::to_string(::getpid())) {}

  void create() {
    auto receiveResult = config::loadReceiveConfig(vehicle);
    REQUIRE_MESSAGE(receiveResult, (receiveResult ? "" : receiveResult.error().toString()));
    config::ReceiveConfig receive = std::move(*receiveResult);
    receive.expectations.push_back(config::ReceiveExpectation{CONDITION, AWAKE, WAKE_GRACE, "/senders/ECU1"});
    receive.expectationOf[message("ECU1_Status")] = 0;
    auto receiverResult = canrx::Receiver::create(vehicle, std::move(receive), catalog, *table, outputs, START);
    REQUIRE_MESSAGE(receiverResult, (receiverResult ? "" : receiverResult.error().toString()));
    sut.emplace(std::move(*receiverResult));
  }
  std::size_t message(std::string_view name) const {
    for (std::size_t m = 0; m < vehicle.database.messages.size(); ++m) {
      if (vehicle.database.messages[m].name == name) return m;
    }
    FAIL("no message " << name);
    return 0;
  }
  void condition(double value, std::int64_t atNs) {
    const auto index = catalog.indexOf(CONDITION);
    REQUIRE(index);
    REQUIRE(table->writeBus(*index, value, atNs, 0, signals::Quality::Valid));
  }
  signals::Quality quality() {
    const auto index = catalog.indexOf("ECU1.ECU1_Status.Speed");
    REQUIRE(index);
    const auto value = table->readBus(*index);
    REQUIRE(value);
    return value->quality;
  }
};

}  // namespace

TEST_CASE("a sender not expected raises no receive timeout although its data go stale") {
  Fixture f;
  f.create();
  f.sut->onFrame(BUS_A, ecu1Status(START + 10 * MS));
  f.sut->onTick(START + 10 * MS + TIMEOUT + 1);
  CHECK(f.quality() == signals::Quality::Stale);  // the data are old either way
  f.sut->onTick(START + 60'000 * MS);
  CHECK(f.outputs.lastFault(FAULT) == nullptr);
  // Another message without a condition is still supervised from the start (BMS_Safe: 150 ms).
  CHECK(f.outputs.lastFault("rx_timeout.a.BMS_Safe") != nullptr);
  CHECK(f.sut->counters(BUS_A).timeouts == 1);
}

TEST_CASE(
    "once its sender is expected, a silent message faults after the wake grace plus its timeout, and clears when no "
    "longer expected") {
  Fixture f;
  f.create();
  f.sut->onTick(START + 500 * MS);
  CHECK(f.outputs.lastFault(FAULT) == nullptr);

  const std::int64_t woken = START + 1'000 * MS;
  f.condition(AWAKE, woken);
  f.sut->onTick(woken);
  CHECK(f.sut->nextDeadlineNs() <= woken + WAKE_GRACE + TIMEOUT + 1);
  f.sut->onTick(woken + WAKE_GRACE + TIMEOUT);
  CHECK(f.outputs.lastFault(FAULT) == nullptr);
  f.sut->onTick(woken + WAKE_GRACE + TIMEOUT + 1);
  const ipc::FaultEvent* raised = f.outputs.lastFault(FAULT);
  REQUIRE(raised != nullptr);
  CHECK(raised->active);
  CHECK(raised->text == "ECU1_Status never received within 60 ms while expected (internal.fsm.state = 1)");
  CHECK(f.outputs.count(FAULT) == 1);

  f.condition(ASLEEP, woken + 200 * MS);
  f.sut->onTick(woken + 200 * MS);
  const ipc::FaultEvent* cleared = f.outputs.lastFault(FAULT);
  REQUIRE(cleared != nullptr);
  CHECK_FALSE(cleared->active);
  CHECK(cleared->text == "ECU1_Status no longer expected (internal.fsm.state = 1 does not hold)");
  f.sut->onTick(woken + 10'000 * MS);
  CHECK(f.outputs.count(FAULT) == 2);
}

TEST_CASE("an expected message that stops is reported after its timeout and clears with its next frame") {
  Fixture f;
  f.condition(AWAKE, START - 10'000 * MS);
  f.create();
  f.sut->onFrame(BUS_A, ecu1Status(START + 10 * MS));
  f.sut->onTick(START + 10 * MS + TIMEOUT + 1);
  const ipc::FaultEvent* raised = f.outputs.lastFault(FAULT);
  REQUIRE(raised != nullptr);
  CHECK(raised->active);
  CHECK(raised->text.find("not received for 60 ms") != std::string::npos);
  f.sut->onFrame(BUS_A, ecu1Status(START + 100 * MS));
  CHECK(f.quality() == signals::Quality::Valid);
  const ipc::FaultEvent* cleared = f.outputs.lastFault(FAULT);
  REQUIRE(cleared != nullptr);
  CHECK_FALSE(cleared->active);
}

TEST_CASE("a condition that holds at the start supervises from the start, without the wake grace") {
  Fixture f;
  f.condition(AWAKE, START - 10'000 * MS);  // can-rx restarted while the vehicle is awake
  f.create();
  f.sut->onTick(START + TIMEOUT);
  CHECK(f.outputs.lastFault(FAULT) == nullptr);
  f.sut->onTick(START + TIMEOUT + 1);
  const ipc::FaultEvent* raised = f.outputs.lastFault(FAULT);
  REQUIRE(raised != nullptr);
  CHECK(raised->active);
}
