// The HMI's header and Debug models when a service stops beating, with a real signal table
// (a private instance) whose heartbeat slots say when each service last beat: vcu-fsm silent
// makes the FSM state stale with a note, its health row silent and the fault
// service_silent.fsm listed; a beat again clears all three.
#include <doctest/doctest.h>

#include <memory>
#include <string>

#include "debug/fault_model.hpp"
#include "header/fsm_model.hpp"
#include "header/health_model.hpp"
#include "hmi_test_support.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/signals/table.hpp"

using namespace openvcu;
using namespace openvcu::hmi;

namespace {

constexpr std::int64_t SECOND_NS = 1'000'000'000;

int rowNamed(const HealthModel& model, const QString& name) {
  for (int row = 0; row < model.rowCount(); ++row) {
    if (model.data(model.index(row), HealthModel::NameRole).toString() == name) return row;
  }
  return -1;
}

bool listsFault(const FaultModel& model, const QString& name) {
  for (int row = 0; row < model.rowCount(); ++row) {
    if (model.data(model.index(row), FaultModel::NameRole).toString() == name) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("the HMI shows a vcu-fsm that stopped beating as silent, its state as not current, and the fault") {
  test::ensureApplication("test_hmi_models");
  const StackSettings settings = test::memqSettings("hmi-silent");
  auto opened = StackConnection::open(settings);
  REQUIRE_MESSAGE(opened, opened.error().toString());
  const std::unique_ptr<StackConnection> stack = std::move(*opened);
  auto tableResult = signals::SignalTable::open(stack->catalog(), settings.instance);
  REQUIRE(tableResult);
  signals::SignalTable& table = *tableResult;
  const auto stateSlot = stack->catalog().indexOf("internal.fsm.state");
  const auto fsmBeat = stack->catalog().indexOf("internal.service.fsm.heartbeat");
  const auto canRxBeat = stack->catalog().indexOf("internal.service.can-rx.heartbeat");
  REQUIRE(stateSlot);
  REQUIRE(fsmBeat);
  REQUIRE(canRxBeat);
  const std::int64_t now = clock::monotonicNs();
  table.writeBus(*stateSlot, 0, now - 4 * SECOND_NS, 3, signals::Quality::Valid);
  table.writeBus(*fsmBeat, 7, now - 4 * SECOND_NS, 3, signals::Quality::Valid);  // its last beat, 4 s ago
  table.writeBus(*canRxBeat, 9, now, 1, signals::Quality::Valid);
  stack->reconnect();
  REQUIRE(stack->table());
  HealthModel health;
  FsmModel fsm;
  FaultModel faults;
  health.refresh();
  fsm.refresh();
  faults.refresh();

  CHECK(fsm.stateName() != "--");
  CHECK(fsm.status() == ModelStatus::Stale);
  CHECK_MESSAGE(fsm.stateNote().startsWith("vcu-fsm silent for 4"), fsm.stateNote().toStdString());
  const int fsmRow = rowNamed(health, "vcu-fsm");
  REQUIRE(fsmRow >= 0);
  CHECK(health.data(health.index(fsmRow), HealthModel::LivenessRole).toString() == "silent");
  CHECK(health.data(health.index(fsmRow), HealthModel::StatusTextRole).toString().startsWith("silent for 4"));
  const int canRxRow = rowNamed(health, "vcu-can-rx");
  REQUIRE(canRxRow >= 0);
  CHECK(health.data(health.index(canRxRow), HealthModel::LivenessRole).toString() == "beating");
  CHECK(listsFault(faults, "service_silent.fsm"));
  CHECK_FALSE(listsFault(faults, "service_silent.can-rx"));

  table.writeBus(*fsmBeat, 8, clock::monotonicNs(), 3, signals::Quality::Valid);  // vcu-fsm beats again
  health.refresh();
  fsm.refresh();
  faults.refresh();

  CHECK(fsm.stateNote().isEmpty());
  CHECK(fsm.status() == ModelStatus::Ready);
  CHECK(health.data(health.index(fsmRow), HealthModel::LivenessRole).toString() == "beating");
  CHECK_FALSE(listsFault(faults, "service_silent.fsm"));
  (void)signals::SignalTable::remove(settings.instance);
}
