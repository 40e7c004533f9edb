// vcu-web's live state (services/web/src/live_state.hpp) on a set clock with a real signal
// table: a service that stops beating is shown as silent in the header's services, the FSM
// state of a silent vcu-fsm is marked as not current, and the fault service_silent.<name>
// is listed once (vcu-watchdog's, when it raised the same name).
#include <doctest/doctest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "live_state.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

using namespace openvcu;
using Json = nlohmann::json;

namespace {

constexpr std::int64_t SECOND_NS = 1'000'000'000;

signals::SignalInfo internal(const std::string& key) {
  signals::SignalInfo info;
  info.key = key;
  info.kind = signals::SignalKind::Internal;
  info.direction = signals::SignalDirection::Internal;
  info.minimum = 0;
  info.maximum = 1.8e19;
  return info;
}

signals::Catalog liveCatalog() {
  auto catalog = signals::Catalog::create({internal("internal.fsm.state"), internal("internal.service.fsm.heartbeat"),
                                           internal("internal.service.gpio.heartbeat")});
  REQUIRE(catalog);
  return std::move(*catalog);
}

/// A table of its own for one case, removed afterwards.
struct ScopedTable {
  std::string instance = "weblive" + std::to_string(::getpid());
  signals::SignalTable table;
  explicit ScopedTable(const signals::Catalog& catalog) : table(open(catalog, instance)) {}
  ~ScopedTable() { (void)signals::SignalTable::remove(instance); }
  static signals::SignalTable open(const signals::Catalog& catalog, const std::string& instance) {
    auto opened = signals::SignalTable::open(catalog, instance);
    REQUIRE(opened);
    return std::move(*opened);
  }
};

Json commonJson(web::LiveState& sut, std::int64_t nowNs) {
  std::uint64_t version = 0;
  return Json::parse("{" + sut.common(nowNs, version) + "}");
}

const Json* serviceNamed(const Json& common, const std::string& name) {
  for (const Json& service : common["header"]["services"]) {
    if (service["name"] == name) return &service;
  }
  return nullptr;
}

std::vector<Json> faultsNamed(const Json& common, const std::string& name) {
  std::vector<Json> found;
  for (const Json& fault : common["faults"]) {
    if (fault["name"] == name) found.push_back(fault);
  }
  return found;
}

}  // namespace

TEST_CASE("vcu-web shows a vcu-fsm that stopped beating as silent, its state as not current, and the fault") {
  const signals::Catalog catalog = liveCatalog();
  ScopedTable scoped(catalog);
  const std::int64_t start = clock::monotonicNs();
  scoped.table.writeBus(*catalog.indexOf("internal.fsm.state"), 2, start, 3, signals::Quality::Valid);
  scoped.table.writeBus(*catalog.indexOf("internal.service.fsm.heartbeat"), 1, start, 3, signals::Quality::Valid);
  web::LiveState sut(catalog, scoped.table, web::LiveSetup{});
  sut.onHeartbeat({.service = "vcu-fsm", .instance = "t", .pid = 42, .uptimeMs = 1, .counters = {}, .status = "ready"},
                  start);

  const Json beating = commonJson(sut, start + SECOND_NS);
  REQUIRE(serviceNamed(beating, "vcu-fsm"));
  CHECK((*serviceNamed(beating, "vcu-fsm"))["status"] == "Ready");
  CHECK(beating["header"]["stateStale"] == false);
  CHECK(faultsNamed(beating, "service_silent.fsm").empty());

  const Json silent = commonJson(sut, start + 4 * SECOND_NS);
  const Json* fsm = serviceNamed(silent, "vcu-fsm");
  REQUIRE(fsm);
  CHECK((*fsm)["status"] == "Stale");
  CHECK((*fsm)["liveness"] == "silent");
  CHECK(silent["header"]["stateStale"] == true);
  CHECK(silent["header"]["stateNote"].get<std::string>().find("vcu-fsm silent") != std::string::npos);
  const auto faults = faultsNamed(silent, "service_silent.fsm");
  REQUIRE(faults.size() == 1);
  CHECK(faults[0]["severity"] == "critical");
  CHECK(faults[0]["source"] == "heartbeats");
  CHECK(faultsNamed(silent, "service_silent.gpio").empty());  // never beat: not connected, no fault

  // vcu-watchdog raises the same name: listed once, as its fault
  sut.onFault({.timestampNs = 5,
               .name = "service_silent.fsm",
               .source = "vcu-watchdog",
               .severity = ipc::FaultSeverity::Critical,
               .active = true,
               .text = "vcu-fsm silent for 1.6 s"});
  const auto once = faultsNamed(commonJson(sut, start + 5 * SECOND_NS), "service_silent.fsm");
  REQUIRE(once.size() == 1);
  CHECK(once[0]["source"] == "vcu-watchdog");
}

TEST_CASE("vcu-web lists a service that beat only into the table before it started, as silent once it stops") {
  const signals::Catalog catalog = liveCatalog();
  ScopedTable scoped(catalog);
  const std::int64_t start = clock::monotonicNs();
  scoped.table.writeBus(*catalog.indexOf("internal.service.gpio.heartbeat"), 9, start, 4, signals::Quality::Valid);
  web::LiveState sut(catalog, scoped.table, web::LiveSetup{});

  const Json common = commonJson(sut, start + 3 * SECOND_NS);

  const Json* gpio = serviceNamed(common, "vcu-gpio");
  REQUIRE(gpio);
  CHECK((*gpio)["liveness"] == "silent");
  CHECK(faultsNamed(common, "service_silent.gpio").size() == 1);
}
