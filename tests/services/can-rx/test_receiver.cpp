// canrx::Receiver frame by frame: decoding into the table, staleness, requests, the
// transport protocol, DM1, J1939-76 checking, forwarding, bus events and filters.
// Tests/data/can-rx: rx.dbc (nodes VCU 0x21, ECU1 0x10, BMS 0xF3, GW), vehicle.json
// (buses a and b), receive.json (factor 3, BMS_Safe safety group, two forwarding rules).

#include <doctest/doctest.h>

#include "vehicle_fixture.hpp"
#include <unistd.h>

#include <algorithm>
#include <string>
#include <vector>

#include "openvcu/config/catalog.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/safety.hpp"
#include "openvcu/j1939/transport.hpp"
#include "receiver.hpp"

using namespace openvcu;

namespace {

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START = 1'000 * MS;
constexpr std::size_t BUS_A = 0;
constexpr std::size_t BUS_B = 1;
const std::string CONFIG = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/can-rx/vehicle.json";

struct Recorder final : canrx::ReceiverOutputs {
  std::vector<std::pair<std::size_t, can::Frame>> receivedFrames, forwarded, transmitted, networkFrames;
  std::vector<std::pair<std::size_t, j1939::Request>> requests;
  std::vector<ipc::FaultEvent> faults;
  std::vector<ipc::NodeDm1> dm1s;
  void received(std::size_t bus, const can::ReceivedFrame& frame) noexcept override {
    receivedFrames.emplace_back(bus, frame.frame);
  }
  void request(std::size_t bus, const j1939::Request& request, std::int64_t) noexcept override {
    requests.emplace_back(bus, request);
  }
  void network(std::size_t bus, const can::ReceivedFrame& frame) noexcept override {
    networkFrames.emplace_back(bus, frame.frame);
  }
  void forward(std::size_t toBus, const can::Frame& frame) noexcept override { forwarded.emplace_back(toBus, frame); }
  bool transmit(std::size_t bus, const can::Frame& frame) noexcept override {
    transmitted.emplace_back(bus, frame);
    return true;
  }
  void fault(const ipc::FaultEvent& event) override { faults.push_back(event); }
  void dm1(const ipc::NodeDm1& message) override { dm1s.push_back(message); }

  [[nodiscard]] const ipc::FaultEvent* lastFault(std::string_view name) const {
    for (auto it = faults.rbegin(); it != faults.rend(); ++it) {
      if (it->name == name) return &*it;
    }
    return nullptr;
  }
};

can::ReceivedFrame frameOf(std::uint32_t id, std::vector<std::uint8_t> data, std::int64_t atNs, bool extended = true) {
  can::ReceivedFrame received;
  received.frame.id = id;
  received.frame.flags = extended ? can::FLAG_EXTENDED : 0;
  received.frame.length = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), received.frame.data.begin());
  received.monotonicNs = atNs;
  return received;
}

/// Loads the test configuration into a private table; the Receiver under test is `sut`.
struct Fixture : openvcu::testing::VehicleTable {
  Recorder outputs;
  std::optional<canrx::Receiver> sut;

  Fixture() : VehicleTable(CONFIG, "rxunit-" + std::to_string(::getpid())) {
    auto receiveResult = config::loadReceiveConfig(vehicle);
    REQUIRE_MESSAGE(receiveResult, (receiveResult ? "" : receiveResult.error().toString()));
    auto receiverResult = canrx::Receiver::create(vehicle, std::move(*receiveResult), catalog, *table, outputs, START);
    REQUIRE(receiverResult);
    sut.emplace(std::move(*receiverResult));
  }

  signals::BusValue bus(std::string_view key) {
    const auto index = catalog.indexOf(key);
    REQUIRE_MESSAGE(index, key);
    const auto value = table->readBus(*index);
    REQUIRE(value);
    return *value;
  }
};

}  // namespace

TEST_CASE("a frame is decoded into the bus plane with its time, source address and quality") {
  Fixture f;
  // Speed 0x03E8 = 1000 -> 100.0 km/h, State 2, Temp -5 (0xFB).
  f.sut->onFrame(BUS_A, frameOf(0x18FF1010, {0xE8, 0x03, 0x02, 0xFB, 0, 0, 0, 0}, START + 5 * MS));
  const auto speed = f.bus("ECU1.ECU1_Status.Speed");
  CHECK(speed.value == doctest::Approx(100.0));
  CHECK(speed.timestampNs == START + 5 * MS);
  CHECK(speed.source == 0x10);
  CHECK(speed.quality == signals::Quality::Valid);
  CHECK(f.bus("ECU1.ECU1_Status.State").value == 2.0);
  CHECK(f.bus("ECU1.ECU1_Status.Temp").value == -5.0);
  CHECK(f.sut->counters(BUS_A).decoded == 1);
  REQUIRE(f.outputs.receivedFrames.size() == 1);
  CHECK(f.outputs.receivedFrames[0].first == BUS_A);
}

TEST_CASE("a frame from another source address matches its message by PGN") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18FF1077, {0x0A, 0x00, 0x01, 0, 0, 0, 0, 0}, START + MS));
  const auto speed = f.bus("ECU1.ECU1_Status.Speed");
  CHECK(speed.value == doctest::Approx(1.0));
  CHECK(speed.source == 0x77);
}

TEST_CASE("an 11-bit frame is decoded by its exact identifier") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x123, {7, 0x34, 0x12, 0}, START + MS, false));
  CHECK(f.bus("GW.Std_Msg.Counter").value == 7.0);
  CHECK(f.bus("GW.Std_Msg.Value").value == 0x1234);
}

TEST_CASE("values outside the DBC range are written with quality OutOfRange") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18FF1010, {0, 0, 9, 0, 0, 0, 0, 0}, START + MS));  // State 9 > 3
  CHECK(f.bus("ECU1.ECU1_Status.State").quality == signals::Quality::OutOfRange);
  CHECK(f.bus("ECU1.ECU1_Status.Speed").quality == signals::Quality::Valid);
  CHECK(f.sut->counters(BUS_A).outOfRange == 1);
}

TEST_CASE("unknown identifiers, frames of another bus and this node's own messages are counted, not decoded") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18AB1234, {1, 2, 3}, START + MS));
  f.sut->onFrame(BUS_A, frameOf(0x18FF6045, {1, 0, 0, 0, 0, 0, 0, 0}, START + MS));  // GW_Info lives on bus b
  f.sut->onFrame(BUS_A, frameOf(0x18FF2021, {1, 0, 0, 0, 0, 0, 0, 0}, START + MS));  // VCU_Cmd: our own
  CHECK(f.sut->counters(BUS_A).unknownIds == 2);
  CHECK(f.sut->counters(BUS_A).ownFrames == 1);
  CHECK(f.sut->counters(BUS_A).decoded == 0);
  CHECK(f.bus("VCU.VCU_Cmd.Enable").quality == signals::Quality::NeverReceived);
  CHECK(f.outputs.receivedFrames.size() == 3);
}

TEST_CASE("a short frame decodes what fits and counts a decode error") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18FF1010, {0x0A, 0x00}, START + MS));
  CHECK(f.bus("ECU1.ECU1_Status.Speed").value == doctest::Approx(1.0));
  CHECK(f.bus("ECU1.ECU1_Status.State").quality == signals::Quality::NeverReceived);
  CHECK(f.sut->counters(BUS_A).decodeErrors == 1);
}

TEST_CASE("a message silent for its timeout goes stale with a fault, and the next frame clears both") {
  Fixture f;
  // ECU1_Status: cycle 20 ms x factor 3 = 60 ms.
  f.sut->onFrame(BUS_A, frameOf(0x18FF1010, {1, 0, 1, 0, 0, 0, 0, 0}, START + 10 * MS));
  f.sut->onTick(START + 70 * MS);  // 60 ms after the frame: not yet
  CHECK(f.bus("ECU1.ECU1_Status.Speed").quality == signals::Quality::Valid);
  CHECK(f.outputs.lastFault("rx_timeout.a.ECU1_Status") == nullptr);
  f.sut->onTick(START + 71 * MS);
  CHECK(f.bus("ECU1.ECU1_Status.Speed").quality == signals::Quality::Stale);
  CHECK(f.bus("ECU1.ECU1_Status.Speed").value == doctest::Approx(0.1));
  const ipc::FaultEvent* raised = f.outputs.lastFault("rx_timeout.a.ECU1_Status");
  REQUIRE(raised != nullptr);
  CHECK(raised->active);
  CHECK(raised->text.find("not received for 60 ms") != std::string::npos);
  CHECK(f.sut->messageCounters(0).stale);
  f.sut->onTick(START + 90 * MS);  // raised once, not on every tick
  CHECK(std::count_if(f.outputs.faults.begin(), f.outputs.faults.end(),
                      [](const ipc::FaultEvent& e) { return e.name == "rx_timeout.a.ECU1_Status"; }) == 1);
  f.sut->onFrame(BUS_A, frameOf(0x18FF1010, {2, 0, 1, 0, 0, 0, 0, 0}, START + 100 * MS));
  CHECK(f.bus("ECU1.ECU1_Status.Speed").quality == signals::Quality::Valid);
  const ipc::FaultEvent* cleared = f.outputs.lastFault("rx_timeout.a.ECU1_Status");
  REQUIRE(cleared != nullptr);
  CHECK_FALSE(cleared->active);
  CHECK(f.sut->counters(BUS_A).timeouts == 1);
}

TEST_CASE("a message never received is reported once its timeout after start has passed") {
  Fixture f;
  f.sut->onTick(START + 60 * MS);
  CHECK(f.outputs.lastFault("rx_timeout.a.ECU1_Status") == nullptr);
  f.sut->onTick(START + 61 * MS);
  const ipc::FaultEvent* raised = f.outputs.lastFault("rx_timeout.a.ECU1_Status");
  REQUIRE(raised != nullptr);
  CHECK(raised->text.find("never received") != std::string::npos);
  // Std_Msg has timeoutMs 0 (never stale); VCU_Cmd is our own.
  f.sut->onTick(START + 100'000 * MS);
  CHECK(f.outputs.lastFault("rx_timeout.a.Std_Msg") == nullptr);
  CHECK(f.outputs.lastFault("rx_timeout.a.VCU_Cmd") == nullptr);
}

TEST_CASE("J1939 requests to this node or to all are handed on, requests to others are not") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18EA21F3, {0xE6, 0xFE, 0x00}, START + MS));  // to 0x21: us
  f.sut->onFrame(BUS_A, frameOf(0x18EAFFF3, {0xE6, 0xFE, 0x00}, START + MS));  // global
  f.sut->onFrame(BUS_A, frameOf(0x18EA10F3, {0xE6, 0xFE, 0x00}, START + MS));  // to ECU1
  REQUIRE(f.outputs.requests.size() == 2);
  CHECK(f.outputs.requests[0].second == j1939::Request{0xFEE6, 0xF3, false});  // 0x18EA21F3
  CHECK(f.outputs.requests[1].second == j1939::Request{0xFEE6, 0xF3, true});   // 0x18EAFFF3
  CHECK(f.sut->counters(BUS_A).requests == 2);
}

TEST_CASE("a J1939 request to this node whose payload is not a PGN is not handed on (issue 20)") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18EA21F3, {0xE6, 0xFE}, START + MS));              // 2 bytes
  f.sut->onFrame(BUS_A, frameOf(0x18EA21F3, {0xE6, 0xFE, 0x04}, START + MS));        // 19 bits
  CHECK(f.outputs.requests.empty());
  CHECK(f.sut->counters(BUS_A).requests == 0);
}

TEST_CASE("a BAM transfer is reassembled and decoded through the DBC") {
  Fixture f;
  // ECU1_Big: PGN 0xFF30, 20 bytes in 3 packets; First = bytes 0-1, Last = bytes 18-19.
  std::vector<std::uint8_t> payload(20);
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<std::uint8_t>(i + 1);
  f.sut->onFrame(BUS_A, frameOf(0x1CECFF10, {0x20, 20, 0, 3, 0xFF, 0x30, 0xFF, 0x00}, START + MS));
  for (std::uint8_t packet = 1; packet <= 3; ++packet) {
    std::vector<std::uint8_t> data{packet};
    for (std::size_t i = 0; i < 7; ++i) {
      const std::size_t at = (packet - 1u) * 7u + i;
      data.push_back(at < payload.size() ? payload[at] : 0xFF);
    }
    f.sut->onFrame(BUS_A, frameOf(0x1CEBFF10, data, START + (1 + packet * 50) * MS));
  }
  CHECK(f.bus("ECU1.ECU1_Big.First").value == 0x0201);
  CHECK(f.bus("ECU1.ECU1_Big.Last").value == 0x1413);
  CHECK(f.bus("ECU1.ECU1_Big.Last").source == 0x10);
  CHECK(f.sut->counters(BUS_A).tpSessions == 1);
  CHECK(f.sut->counters(BUS_A).tpCompleted == 1);
  CHECK(f.outputs.transmitted.empty());  // BAM is never answered
}

TEST_CASE("an RTS/CTS transfer to this node is answered with CTS and EndOfMsgAck on the same bus") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x1CEC2110, {0x10, 20, 0, 3, 0xFF, 0x30, 0xFF, 0x00}, START + MS));
  REQUIRE(f.outputs.transmitted.size() == 1);
  CHECK(f.outputs.transmitted[0].first == BUS_A);
  const can::Frame& cts = f.outputs.transmitted[0].second;
  CHECK(cts.id == 0x1CEC1021);  // TP.CM priority 7, to 0x10 from 0x21
  CHECK(cts.extended());
  CHECK(cts.data[0] == 0x11);  // CTS
  CHECK(cts.data[1] == 3);     // packets (maxPacketsPerCts 16)
  CHECK(cts.data[2] == 1);     // next packet
  for (std::uint8_t packet = 1; packet <= 3; ++packet) {
    std::vector<std::uint8_t> data{packet, packet, packet, packet, packet, packet, packet, packet};
    f.sut->onFrame(BUS_A, frameOf(0x1CEB2110, data, START + (2 + packet) * MS));
  }
  REQUIRE(f.outputs.transmitted.size() == 2);
  const can::Frame& ack = f.outputs.transmitted[1].second;
  CHECK(ack.id == 0x1CEC1021);
  CHECK(ack.data[0] == 0x13);
  CHECK(ack.data[1] == 20);
  CHECK(ack.data[3] == 3);
  CHECK(f.bus("ECU1.ECU1_Big.First").value == 0x0101);
  CHECK(f.bus("ECU1.ECU1_Big.Last").value == 0x0303);
}

TEST_CASE("an RTS/CTS session that stalls is aborted on the tick after its timeout") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x1CEC2110, {0x10, 20, 0, 3, 0xFF, 0x30, 0xFF, 0x00}, START + MS));
  f.sut->onFrame(BUS_A, frameOf(0x1CEB2110, {1, 1, 1, 1, 1, 1, 1, 1}, START + 2 * MS));
  f.sut->onTick(START + 2 * MS + j1939::TP_T1_NS + MS);
  REQUIRE(f.outputs.transmitted.size() == 2);
  CHECK(f.outputs.transmitted[1].second.data[0] == 0xFF);  // Abort
  CHECK(f.outputs.transmitted[1].second.data[1] == 3);     // reason: timeout
  CHECK(f.sut->counters(BUS_A).tpAborted == 1);
}

TEST_CASE("a single-frame DM1 raises one fault per DTC and fills the node's DM1 slots") {
  Fixture f;
  // Lamps: amber warning on (byte 0 bits 3-2 = 01); DTC SPN 1234 FMI 3 OC 5.
  const std::uint32_t spn = 1234;
  f.sut->onFrame(BUS_A, frameOf(0x18FECAF3,
                                {0x04, 0xFF, static_cast<std::uint8_t>(spn & 0xFF),
                                 static_cast<std::uint8_t>((spn >> 8) & 0xFF),
                                 static_cast<std::uint8_t>(((spn >> 16) << 5) | 3), 5, 0xFF, 0xFF},
                                START + MS));
  CHECK(f.bus("internal.dm1.BMS.activeDtcs").value == 1.0);
  CHECK(f.bus("internal.dm1.BMS.amberWarningLamp").value == 1.0);
  CHECK(f.bus("internal.dm1.BMS.firstSpn").value == 1234.0);
  CHECK(f.bus("internal.dm1.BMS.firstFmi").value == 3.0);
  const ipc::FaultEvent* raised = f.outputs.lastFault("dm1.BMS.spn1234.fmi3");
  REQUIRE(raised != nullptr);
  CHECK(raised->active);
  CHECK(raised->text.find("occurrence 5") != std::string::npos);
  // The DTC goes away: a DM1 without DTCs clears it.
  f.sut->onFrame(BUS_A, frameOf(0x18FECAF3, {0x00, 0xFF, 0, 0, 0, 0, 0xFF, 0xFF}, START + 1000 * MS));
  CHECK(f.bus("internal.dm1.BMS.activeDtcs").value == 0.0);
  const ipc::FaultEvent* cleared = f.outputs.lastFault("dm1.BMS.spn1234.fmi3");
  REQUIRE(cleared != nullptr);
  CHECK_FALSE(cleared->active);
  CHECK(f.sut->counters(BUS_A).dm1Messages == 2);
}

TEST_CASE("a multi-packet DM1 over BAM appears as several DTCs") {
  Fixture f;
  // 2 lamp bytes + 3 DTCs x 4 = 14 bytes, 2 packets.
  const std::vector<std::uint8_t> dm1{0x10, 0xFF,                 // red stop lamp on
                                      100, 0, 1, 1,               // SPN 100 FMI 1 OC 1
                                      0x10, 0x27, 0x02, 2,        // SPN 10000 FMI 2 OC 2
                                      0xFF, 0xFF, 0xE4, 7};       // SPN 0x7FFFF FMI 4 OC 7
  f.sut->onFrame(BUS_A, frameOf(0x1CECFFF3, {0x20, 14, 0, 2, 0xFF, 0xCA, 0xFE, 0x00}, START + MS));
  std::vector<std::uint8_t> first{1};
  first.insert(first.end(), dm1.begin(), dm1.begin() + 7);
  std::vector<std::uint8_t> second{2};
  second.insert(second.end(), dm1.begin() + 7, dm1.end());
  f.sut->onFrame(BUS_A, frameOf(0x1CEBFFF3, first, START + 60 * MS));
  f.sut->onFrame(BUS_A, frameOf(0x1CEBFFF3, second, START + 120 * MS));
  CHECK(f.bus("internal.dm1.BMS.activeDtcs").value == 3.0);
  CHECK(f.bus("internal.dm1.BMS.redStopLamp").value == 1.0);
  CHECK(f.bus("internal.dm1.BMS.firstSpn").value == 100.0);
  for (const char* name : {"dm1.BMS.spn100.fmi1", "dm1.BMS.spn10000.fmi2", "dm1.BMS.spn524287.fmi4"}) {
    const ipc::FaultEvent* raised = f.outputs.lastFault(name);
    REQUIRE_MESSAGE(raised != nullptr, name);
    CHECK(raised->active);
    CHECK(raised->severity == ipc::FaultSeverity::Error);  // red stop lamp
  }
}

TEST_CASE("a node's DM1 goes out whole when it changes and again after a second unchanged (#25)") {
  Fixture f;
  // amber warning on; SPN 1234 FMI 3 OC 5 CM 0, then SPN 100 FMI 1 OC 127 CM 1
  const std::vector<std::uint8_t> twoDtcs{0x04, 0xFF, 0xD2, 0x04, 0x03, 0x05, 100, 0, 1, 0xFF};
  const auto sendTwo = [&](std::int64_t atNs) {
    f.sut->onFrame(BUS_A, frameOf(0x1CECFFF3, {0x20, 10, 0, 2, 0xFF, 0xCA, 0xFE, 0x00}, atNs));
    std::vector<std::uint8_t> first{1};
    first.insert(first.end(), twoDtcs.begin(), twoDtcs.begin() + 7);
    std::vector<std::uint8_t> second{2};
    second.insert(second.end(), twoDtcs.begin() + 7, twoDtcs.end());
    second.resize(8, 0xFF);
    f.sut->onFrame(BUS_A, frameOf(0x1CEBFFF3, first, atNs + 50 * MS));
    f.sut->onFrame(BUS_A, frameOf(0x1CEBFFF3, second, atNs + 100 * MS));
  };
  sendTwo(START + MS);
  REQUIRE(f.outputs.dm1s.size() == 1);
  const ipc::NodeDm1& sent = f.outputs.dm1s[0];
  CHECK(sent.node == "BMS");
  CHECK(sent.bus == f.vehicle.buses[BUS_A].name);
  CHECK(sent.source == 0xF3);
  CHECK(sent.lamps == 0x04);
  CHECK(sent.flash == 0xFF);
  CHECK(sent.dtcs == std::vector<ipc::NodeDtc>{{1234, 3, 5, false}, {100, 1, 127, true}});
  sendTwo(START + 500 * MS);  // unchanged, within a second: not again
  CHECK(f.outputs.dm1s.size() == 1);
  sendTwo(START + 1100 * MS);  // unchanged, a second later: again
  CHECK(f.outputs.dm1s.size() == 2);
  f.sut->onFrame(BUS_A, frameOf(0x18FECAF3, {0x04, 0xFF, 0xD2, 0x04, 0x03, 0x05, 0xFF, 0xFF}, START + 1300 * MS));
  REQUIRE(f.outputs.dm1s.size() == 3);  // SPN 100 went away
  CHECK(f.outputs.dm1s[2].dtcs == std::vector<ipc::NodeDtc>{{1234, 3, 5, false}});
  // only the occurrence count changes: no fault event (same SPN and FMI), but the DM1 goes out
  const std::size_t faultsBefore = f.outputs.faults.size();
  f.sut->onFrame(BUS_A, frameOf(0x18FECAF3, {0x04, 0xFF, 0xD2, 0x04, 0x03, 0x06, 0xFF, 0xFF}, START + 1400 * MS));
  CHECK(f.outputs.faults.size() == faultsBefore);
  REQUIRE(f.outputs.dm1s.size() == 4);
  CHECK(f.outputs.dm1s[3].dtcs == std::vector<ipc::NodeDtc>{{1234, 3, 6, false}});
}

TEST_CASE("a DM1 from an address no DBC node has is still reported, by address") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18FECA99, {0x00, 0xFF, 50, 0, 3, 1, 0xFF, 0xFF}, START + MS));
  CHECK(f.outputs.lastFault("dm1.SA 0x99.spn50.fmi3") != nullptr);
}

namespace {

constexpr std::uint32_t SDM_ID = 0x0CFF50F3;

struct SafetySender {
  j1939::SafetyPairBuilder builder{SDM_ID};
  std::pair<can::ReceivedFrame, can::ReceivedFrame> pair(std::array<std::uint8_t, 8> data, std::int64_t atNs,
                                                          std::int64_t delayNs = MS) {
    const j1939::SafetyPayload header = builder.nextHeader(j1939::SafetyDataView(data));
    return {frameOf(builder.headerCanId(), {header.begin(), header.end()}, atNs),
            frameOf(SDM_ID, {data.begin(), data.end()}, atNs + delayNs)};
  }
};

void feed(Fixture& f, const std::pair<can::ReceivedFrame, can::ReceivedFrame>& pair) {
  f.sut->onFrame(BUS_A, pair.first);
  f.sut->onFrame(BUS_A, pair.second);
}

}  // namespace

TEST_CASE("J1939-76: intact pairs in sequence are written from the second pair on") {
  Fixture f;
  SafetySender sender;
  feed(f, sender.pair({1, 0x10, 0x27, 0, 0, 0, 0, 0}, START + 10 * MS));  // synchronising
  CHECK(f.bus("BMS.BMS_Safe.ContactorState").quality == signals::Quality::NeverReceived);
  feed(f, sender.pair({2, 0x10, 0x27, 0, 0, 0, 0, 0}, START + 60 * MS));
  CHECK(f.bus("BMS.BMS_Safe.ContactorState").value == 2.0);
  CHECK(f.bus("BMS.BMS_Safe.PackVoltage").value == doctest::Approx(500.0));
  CHECK(f.outputs.faults.empty());
}

TEST_CASE("J1939-76: each error class is detected, the SDM is not written and a fault is raised") {
  struct Case {
    const char* name;
    const char* expected;
  };
  const Case cases[] = {{"crc", "CrcMismatch"},       {"repetition", "Repetition"},
                        {"sequence", "SequenceError"}, {"late", "Timeout"},
                        {"no header", "MissingHeader"}, {"short", "BadLength"}};
  for (const Case& c : cases) {
    const std::string caseName = c.name;
    CAPTURE(caseName);
    Fixture f;
    SafetySender sender;
    feed(f, sender.pair({1, 0, 0, 0, 0, 0, 0, 0}, START + 10 * MS));
    feed(f, sender.pair({2, 0, 0, 0, 0, 0, 0, 0}, START + 60 * MS));
    REQUIRE(f.bus("BMS.BMS_Safe.ContactorState").value == 2.0);
    auto bad = sender.pair({3, 0, 0, 0, 0, 0, 0, 0}, START + 110 * MS);
    const std::string kind = c.name;
    if (kind == "crc") {
      bad.second.frame.data[1] = 0x55;  // data changed after the SHM's CRC was computed
    } else if (kind == "repetition") {
      j1939::SafetyPairBuilder again(SDM_ID, 1);  // the previous pair's sequence number
      const std::array<std::uint8_t, 8> data{3, 0, 0, 0, 0, 0, 0, 0};
      const auto header = again.nextHeader(j1939::SafetyDataView(data));
      std::copy(header.begin(), header.end(), bad.first.frame.data.begin());
    } else if (kind == "sequence") {
      j1939::SafetyPairBuilder skip(SDM_ID, 5);
      const std::array<std::uint8_t, 8> data{3, 0, 0, 0, 0, 0, 0, 0};
      const auto header = skip.nextHeader(j1939::SafetyDataView(data));
      std::copy(header.begin(), header.end(), bad.first.frame.data.begin());
    } else if (kind == "late") {
      bad.second.monotonicNs = bad.first.monotonicNs + 11 * MS;  // SRVT 10 ms
    } else if (kind == "no header") {
      bad.first.frame.id = 0x18FF9999;  // the SHM never arrives (an unknown frame instead)
    } else if (kind == "short") {
      bad.second.frame.length = 7;
    }
    feed(f, bad);
    CHECK(f.bus("BMS.BMS_Safe.ContactorState").value == 2.0);  // not 3: refused
    CHECK(f.sut->counters(BUS_A).safetyFailures == 1);
    const ipc::FaultEvent* raised = f.outputs.lastFault("j1939_76.BMS_Safe");
    REQUIRE(raised != nullptr);
    CHECK(raised->active);
    CHECK_MESSAGE(raised->text.find(c.expected) != std::string::npos, raised->text);
  }
}

TEST_CASE("J1939-76: a fault clears once pairs are good again, and a late SHM is reported on the tick") {
  Fixture f;
  SafetySender sender;
  feed(f, sender.pair({1, 0, 0, 0, 0, 0, 0, 0}, START + 10 * MS));
  feed(f, sender.pair({2, 0, 0, 0, 0, 0, 0, 0}, START + 60 * MS));
  auto bad = sender.pair({3, 0, 0, 0, 0, 0, 0, 0}, START + 110 * MS);
  bad.second.frame.data[0] = 9;
  feed(f, bad);
  feed(f, sender.pair({4, 0, 0, 0, 0, 0, 0, 0}, START + 160 * MS));  // resynchronising
  feed(f, sender.pair({5, 0, 0, 0, 0, 0, 0, 0}, START + 210 * MS));
  CHECK(f.bus("BMS.BMS_Safe.ContactorState").value == 5.0);
  const ipc::FaultEvent* cleared = f.outputs.lastFault("j1939_76.BMS_Safe");
  REQUIRE(cleared != nullptr);
  CHECK_FALSE(cleared->active);
  f.sut->onTick(START + 210 * MS + 101 * MS);  // SCT 100 ms without a new SHM
  const ipc::FaultEvent* overdue = f.outputs.lastFault("j1939_76.BMS_Safe.header");
  REQUIRE(overdue != nullptr);
  CHECK(overdue->active);
}

TEST_CASE("forwarding rules copy matching frames to the other bus, with an ID rewrite") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18FF1010, {1, 2, 3, 4, 5, 6, 7, 8}, START + MS));
  f.sut->onFrame(BUS_A, frameOf(0x18FF1020, {1, 2, 3, 4, 5, 6, 7, 8}, START + MS));  // ID rule: exact only
  f.sut->onFrame(BUS_B, frameOf(0x18FF6045, {9}, START + MS));                       // PGN rule, source 0x45
  f.sut->onFrame(BUS_B, frameOf(0x10FF6045, {10}, START + MS));                      // other priority: same PGN
  f.sut->onFrame(BUS_B, frameOf(0x18FF6046, {11}, START + MS));                      // other source
  REQUIRE(f.outputs.forwarded.size() == 3);
  CHECK(f.outputs.forwarded[0].first == BUS_B);
  CHECK(f.outputs.forwarded[0].second.id == 0x18FF1011);
  CHECK(f.outputs.forwarded[0].second.data[7] == 8);
  CHECK(f.outputs.forwarded[1].first == BUS_A);
  CHECK(f.outputs.forwarded[1].second.id == 0x18FF6045);
  CHECK(f.outputs.forwarded[2].second.id == 0x10FF6045);
  CHECK(f.sut->counters(BUS_A).forwarded == 1);
  CHECK(f.sut->counters(BUS_B).forwarded == 2);
}

TEST_CASE("bus events set the bus state slot and raise a fault for bus-off until the bus is back") {
  Fixture f;
  CHECK(f.bus("internal.bus.a.state").updates == 0);
  f.sut->onTick(START + MS / 2);  // a link without a LinkUp event (sim) reads Active from the first tick
  CHECK(f.bus("internal.bus.a.state").updates > 0);
  CHECK(f.bus("internal.bus.a.state").value == 0.0);
  f.sut->onBusEvent(BUS_A, can::BusEvent{can::BusEventKind::ErrorPassive, START + MS, 0, 128, 0});
  CHECK(f.bus("internal.bus.a.state").value == 2.0);
  CHECK(f.outputs.faults.empty());
  f.sut->onBusEvent(BUS_A, can::BusEvent{can::BusEventKind::BusOff, START + 2 * MS, 0, 255, 0});
  CHECK(f.bus("internal.bus.a.state").value == 3.0);
  f.sut->onTick(START + 2 * MS + MS / 2);  // the tick keeps the last event's state
  CHECK(f.bus("internal.bus.a.state").value == 3.0);
  REQUIRE(f.outputs.lastFault("bus.a") != nullptr);
  CHECK(f.outputs.lastFault("bus.a")->active);
  f.sut->onBusEvent(BUS_A, can::BusEvent{can::BusEventKind::Restarted, START + 3 * MS, 0, 0, 0});
  CHECK(f.bus("internal.bus.a.state").value == 0.0);
  CHECK_FALSE(f.outputs.lastFault("bus.a")->active);
  CHECK(f.sut->counters(BUS_A).busErrors == 3);
}

TEST_CASE("the bus load slot follows the wire time of the frames received") {
  Fixture f;
  // 250 extended 8-byte frames in 100 ms on bus a (500 kbit/s), each ~130 bits = 260 us.
  for (int i = 0; i < 250; ++i) {
    f.sut->onFrame(BUS_A, frameOf(0x18AB0001, {0, 0, 0, 0, 0, 0, 0, 0}, START + 900 * MS + i * 400'000));
  }
  f.sut->onTick(START + 1000 * MS);
  const double load = f.bus("internal.bus.a.load").value;
  CHECK(load > 5.0);
  CHECK(load < 10.0);  // 250 x ~260 us = ~65 ms in a 1 s window: ~6.5 %
}

TEST_CASE("the DBC filters of a bus accept its messages and the J1939 protocol PGNs only") {
  Fixture f;
  const std::vector<can::IdFilter> filters = f.sut->filters(BUS_A);
  auto accepts = [&](std::uint32_t id, bool extended) {
    can::Frame frame;
    frame.id = id;
    frame.flags = extended ? can::FLAG_EXTENDED : 0;
    return can::passes(filters, frame);
  };
  CHECK(accepts(0x18FF1010, true));
  CHECK(accepts(0x18FF1099, true));   // same PGN, other source
  CHECK(accepts(0x123, false));
  CHECK(accepts(0x1CECFF10, true));   // TP.CM
  CHECK(accepts(0x1CEB2110, true));   // TP.DT
  CHECK(accepts(0x18EA21F3, true));   // Request
  CHECK(accepts(0x18FECAF3, true));   // DM1
  CHECK(accepts(0x18EEFF10, true));   // Address Claimed
  CHECK(accepts(j1939::safetyHeaderCanId(SDM_ID), true));
  CHECK_FALSE(accepts(0x18FF6045, true));  // GW_Info is on bus b
  CHECK_FALSE(accepts(0x124, false));
  CHECK_FALSE(accepts(0x123, true));
}

TEST_CASE("the next deadline is the earliest running receive timeout, or the next bus-load update") {
  Fixture f;
  // Safety group BMS_Safe (SCT 100 ms) is looked at every 25 ms from the last tick.
  CHECK(f.sut->nextDeadlineNs() == START + 25 * MS);
  f.sut->onTick(START + 61 * MS);  // everything timed out ("never received")
  CHECK(f.sut->nextDeadlineNs() == START + 61 * MS + 25 * MS);
  f.sut->onFrame(BUS_A, frameOf(0x18FF1010, {1, 0, 1, 0, 0, 0, 0, 0}, START + 70 * MS));
  f.sut->onTick(START + 71 * MS);
  CHECK(f.sut->nextDeadlineNs() == START + 96 * MS);  // the safety look, before ECU1_Status' timeout
  f.sut->onTick(START + 110 * MS);
  CHECK(f.sut->nextDeadlineNs() == START + 70 * MS + 60 * MS + 1);  // ECU1_Status: 60 ms after its frame
}

TEST_CASE("a BAM from one node and an RTS/CTS transfer from another, interleaved, both complete") {
  Fixture f;
  // ECU1 broadcasts ECU1_Big (20 bytes) while the BMS sends us a DM1 with 2 DTCs (10 bytes) by RTS/CTS.
  f.sut->onFrame(BUS_A, frameOf(0x1CECFF10, {0x20, 20, 0, 3, 0xFF, 0x30, 0xFF, 0x00}, START + 1 * MS));
  f.sut->onFrame(BUS_A, frameOf(0x1CEC21F3, {0x10, 10, 0, 2, 0xFF, 0xCA, 0xFE, 0x00}, START + 2 * MS));
  REQUIRE(f.outputs.transmitted.size() == 1);
  CHECK(f.outputs.transmitted[0].second.id == 0x1CECF321);  // CTS to the BMS
  f.sut->onFrame(BUS_A, frameOf(0x1CEBFF10, {1, 0xAA, 0xBB, 3, 4, 5, 6, 7}, START + 3 * MS));
  f.sut->onFrame(BUS_A, frameOf(0x1CEB21F3, {1, 0x00, 0xFF, 77, 0, 2, 1, 88}, START + 4 * MS));
  f.sut->onFrame(BUS_A, frameOf(0x1CEBFF10, {2, 8, 9, 10, 11, 12, 13, 14}, START + 5 * MS));
  f.sut->onFrame(BUS_A, frameOf(0x1CEB21F3, {2, 0, 4, 1, 0xFF, 0xFF, 0xFF, 0xFF}, START + 6 * MS));
  f.sut->onFrame(BUS_A, frameOf(0x1CEBFF10, {3, 15, 16, 17, 18, 0x34, 0x12, 0xFF}, START + 7 * MS));
  CHECK(f.bus("ECU1.ECU1_Big.First").value == 0xBBAA);
  CHECK(f.bus("ECU1.ECU1_Big.Last").value == 0x1234);
  CHECK(f.bus("internal.dm1.BMS.activeDtcs").value == 2.0);
  CHECK(f.outputs.lastFault("dm1.BMS.spn77.fmi2") != nullptr);
  CHECK(f.outputs.lastFault("dm1.BMS.spn88.fmi4") != nullptr);
  REQUIRE(f.outputs.transmitted.size() == 2);
  CHECK(f.outputs.transmitted[1].second.data[0] == 0x13);  // EndOfMsgAck to the BMS
  CHECK(f.sut->counters(BUS_A).tpCompleted == 2);
}

TEST_CASE("a request the DBC does not define is counted as an unknown ID after it is handed on") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18EA21F3, {0xE6, 0xFE, 0x00}, START + MS));
  CHECK(f.outputs.requests.size() == 1);
  CHECK(f.sut->counters(BUS_A).unknownIds == 1);
}

TEST_CASE("address claims and TP answers to this node go to can-tx on the net stream and others do not (issue 24)") {
  Fixture f;
  f.sut->onFrame(BUS_A, frameOf(0x18EEFF10, {1, 2, 3, 4, 5, 6, 7, 8}, START + MS));        // Address Claimed by 0x10
  f.sut->onFrame(BUS_A, frameOf(0x1CEC2110, {0x11, 2, 1, 0xFF, 0xFF, 0xCA, 0xFE, 0}, START + 2 * MS));  // CTS to us
  f.sut->onFrame(BUS_A, frameOf(0x1CEC2110, {0x13, 20, 0, 3, 0xFF, 0xCA, 0xFE, 0}, START + 3 * MS));   // EoMA to us
  f.sut->onFrame(BUS_A, frameOf(0x1CEC2110, {0xFF, 3, 0xFF, 0xFF, 0xFF, 0xCA, 0xFE, 0}, START + 4 * MS));  // Abort to us
  f.sut->onFrame(BUS_A, frameOf(0x1CEC3310, {0x11, 2, 1, 0xFF, 0xFF, 0xCA, 0xFE, 0}, START + 5 * MS));  // CTS to 0x33
  f.sut->onFrame(BUS_A, frameOf(0x1CEC2110, {0x10, 20, 0, 3, 0xFF, 0x30, 0xFF, 0}, START + 6 * MS));   // RTS to us: can-rx's
  REQUIRE(f.outputs.networkFrames.size() == 4);
  CHECK(f.outputs.networkFrames[0].second.id == 0x18EEFF10);
  CHECK(f.outputs.networkFrames[1].second.data[0] == 0x11);
  CHECK(f.outputs.networkFrames[2].second.data[0] == 0x13);
  CHECK(f.outputs.networkFrames[3].second.data[0] == 0xFF);
  CHECK(f.sut->counters(BUS_A).addressClaims == 1);
  CHECK(f.sut->counters(BUS_A).ownAddressChanges == 0);
  // the RTS went to the receiver as before: it answered with a CTS
  REQUIRE_FALSE(f.outputs.transmitted.empty());
  CHECK(f.outputs.transmitted.back().second.data[0] == 0x11);
}

TEST_CASE("after the VCU's own claim of a new address requests and RTS to it are answered and the old address is another node's (issue 24)") {
  Fixture f;
  // the VCU's NAME (tests/data/can-rx/vehicle.json bus a): identity 1, function 128,
  // vehicle system 1, industry group 3, arbitrary address capable -> 0xB002800000000001
  const std::vector<std::uint8_t> ownName{0x01, 0x00, 0x00, 0x00, 0x00, 0x80, 0x02, 0xB0};
  f.sut->onFrame(BUS_A, frameOf(0x18EA21F3, {0xE6, 0xFE, 0x00}, START + MS));  // Time/Date to 0x21
  REQUIRE(f.outputs.requests.size() == 1);
  f.sut->onFrame(BUS_A, frameOf(0x18EEFF80, ownName, START + 2 * MS));  // the VCU moved to 0x80
  CHECK(f.sut->counters(BUS_A).ownAddressChanges == 1);
  f.sut->onFrame(BUS_A, frameOf(0x18EA21F3, {0xE6, 0xFE, 0x00}, START + 3 * MS));  // to 0x21: not ours now
  CHECK(f.outputs.requests.size() == 1);
  f.sut->onFrame(BUS_A, frameOf(0x18EA80F3, {0xE6, 0xFE, 0x00}, START + 4 * MS));  // to 0x80: ours
  CHECK(f.outputs.requests.size() == 2);
  // an RTS to the new address is answered from it; a CTS to it goes to can-tx
  f.outputs.transmitted.clear();
  f.sut->onFrame(BUS_A, frameOf(0x1CEC8010, {0x10, 20, 0, 3, 0xFF, 0x30, 0xFF, 0x00}, START + 5 * MS));
  REQUIRE(f.outputs.transmitted.size() == 1);
  CHECK(f.outputs.transmitted[0].second.id == 0x1CEC1080u);  // CTS to 0x10 from 0x80
  const std::size_t before = f.outputs.networkFrames.size();
  f.sut->onFrame(BUS_A, frameOf(0x1CEC8010, {0x11, 2, 1, 0xFF, 0xFF, 0xCA, 0xFE, 0}, START + 6 * MS));
  CHECK(f.outputs.networkFrames.size() == before + 1);
}
