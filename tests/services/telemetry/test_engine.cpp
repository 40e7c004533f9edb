// vcu-telemetry's engine (services/telemetry/src/engine.*) on a set clock and a real signal
// table: the rate limit and deadband per signal, one record per message with consecutive seq,
// state transitions, the fault set only when it changes, health when due.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "engine.hpp"
#include "shared/signals/signals_test_support.hpp"

namespace {

using namespace openvcu;
using Json = nlohmann::json;

constexpr std::int64_t MS = 1'000'000;
constexpr std::int64_t START_NS = 1'000'000 * MS;  ///< an arbitrary monotonic start
constexpr std::int64_t START_UNIX_MS = 1'764'259'200'000;
constexpr std::uint16_t SOURCE = 0xF3;

/// A DM1 event as vcu-can-rx publishes it (docs/design/telemetry.md, "Payloads").
ipc::NodeDm1 nodeDm1(std::string bus, std::string node, std::uint8_t source, std::uint8_t lamps, std::uint8_t flash,
                     std::vector<ipc::NodeDtc> dtcs) {
  ipc::NodeDm1 message;
  message.bus = std::move(bus);
  message.node = std::move(node);
  message.source = source;
  message.lamps = lamps;
  message.flash = flash;
  message.dtcs = std::move(dtcs);
  return message;
}

struct Bench {
  signals::testing::ScopedInstance instance{"telemetry-engine"};
  signals::Catalog catalog =
      signals::testing::makeCatalog({"BMS.SOC", "BMS.Current", "BMS.Unwatched", "internal.dm1.BMS.activeDtcs"});
  std::optional<signals::SignalTable> table;
  std::optional<telemetry::Engine> sut;

  explicit Bench(std::vector<config::TelemetrySignal> watched) {
    auto opened = signals::SignalTable::open(catalog, instance.name());
    REQUIRE(opened.ok());
    table.emplace(std::move(*opened));
    config::TelemetryConfig settings;
    settings.signals = std::move(watched);
    auto created = telemetry::Engine::create(settings, catalog, *table);
    REQUIRE(created);
    sut.emplace(std::move(*created));
  }
  void write(const std::string& key, double value, std::int64_t atNs) {
    REQUIRE(table->writeBus(*catalog.indexOf(key), value, atNs, SOURCE, signals::Quality::Valid));
  }
  /// The records of a tick at `nowNs`, parsed: (topic suffix, JSON).
  std::vector<std::pair<std::string, Json>> tick(std::uint64_t first, std::int64_t nowNs) {
    telemetry::TickInputs inputs;
    inputs.clocks = {.monoNs = nowNs, .unixMs = START_UNIX_MS + (nowNs - START_NS) / MS};
    std::vector<std::pair<std::string, Json>> out;
    for (const std::string& record : sut->tick(first, inputs)) {
      const auto newline = record.find('\n');
      REQUIRE(newline != std::string::npos);
      out.emplace_back(record.substr(0, newline), Json::parse(record.substr(newline + 1)));
    }
    return out;
  }
  static std::vector<Json> samplesOf(const std::vector<std::pair<std::string, Json>>& records) {
    std::vector<Json> samples;
    for (const auto& [topic, body] : records) {
      if (topic != "signals") continue;
      for (const Json& sample : body["samples"])
        samples.push_back({body["names"][sample[0].get<int>()], sample[1], sample[2]});
    }
    return samples;
  }
};

}  // namespace

TEST_CASE("telemetry engine: a signal changing every 10 ms is sampled at most maxRateHz times a second") {
  Bench bench({{.name = "BMS.Current", .maxRateHz = 2, .deadband = 0}});
  for (int i = 0; i < 100; ++i) {  // one second, a new value every 10 ms
    const std::int64_t now = START_NS + i * 10 * MS;
    bench.write("BMS.Current", i, now);
    bench.sut->sample(now);
  }
  const auto samples = Bench::samplesOf(bench.tick(1, START_NS + 1000 * MS));
  REQUIRE(samples.size() == 2);  // at 0 ms and 500 ms
  CHECK(samples[0][2] == 0.0);
  CHECK(samples[1][2] == 50.0);
  // each sample keeps the table's stamp as Unix ms
  CHECK(samples[0][1] == START_UNIX_MS);
  CHECK(samples[1][1] == START_UNIX_MS + 500);
}

TEST_CASE("telemetry engine: a value within the deadband of the last one sent is not sent, one beyond it is") {
  Bench bench({{.name = "BMS.SOC", .maxRateHz = 100, .deadband = 0.5}});
  const std::vector<double> values{50.0, 50.3, 50.45, 50.6, 50.9, 51.2, 49.0};
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::int64_t now = START_NS + static_cast<std::int64_t>(i) * 100 * MS;
    bench.write("BMS.SOC", values[i], now);
    bench.sut->sample(now);
  }
  const auto samples = Bench::samplesOf(bench.tick(1, START_NS + 1000 * MS));
  std::vector<double> sent;
  for (const Json& sample : samples) sent.push_back(sample[2].get<double>());
  CHECK(sent == std::vector<double>{50.0, 50.6, 51.2, 49.0});
}

TEST_CASE("telemetry engine: an unchanged signal is sent again after a minute, an unwritten one never") {
  Bench bench(
      {{.name = "BMS.SOC", .maxRateHz = 1, .deadband = 0}, {.name = "BMS.Current", .maxRateHz = 1, .deadband = 0}});
  bench.write("BMS.SOC", 80, START_NS);
  std::size_t sent = 0;
  for (std::int64_t second = 0; second <= 61; ++second) {
    const std::int64_t now = START_NS + second * 1000 * MS;
    bench.write("BMS.SOC", 80, now);  // rewritten, same value, still fresh
    bench.sut->sample(now);
    sent += Bench::samplesOf(bench.tick(1, now)).size();
  }
  CHECK(sent == 2);  // at 0 s and at 60 s
}

TEST_CASE("telemetry engine: records are numbered from the queue's next sequence, state and faults each once") {
  Bench bench({{.name = "BMS.SOC", .maxRateHz = 1, .deadband = 0}});
  bench.write("BMS.SOC", 80, START_NS);
  bench.sut->sample(START_NS);
  bench.sut->onTransition(
      {.timestampNs = START_UNIX_MS * MS, .fromState = "Init", .toState = "Ready", .cause = "boot"});
  bench.sut->onFault({.timestampNs = START_UNIX_MS * MS,
                      .name = "Contactor",
                      .source = "vcu-fsm",
                      .severity = ipc::FaultSeverity::Error,
                      .active = true,
                      .text = "welded"});

  const auto first = bench.tick(41, START_NS + 500 * MS);
  REQUIRE(first.size() == 4);
  CHECK(first[0].first == "state");
  CHECK(first[0].second["state"] == "Ready");
  CHECK(first[0].second["previous"] == "Init");
  CHECK(first[1].first == "faults");
  CHECK(first[1].second["active"][0]["name"] == "Contactor");
  CHECK(first[2].first == "health");
  CHECK(first[3].first == "signals");
  for (std::size_t i = 0; i < first.size(); ++i) {
    CHECK(first[i].second["v"] == 1);
    CHECK(first[i].second["seq"] == 41 + i);
    CHECK(first[i].second["t"] == START_UNIX_MS + 500);
  }

  // nothing new: no state, no faults, no health before 10 s, no signals
  CHECK(bench.tick(45, START_NS + 1500 * MS).empty());

  // a node's DM1 with two DTCs and the fault cleared: one faults message with the new set
  bench.sut->onDm1(nodeDm1("", "BMS", 0xF3, 0x04, 0, {{100, 1, 3, false}, {200, 2, 1, false}}));
  bench.sut->onFault({.timestampNs = 0,
                      .name = "Contactor",
                      .source = "vcu-fsm",
                      .severity = ipc::FaultSeverity::Error,
                      .active = false,
                      .text = {}});
  const auto second = bench.tick(45, START_NS + 2500 * MS);
  REQUIRE(second.size() == 1);
  CHECK(second[0].first == "faults");
  CHECK(second[0].second["active"].empty());
  CHECK(second[0].second["dm1"][0]["node"] == "BMS");
  CHECK(second[0].second["dm1"][0]["activeDtcs"] == 2);

  // health at once when the link's counters change, else again after 10 s
  telemetry::TickInputs connected;
  connected.clocks = {.monoNs = START_NS + 3500 * MS, .unixMs = START_UNIX_MS + 3500};
  connected.link.connects = 1;
  const auto linked = bench.sut->tick(46, connected);
  REQUIRE(linked.size() == 1);
  CHECK(linked[0].starts_with("health\n"));
  CHECK(linked[0].find("\"connects\":1") != std::string::npos);
  CHECK(bench.sut->tick(47, connected).empty());
  const auto later = bench.tick(47, START_NS + 13'600 * MS);  // connects back to 0: a change too
  REQUIRE(later.size() == 1);
  CHECK(later[0].first == "health");
}

TEST_CASE("telemetry engine: the faults message carries each node's DM1 lamps and DTCs, again when one changes (#25)") {
  Bench bench({});
  // BMS: red stop and amber warning lamps on (DM1 byte 0 = 0x14), two DTCs; INV: a DM1 without DTCs
  bench.sut->onDm1(nodeDm1("vehicle", "BMS", 0xF3, 0x14, 0xFF,
                           {{.spn = 1234, .fmi = 3, .occurrences = 5, .conversionMethod = false},
                            {.spn = 524287, .fmi = 31, .occurrences = 127, .conversionMethod = true}}));
  bench.sut->onDm1(nodeDm1("vehicle", "INV", 0xEF, 0x00, 0xFF, {}));
  telemetry::TickInputs inputs;
  inputs.clocks = {.monoNs = START_NS, .unixMs = START_UNIX_MS};
  const std::vector<std::string> first = bench.sut->tick(7, inputs);
  REQUIRE_FALSE(first.empty());
  CHECK(first[0] ==
        "faults\n{\"v\":1,\"seq\":7,\"t\":1764259200000,\"active\":[],\"dm1\":[{\"node\":\"BMS\",\"activeDtcs\":2,"
        "\"lamps\":{\"malfunction\":\"Off\",\"redStop\":\"On\",\"amberWarning\":\"On\",\"protect\":\"Off\"},"
        "\"dtcs\":[{\"spn\":1234,\"fmi\":3,\"oc\":5,\"cm\":0},{\"spn\":524287,\"fmi\":31,\"oc\":127,\"cm\":1}]}]}");

  // the same DM1 again (can-rx repeats it every second): no faults message
  bench.sut->onDm1(nodeDm1("vehicle", "BMS", 0xF3, 0x14, 0xFF, {{1234, 3, 5, false}, {524287, 31, 127, true}}));
  inputs.clocks = {.monoNs = START_NS + 1000 * MS, .unixMs = START_UNIX_MS + 1000};
  CHECK(bench.sut->tick(9, inputs).empty());

  // only an occurrence count moves: the whole set goes out again
  bench.sut->onDm1(nodeDm1("vehicle", "BMS", 0xF3, 0x14, 0xFF, {{1234, 3, 6, false}, {524287, 31, 127, true}}));
  const auto counted = bench.tick(9, START_NS + 2000 * MS);
  REQUIRE(counted.size() == 1);
  CHECK(counted[0].first == "faults");
  CHECK(counted[0].second["dm1"][0]["dtcs"][0]["oc"] == 6);

  // the node's DTCs are gone: the node leaves the list
  bench.sut->onDm1(nodeDm1("vehicle", "BMS", 0xF3, 0x00, 0xFF, {}));
  const auto cleared = bench.tick(10, START_NS + 3000 * MS);
  REQUIRE(cleared.size() == 1);
  CHECK(cleared[0].second["dm1"].empty());
}

TEST_CASE("telemetry engine: a configured signal the catalog does not have is refused by name") {
  signals::testing::ScopedInstance instance("telemetry-engine-unknown");
  const signals::Catalog catalog = signals::testing::makeCatalog({"BMS.SOC"});
  auto table = signals::SignalTable::open(catalog, instance.name());
  REQUIRE(table.ok());
  config::TelemetryConfig settings;
  settings.signals = {{.name = "BMS.Nope", .maxRateHz = 1, .deadband = 0}};
  const auto sut = telemetry::Engine::create(settings, catalog, *table);
  REQUIRE_FALSE(sut);
  CHECK(sut.error().message == "/signals: not in this vehicle's catalog: 'BMS.Nope'");
}
