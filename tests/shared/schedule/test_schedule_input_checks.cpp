// Issue #19, "every bad input refused", for the transmit schedule: an entry given twice,
// fractional or too short cycles (file, overlay-style runtime changes, added messages) and a
// schedule whose cyclic frames would take more than config::MAX_CYCLIC_BUS_LOAD of a bus.

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/schedule/schedule_config.hpp"
#include "vehicle_fixture.hpp"

using namespace openvcu;

namespace {

const std::string HHEA = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";
constexpr std::int64_t NS_PER_MS = 1'000'000;

struct Fixture : openvcu::testing::VehicleTable {
  std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("openvcu-txinput-" + std::to_string(::getpid()));

  Fixture() : VehicleTable(HHEA) { std::filesystem::create_directories(folder); }
  ~Fixture() {
    std::error_code ignored;
    std::filesystem::remove_all(folder, ignored);
  }
  Result<schedule::Schedule> load(const std::string& json) {
    vehicle.scheduleFile = (folder / "schedule.json").string();
    std::ofstream(vehicle.scheduleFile) << json;
    return schedule::loadSchedule(vehicle, catalog);
  }
  std::string error(const std::string& json) {
    auto result = load(json);
    REQUIRE_MESSAGE(!result, json);
    return result.error().toString();
  }
};

}  // namespace

TEST_CASE("#19 a schedule entry given twice is refused with both places, not the last one sent") {
  Fixture f;
  const std::string sut = f.error(
      "{\n"
      "  \"messages\": {\n"
      "    \"PDU_Rx_1\": {\"cycleMs\": 100},\n"
      "    \"PDU_Rx_1\": {\"cycleMs\": 1}\n"
      "  }\n"
      "}\n");
  CHECK(sut.ends_with("schedule.json:4:5: /messages: key \"PDU_Rx_1\" given twice (first at 3:5)"));
}

TEST_CASE("#19 a fractional or too short cycle in the schedule file is refused") {
  Fixture f;
  CHECK(f.error(R"({"messages": {"PDU_Rx_1": {"cycleMs": 0.5}}})")
            .ends_with("/messages/PDU_Rx_1/cycleMs: the cycle must be a whole number of ms from 1 to 3600000, "
                       "not 0.5"));
  CHECK(f.error(R"({"messages": {"PDU_Rx_1": {"cycleMs": 20.5}}})").find("not 20.5") != std::string::npos);
  CHECK(f.error(R"({"messages": {"PDU_Rx_1": {"cycleMs": 3600001}}})").find("/cycleMs") != std::string::npos);
  CHECK(f.error(R"({"messages": {"PDU_Rx_1": {"cycleMs": -1}}})").find("/cycleMs") != std::string::npos);

  const auto whole = f.load(R"({"messages": {"PDU_Rx_1": {"cycleMs": 20}}})");
  REQUIRE_MESSAGE(whole, whole.error().toString());
  const auto pdu = schedule::findScheduled(*whole, f.vehicle, "PDU_Rx_1");
  REQUIRE(pdu);
  CHECK(whole->messages[*pdu].cycleNs == 20 * NS_PER_MS);
}

TEST_CASE("cycleMs 0 in the schedule file is refused with the allowed range, not taken as 'never cyclic'") {
  Fixture f;
  const std::string sut = f.error(R"({"messages": {"HC1_Demands": {"cycleMs": 0}}})");
  CHECK_MESSAGE(sut.ends_with("schedule.json: /messages/HC1_Demands/cycleMs: the cycle must be a whole number of ms "
                              "from 1 to 3600000, not 0; leave \"cycleMs\" out for the DBC's GenMsgCycleTime "
                              "(a message without one is not cyclic)"),
                sut);
}

TEST_CASE("a schedule naming another node's message is refused: the VCU would send as that node") {
  Fixture f;
  SUBCASE("under /messages") {
    const std::string sut = f.error(R"({"messages": {"HVESSS1_PGN61590": {}}})");
    CHECK_MESSAGE(sut.ends_with("schedule.json: /messages/HVESSS1_PGN61590: message 'HVESSS1_PGN61590' is sent by "
                                "VIC (its DBC transmitter), not by Vehicle_Control_Unit: scheduling it would make "
                                "the VCU impersonate VIC; if Vehicle_Control_Unit really sends it (a gateway), name "
                                "it among the message's transmitters in the DBC (BO_TX_BU_ 2498795251 : "
                                "VIC,Vehicle_Control_Unit;)"),
                  sut);
  }
  SUBCASE("in the include list") {
    const std::string sut = f.error(R"({"include": ["PDU_Rx_1", "HVESSS1_PGN61590"]})");
    CHECK_MESSAGE(sut.find("schedule.json: /include/1: message 'HVESSS1_PGN61590' is sent by VIC") != std::string::npos,
                  sut);
  }
}

TEST_CASE("#19 runtime cycle changes and added messages take whole milliseconds only") {
  Fixture f;
  const auto schedule = f.load("{}");
  REQUIRE(schedule);
  const auto pdu = schedule::findScheduled(*schedule, f.vehicle, "PDU_Rx_1");
  REQUIRE(pdu);
  const schedule::ScheduledMessage& entry = schedule->messages[*pdu];

  CHECK(schedule::checkCycle(entry, 0.5) == "the cycle must be a whole number of ms from 1 to 3600000, not 0.5");
  CHECK(schedule::checkCycle(entry, 1.5).has_value());
  CHECK_FALSE(schedule::checkCycle(entry, config::MIN_CYCLE_MS).has_value());
  const auto added = schedule::runtimeMessage(*schedule, f.vehicle, f.catalog, "HVESSD2_PGN61585", 0.5);
  REQUIRE_FALSE(added);
  CHECK(added.error().message.find("not 0.5") != std::string::npos);
}

TEST_CASE("#19 a schedule whose cyclic frames would take over half the bus is refused, naming the heaviest") {
  Fixture f;
  const auto hhea = f.load("{}");  // every transmitted message at its DBC cycle
  REQUIRE(hhea);
  CHECK_FALSE(schedule::checkBusLoad(*hhea, f.vehicle).has_value());

  // one 8-byte extended frame every ms is about 30 % of 500 kbit/s: two are over 50 %
  const std::string sut = f.error(R"({"messages": {"PDU_Rx_1": {"cycleMs": 1}, "HC1_Demands": {"cycleMs": 1}}})");

  CHECK(sut.find("schedule.json: /: the cyclic frames on bus 'vehicle' would take ") != std::string::npos);
  CHECK(sut.find("of its 500000 bit/s, more than the 50.0 % the VCU may use") != std::string::npos);
  CHECK(sut.find("every 1 ms") != std::string::npos);
  CHECK(sut.find("PDU_Rx_1") != std::string::npos);
  CHECK(sut.find("HC1_Demands") != std::string::npos);
}

TEST_CASE("#19 a message added at run time is refused when the schedule with it would take over half the bus") {
  Fixture f;
  const auto schedule = f.load("{}");  // HHEA: about a third of the bus
  REQUIRE(schedule);

  const auto sut = schedule::runtimeMessage(*schedule, f.vehicle, f.catalog, "HVESSD2_PGN61585", 1);
  const auto slower = schedule::runtimeMessage(*schedule, f.vehicle, f.catalog, "HVESSD2_PGN61585", 100);

  REQUIRE_FALSE(sut);
  CHECK(sut.error().message.find("the cyclic frames on bus 'vehicle' would take") != std::string::npos);
  CHECK(sut.error().message.find("HVESSD2_PGN61585 every 1 ms") != std::string::npos);
  CHECK(slower);
}
