// receive.json "senders" and "expectedWhen": which condition each received message is
// supervised under, and bad input refused with the file, the JSON path and the reason.
// Tests/data/can-rx: nodes VCU (this node), ECU1, BMS, GW.

#include <doctest/doctest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "openvcu/config/receive.hpp"

using namespace openvcu;
namespace fs = std::filesystem;

namespace {

const std::string DATA = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/can-rx/";
constexpr std::int64_t MS = 1'000'000;

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

Result<config::ReceiveConfig> loadText(const std::string& text) {
  config::VehicleConfig v = vehicle();
  const fs::path file = fs::temp_directory_path() / ("receive-expect-" + std::to_string(::getpid()) + ".json");
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

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

const std::string AWAKE = R"({"signal": "internal.fsm.state", "eq": 2, "startMs": 500})";

}  // namespace

TEST_CASE("without expectedWhen every received message is expected from the start") {
  const config::VehicleConfig v = vehicle();
  const config::ReceiveConfig sut = config::defaultReceiveConfig(v);
  CHECK(sut.expectations.empty());
  REQUIRE(sut.expectationOf.size() == v.database.messages.size());
  for (const std::int32_t expectation : sut.expectationOf) CHECK(expectation == config::ALWAYS_EXPECTED);
}

TEST_CASE("a sender's expectedWhen applies to its messages, and a message's own wins, also always") {
  const config::VehicleConfig v = vehicle();
  auto result = loadText(R"({"senders": {"ECU1": {"expectedWhen": )" + AWAKE + R"(}},
                             "messages": {"ECU1_Big": {"expectedWhen": "always"},
                                          "Std_Msg": {"timeoutMs": 0, "expectedWhen": )" +
                         AWAKE + R"(}}})");
  REQUIRE_MESSAGE(result, (result ? "" : result.error().toString()));
  REQUIRE(result->expectations.size() == 1);  // the same condition twice is stored once
  const config::ReceiveExpectation& awake = result->expectations[0];
  CHECK(awake.signal == "internal.fsm.state");
  CHECK(awake.equals == 2.0);
  CHECK(awake.startNs == 500 * MS);
  CHECK(awake.origin == "/senders/ECU1/expectedWhen");
  CHECK(result->expectationOf[messageIndex(v, "ECU1_Status")] == 0);
  CHECK(result->expectationOf[messageIndex(v, "ECU1_Big")] == config::ALWAYS_EXPECTED);
  CHECK(result->expectationOf[messageIndex(v, "Std_Msg")] == 0);
  CHECK(result->expectationOf[messageIndex(v, "BMS_Safe")] == config::ALWAYS_EXPECTED);
  CHECK(result->timeoutNs[messageIndex(v, "ECU1_Status")] == 60 * MS);  // timeouts unchanged
  CHECK(result->timeoutNs[messageIndex(v, "Std_Msg")] == 0);
}

TEST_CASE("expectedWhen errors name the file, the JSON path and the reason") {
  const std::string unknownNode = errorOf(R"({"senders": {"ECU2": {"expectedWhen": "always"}}})");
  CHECK(contains(unknownNode, "receive-expect-"));
  CHECK(contains(unknownNode, "/senders/ECU2: unknown node 'ECU2'; did you mean 'ECU1'?"));
  CHECK(contains(errorOf(R"({"senders": {"VCU": {"expectedWhen": "always"}}})"), "/senders/VCU: 'VCU' is this node"));
  CHECK(contains(errorOf(R"({"senders": {"ECU1": {}}})"), "/senders/ECU1"));
  CHECK(contains(errorOf(R"({"senders": {"ECU1": {"expectedWhen": "sometimes"}}})"),
                 "/senders/ECU1/expectedWhen: must be \"always\" or an object"));
  CHECK(contains(errorOf(R"({"senders": {"ECU1": {"expectedWhen": {"signal": "internal.fsm.stat", "eq": 1}}}})"),
                 "/senders/ECU1/expectedWhen/signal: unknown signal 'internal.fsm.stat'"));
  CHECK(contains(errorOf(R"({"senders": {"ECU1": {"expectedWhen": {"signal": "internal.fsm.state"}}}})"),
                 "/senders/ECU1/expectedWhen"));
  CHECK(contains(errorOf(R"({"senders": {"ECU1": {"expectedWhen": {"signal": "internal.fsm.state", "eq": "on"}}}})"),
                 "/senders/ECU1/expectedWhen/eq"));
  CHECK(contains(
      errorOf(R"({"senders": {"ECU1": {"expectedWhen": {"signal": "internal.fsm.state", "eq": 1, "startMs": -5}}}})"),
      "/senders/ECU1/expectedWhen/startMs: must be a whole number of milliseconds from 0 to 600000"));
  CHECK(contains(
      errorOf(R"({"senders": {"ECU1": {"expectedWhen": {"signal": "internal.fsm.state", "eq": 1, "after": 5}}}})"),
      "after"));
  CHECK(contains(errorOf(R"({"messages": {"ECU1_Status": {}}})"),
                 "/messages/ECU1_Status: give \"timeoutMs\", \"expectedWhen\" or both"));
  CHECK(contains(errorOf(R"({"messages": {"VCU_Cmd": {"expectedWhen": "always"}}})"),
                 "/messages/VCU_Cmd/expectedWhen: message 'VCU_Cmd' is sent by this node"));
}
