// can-rx's receive.json: defaults, every key, and errors with file and JSON path.

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "openvcu/config/receive.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string DATA = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/can-rx/";

config::VehicleConfig vehicle() {
  auto loaded = config::loadVehicleConfig(DATA + "vehicle.json");
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().toString()));
  return std::move(*loaded);
}

std::size_t messageIndex(const config::VehicleConfig& v, std::string_view name) {
  for (std::size_t m = 0; m < v.database.messages.size(); ++m) {
    if (v.database.messages[m].name == name) return m;
  }
  FAIL("no message " << name);
  return 0;
}

/// Loads `text` as the receive file of the test vehicle.
Result<config::ReceiveConfig> loadText(const std::string& text) {
  config::VehicleConfig v = vehicle();
  const fs::path file = fs::temp_directory_path() / ("receive-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << text;
  v.receiveFile = file.string();
  auto result = config::loadReceiveConfig(v);
  fs::remove(file);
  return result;
}

std::string errorOf(const std::string& text) {
  auto result = loadText(text);
  REQUIRE_FALSE(result);
  return result.error().toString();
}

}  // namespace

TEST_CASE("without a receive file the timeout is three DBC cycles for messages others send") {
  config::VehicleConfig v = vehicle();
  v.receiveFile.clear();
  const config::ReceiveConfig sut = config::defaultReceiveConfig(v);
  CHECK(sut.timeoutNs[messageIndex(v, "ECU1_Status")] == 60'000'000);
  CHECK(sut.timeoutNs[messageIndex(v, "BMS_Safe")] == 150'000'000);
  CHECK(sut.timeoutNs[messageIndex(v, "VCU_Cmd")] == 0);  // sent by this node
  CHECK(sut.timeoutNs[messageIndex(v, "GW_Info")] == 0);  // no cycle time
  CHECK(sut.safety.empty());
  CHECK(sut.forward.empty());
  CHECK(sut.dm1);
}

TEST_CASE("the test receive file sets a factor, a per-message timeout, a safety group and forwarding") {
  const config::VehicleConfig v = vehicle();
  auto result = config::loadReceiveConfig(v);
  REQUIRE_MESSAGE(result, (result ? "" : result.error().toString()));
  CHECK(result->timeoutNs[messageIndex(v, "Std_Msg")] == 0);
  REQUIRE(result->safety.size() == 1);
  CHECK(result->safety[0].dataMessage == messageIndex(v, "BMS_Safe"));
  CHECK(result->safety[0].maxHeaderToDataNs == 10'000'000);
  CHECK(result->safety[0].maxHeaderCycleNs == 100'000'000);
  REQUIRE(result->forward.size() == 2);
  CHECK(result->forward[0].fromBus == 0);
  CHECK(result->forward[0].toBus == 1);
  CHECK_FALSE(result->forward[0].byPgn);
  CHECK(result->forward[0].id == 0x18FF1010);
  CHECK(result->forward[0].rewriteId == 0x18FF1011u);
  CHECK(result->forward[1].byPgn);
  CHECK(result->forward[1].id == 0xFF60);
  CHECK(result->forward[1].source == std::uint8_t{0x45});
}

TEST_CASE("timeoutFactor scales every DBC-derived timeout, explicit timeouts win") {
  const config::VehicleConfig v = vehicle();
  auto result = loadText(R"({"timeoutFactor": 5, "messages": {"ECU1_Status": {"timeoutMs": 35}}})");
  REQUIRE(result);
  CHECK(result->timeoutNs[messageIndex(v, "ECU1_Status")] == 35'000'000);
  CHECK(result->timeoutNs[messageIndex(v, "BMS_Safe")] == 250'000'000);
}

TEST_CASE("receive file errors name the file, the JSON path and the reason") {
  CHECK(errorOf(R"({"timeoutFactr": 3})").find("timeoutFactr") != std::string::npos);
  CHECK(errorOf(R"({"timeoutFactr": 3})").find("did you mean 'timeoutFactor'") != std::string::npos);
  const std::string unknown = errorOf(R"({"messages": {"ECU1_Statuss": {"timeoutMs": 10}}})");
  CHECK(unknown.find("/messages/ECU1_Statuss") != std::string::npos);
  CHECK(unknown.find("did you mean 'ECU1_Status'") != std::string::npos);
  CHECK(errorOf(R"({"messages": {"VCU_Cmd": {"timeoutMs": 10}}})").find("sent by this node") != std::string::npos);
  CHECK(errorOf(R"({"timeoutFactor": 0.5})").find("/timeoutFactor") != std::string::npos);
  CHECK(errorOf(R"({"safety": [{"message": "Std_Msg", "maxDelayMs": 10, "headerCycleMs": 100}]})")
            .find("8-byte 29-bit") != std::string::npos);
  CHECK(errorOf(R"({"safety": [{"message": "BMS_Safe", "maxDelayMs": 0, "headerCycleMs": 100}]})")
            .find("/safety/0/maxDelayMs") != std::string::npos);
  CHECK(errorOf(R"({"forward": [{"from": "a", "to": "c", "id": 1}]})").find("unknown bus 'c'") != std::string::npos);
  CHECK(errorOf(R"({"forward": [{"from": "a", "to": "a", "id": 1}]})").find("loop") != std::string::npos);
  CHECK(errorOf(R"({"forward": [{"from": "a", "to": "b"}]})").find("exactly one of") != std::string::npos);
  CHECK(errorOf(R"({"forward": [{"from": "a", "to": "b", "id": "0xZZ"}]})").find("/forward/0/id") !=
        std::string::npos);
  CHECK(errorOf(R"({"forward": [{"from": "a", "to": "b", "pgn": 262144}]})").find("18 bits") != std::string::npos);
  CHECK(errorOf(R"({"forward": [{"from": "a", "to": "b", "id": 5, "source": 3}]})").find("/forward/0/source") !=
        std::string::npos);
  CHECK(errorOf("{\"dm1\": tru}").find("receive-") != std::string::npos);  // syntax error names the file
}
