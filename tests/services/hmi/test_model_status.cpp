// The `status` and `errorString` properties that every list model of the HMI shows QML
// through its base (StatusListModel): present, typed, and notified by the signal with
// which each model says they changed.
#include <doctest/doctest.h>

#include <QMetaProperty>
#include <QSignalSpy>
#include <memory>

#include "can/frame_trace_model.hpp"
#include "can/signal_tree_model.hpp"
#include "common/status_list_model.hpp"
#include "dashboard/dashboard_models.hpp"
#include "debug/fault_model.hpp"
#include "debug/j1939_model.hpp"
#include "debug/log_model.hpp"
#include "header/fsm_model.hpp"
#include "header/health_model.hpp"
#include "hmi_test_support.hpp"
#include "setup/schedule_model.hpp"
#include "trace/trace_model.hpp"
#include "vehicle/operator_model.hpp"

using namespace openvcu;
using namespace openvcu::hmi;

namespace {

/// The notify signal of `model`'s property `name`, checked to be readable and notified.
QMetaMethod notifyOf(const QObject& model, const char* name) {
  const QMetaObject* meta = model.metaObject();
  const int index = meta->indexOfProperty(name);
  REQUIRE_MESSAGE(index >= 0, meta->className(), " has no property ", name);
  const QMetaProperty property = meta->property(index);
  CHECK(property.isReadable());
  CHECK_FALSE(property.isWritable());
  REQUIRE(property.hasNotifySignal());
  return property.notifySignal();
}

/// Emitting `emitChanged` notifies both `status` and `errorString` of `model` once each,
/// and both read the model's own getters.
template <class Model, class Emit>
void checkStatusProperties(Model& model, Emit emitChanged) {
  CAPTURE(model.metaObject()->className());
  const QMetaMethod statusNotify = notifyOf(model, "status");
  const QMetaMethod errorNotify = notifyOf(model, "errorString");
  CHECK(model.property("status").template value<ModelStatus::Value>() == model.status());
  CHECK(model.property("errorString").toString() == model.errorString());
  QSignalSpy statusSpy(&model, statusNotify);
  QSignalSpy errorSpy(&model, errorNotify);
  emitChanged(model);
  CHECK(statusSpy.count() == 1);
  CHECK(errorSpy.count() == 1);
}

}  // namespace

TEST_CASE("every list model shows status and errorString, notified when the model says they changed") {
  test::ensureApplication("test_hmi_models");
  StackSettings settings = test::memqSettings("hmi-status");
  auto opened = StackConnection::open(settings);
  REQUIRE_MESSAGE(opened, opened.error().toString());
  const std::unique_ptr<StackConnection> stack = std::move(*opened);

  const auto statusChanged = [](StatusListModel& model) { Q_EMIT model.statusChanged(); };
  FrameTraceModel frames;
  checkStatusProperties(frames, statusChanged);
  SignalTreeModel tree;
  checkStatusProperties(tree, statusChanged);
  SignalListModel list;
  checkStatusProperties(list, statusChanged);
  LogModel log;
  checkStatusProperties(log, statusChanged);
  HealthModel health;
  checkStatusProperties(health, statusChanged);
  ScheduleModel schedule;
  checkStatusProperties(schedule, statusChanged);
  J1939Model j1939;
  checkStatusProperties(j1939, statusChanged);
  OperatorModel operators;
  checkStatusProperties(operators, statusChanged);
  // these three notify status and errorString with the signal of their other properties
  FsmModel fsm;
  checkStatusProperties(fsm, [](FsmModel& model) { Q_EMIT model.stateChanged(); });
  FaultModel faults;
  checkStatusProperties(faults, [](FaultModel& model) { Q_EMIT model.countChanged(); });
  TraceModel trace;
  checkStatusProperties(trace, [](TraceModel& model) { Q_EMIT model.loaded(); });
  CHECK(trace.status() == ModelStatus::NotConnected);  // before any log is opened
}
