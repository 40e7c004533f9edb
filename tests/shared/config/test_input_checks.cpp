// Issue #19, "every bad input refused": the one JSON reader refuses keys given twice (with
// both places and the object's path) and numbers that overflow a double (with the path);
// numbers print short; the cycle limits and the bus-load sum shared by every schedule reader.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include "config_fixture.hpp"
#include "openvcu/can/wire_time.hpp"
#include "openvcu/config/gpio.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/config/vehicle.hpp"

using namespace openvcu;
using namespace openvcu::config;

namespace {
constexpr std::size_t TEN_MEGABYTES = 10'000'000;
}

TEST_CASE("#19 a key given twice is refused with both places and the object's JSON path") {
  const std::string text =
      "{\n"
      "  \"states\": [\n"
      "    {\"name\": \"Idle\"},\n"
      "    {\"name\": \"Run\", \"transitions\": [\n"
      "      {\"nextState\": \"Idle\",\n"
      "        \"nextState\": \"Run\"}]}\n"
      "  ]\n"
      "}\n";
  const auto sut = parseJson(text, "fsm.json");
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().toString() ==
        "fsm.json:6:9: /states/1/transitions/0: key \"nextState\" given twice (first at 5:8)");
  CHECK(sut.error().location.line == 6);
  CHECK(sut.error().location.column == 9);
  CHECK(sut.error().location.jsonPath == "/states/1/transitions/0");
}

TEST_CASE("#19 keys equal once decoded are the same key, and equal keys in different objects are fine") {
  const auto escaped = parseJson(R"({"a": {"bitrate": 1, "bit\u0072ate": 2}})", "v.json");
  const auto atRoot = parseJson("{\"x\": 1, // a comment with \"x\": 2\n \"x\": 3}", "v.json");
  const auto separate = parseJson(R"([{"a": 1}, {"a": 2}, {"b": {"a": 3}}, "a", {"a": {"a": 4}}])", "v.json");
  const auto slashKey = parseJson(R"({"a/b": {"k": 1, "k": 2}})", "v.json");
  const auto withByteOrderMark = parseJson("\xEF\xBB\xBF{\"k\": 1, \"k\": 2}", "v.json");

  REQUIRE_FALSE(escaped.ok());
  CHECK(escaped.error().toString() == "v.json:1:22: /a: key \"bitrate\" given twice (first at 1:8)");
  REQUIRE_FALSE(atRoot.ok());
  CHECK(atRoot.error().toString() == "v.json:2:2: /: key \"x\" given twice (first at 1:2)");
  CHECK(separate.ok());
  REQUIRE_FALSE(slashKey.ok());
  CHECK(slashKey.error().location.jsonPath == "/a~1b");  // RFC 6901
  REQUIRE_FALSE(withByteOrderMark.ok());
  CHECK(withByteOrderMark.error().message == "key \"k\" given twice (first at 1:5)");  // columns count bytes
}

TEST_CASE("#19 a key given twice in an object of many keys is found (the hashed path)") {
  std::string text = "{";
  for (int i = 0; i < 1000; ++i) text += "\"k" + std::to_string(i) + "\": " + std::to_string(i) + ", ";
  text += "\"k17\": 0}";
  const auto sut = parseJson(text, "v.json");
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message == "key \"k17\" given twice (first at 1:" + std::to_string(text.find("\"k17\"") + 1) + ")");
}

TEST_CASE("#19 a control character in a duplicated key is escaped in the message") {
  const auto sut = parseJson("{\"a\\nb\": 1, \"a\\u000ab\": 2}", "v.json");
  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().message == "key \"a\\u000ab\" given twice (first at 1:2)");
}

TEST_CASE("#19 a 10 MB document is read in one linear pass, a duplicate at its very end found") {
  std::string text = "{\"signals\": [";
  int count = 0;
  while (text.size() < TEN_MEGABYTES) {
    text += "{\"name\": \"s" + std::to_string(count) + "\", \"min\": 0, \"max\": 1.5, \"unit\": \"V\"},\n";
    ++count;
  }
  text += "{\"name\": \"last\", \"unit\": \"A\", \"unit\": \"V\"}]}";
  const auto start = std::chrono::steady_clock::now();
  const auto sut = parseJson(text, "big.json");
  const auto elapsed = std::chrono::steady_clock::now() - start;

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().location.jsonPath == "/signals/" + std::to_string(count));
  // nlohmann's parse plus the scan: 0.5 s in Release, about 10 s in the -O0 sanitizer build;
  // a quadratic scan would take hours
  CHECK(elapsed < std::chrono::seconds(60));
}

TEST_CASE("#19 a number that overflows a double is refused with its place and JSON path, not thrown") {
  const auto sut = parseJson("{\"battery\": {\n  \"capacityAh\": 1e999}}", "simulation.json");
  const auto negative = parseJson("[1, 2, -1e400]", "x.json");

  REQUIRE_FALSE(sut.ok());
  CHECK(sut.error().toString() ==
        "simulation.json:2:17: /battery/capacityAh: number 1e999 is out of range (a configuration number must be "
        "a finite double)");
  REQUIRE_FALSE(negative.ok());
  CHECK(negative.error().location.jsonPath == "/2");
}

TEST_CASE("#19 the number getter refuses NaN and infinity put into a document by code") {
  JsonChecker sut("v.json");
  Json document;
  document["nan"] = std::numeric_limits<double>::quiet_NaN();
  document["inf"] = std::numeric_limits<double>::infinity();

  CHECK_FALSE(sut.number(document, "/x", "nan").has_value());
  CHECK_FALSE(sut.number(document, "/x", "inf").has_value());
  REQUIRE(sut.diagnostics().size() == 2);
  CHECK(sut.diagnostics()[0].toString() == "v.json: /x/nan: must be a finite number, not nan");
  CHECK(sut.diagnostics()[1].toString() == "v.json: /x/inf: must be a finite number, not inf");
}

TEST_CASE("#19 vehicle.json and gpio.json go through the reader: a key given twice refuses them") {
  const test::TempConfig vehicle(
      "{\"instance\": \"t\", \"node\": \"VCU\", \"dbc\": \"small.dbc\",\n"
      " \"buses\": [{\"name\": \"vehicle\", \"link\": \"sim:v\", \"bitrate\": 500000,\n"
      "   \"bitrate\": 250000, \"messages\": \"all\"}]}");
  const auto vehicleResult = loadVehicleConfig(vehicle.path());
  REQUIRE_FALSE(vehicleResult.ok());
  CHECK(vehicleResult.error().toString().ends_with(
      "vehicle.json:3:4: /buses/0: key \"bitrate\" given twice (first at 2:49)"));

  const std::string gpioPath = vehicle.dir() + "/gpio.json";
  std::ofstream(gpioPath) << "{\"chip\": \"a\", \"chip\": \"b\"}";
  std::vector<Error> diagnostics;
  const auto gpioResult = loadGpioMap(gpioPath, {}, diagnostics);
  CHECK_FALSE(gpioResult.has_value());
  REQUIRE(diagnostics.size() == 1);
  CHECK(diagnostics[0].message == "key \"chip\" given twice (first at 1:2)");
}

TEST_CASE("#19 numbers in messages are short: whole numbers in full, others the shortest exact form") {
  CHECK(formatNumber(1e308) == "1e+308");
  CHECK(formatNumber(3'600'000) == "3600000");
  CHECK(formatNumber(0.1) == "0.1");
  CHECK(formatNumber(-2.5e-7) == "-2.5e-07");
  CHECK(formatNumber(std::nan("")) == "nan");
  CHECK(formatNumber(-std::numeric_limits<double>::infinity()) == "-inf");
}

TEST_CASE("#19 cycles are whole milliseconds from MIN_CYCLE_MS to MAX_CYCLE_MS") {
  CHECK_FALSE(checkCycleMs(MIN_CYCLE_MS).has_value());
  CHECK_FALSE(checkCycleMs(MAX_CYCLE_MS).has_value());
  CHECK(checkCycleMs(0.5) == "the cycle must be a whole number of ms from 1 to 3600000, not 0.5");
  CHECK(checkCycleMs(20.25).has_value());
  CHECK(checkCycleMs(0).has_value());
  CHECK(checkCycleMs(MAX_CYCLE_MS + 1.0).has_value());
  CHECK(checkCycleMs(std::nan("")) == "the cycle must be a whole number of ms from 1 to 3600000, not nan");
  CHECK(checkCycleMs(std::numeric_limits<double>::infinity()).has_value());
}

TEST_CASE("#19 the cyclic bus load is the exact wire time of an all-zero frame over its cycle") {
  BusConfig bus;
  bus.bitrate = 500'000;
  bus.dataBitrate = 2'000'000;
  constexpr std::int64_t TEN_MS = 10'000'000;
  const std::array<CyclicFrame, 3> frames = {{{0x18FEF121, true, 8, TEN_MS},
                                              {0x123, false, 2, 2 * TEN_MS},
                                              {0x1, false, 8, 0}}};  // not cyclic: skipped
  can::Frame extended;
  extended.id = 0x18FEF121;
  extended.flags = can::FLAG_EXTENDED;
  extended.length = 8;
  can::Frame standard;
  standard.id = 0x123;
  standard.length = 2;
  const double expected = static_cast<double>(can::wireTimeNs(extended, bus.bitrate, bus.dataBitrate)) / TEN_MS +
                          static_cast<double>(can::wireTimeNs(standard, bus.bitrate, bus.dataBitrate)) / (2 * TEN_MS);

  const double sut = cyclicBusLoad(frames, bus);

  CHECK(sut == doctest::Approx(expected).epsilon(1e-12));
  CHECK(sut > 0.03);  // an 8-byte extended frame is ~150 bits with all-zero stuffing: 300 us of 10 ms
}
