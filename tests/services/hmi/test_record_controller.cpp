// The Debug tab's Record button (RecordController, issue 21) with the real `vcu` binary:
// the argument list it runs, a recording that `vcu record` refuses (its stderr shown), and
// a program that does not exist, a Stop before vcu record has begun, and a program that
// ignores SIGTERM (a shell script standing in for a recorder that hangs). A whole
// recording needs a running stack (iox-roudi for sim: buses): the HMI's integration test
// does that.
#include <doctest/doctest.h>

#include <QFile>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QTest>
#include <fstream>
#include <memory>
#include <string>

#include "common/stack_connection.hpp"
#include "debug/record_controller.hpp"
#include "hmi_test_support.hpp"

using namespace openvcu;
using namespace openvcu::hmi;

namespace {

/// `vcu record` fails within this (it loads the configuration and checks the folder first).
constexpr int FAILURE_WAIT_MS = 10000;

std::unique_ptr<StackConnection> openStack(const std::string& dataFolder) {
  test::ensureApplication("test_hmi_models");
  StackSettings settings = test::memqSettings("hmi-record");
  settings.dataFolder = dataFolder;
  settings.vcuProgram = VCU_BINARY;
  auto opened = StackConnection::open(settings);
  REQUIRE_MESSAGE(opened, opened.error().toString());
  return std::move(*opened);
}

}  // namespace

TEST_CASE("the record controller runs vcu record into the data folder with the HMI's configuration and instance") {
  QTemporaryDir data;
  auto stack = openStack(data.path().toStdString());
  RecordController sut;
  CHECK(sut.program() == VCU_BINARY);  // --vcu of vcu-hmi
  const QString folder = sut.newRecordingFolder();
  CHECK(folder.startsWith(data.path() + "/recordings/"));
  CHECK(folder.mid(folder.lastIndexOf('/') + 1).size() == QStringLiteral("yyyyMMdd-hhmmss").size());
  const QStringList argv = sut.recordArgv(folder);
  const QStringList expected{VCU_BINARY,
                             "record",
                             folder,
                             "--config",
                             QString::fromStdString(test::HHEA_CONFIG),
                             "--instance",
                             QString::fromStdString(stack->settings().instance)};
  CHECK(argv == expected);
  CHECK(sut.state() == RecordController::Idle);
  CHECK_FALSE(sut.active());
}

TEST_CASE("a recording that vcu record refuses ends in Error with vcu's own reason and offers nothing to analyse") {
  QTemporaryDir data;
  auto stack = openStack(data.path().toStdString());
  // a file where the recording folder should be: the real vcu record refuses it
  const QString blocked = data.filePath("not-a-folder");
  std::ofstream(blocked.toStdString()) << "x";
  RecordController sut;
  QSignalSpy finished(&sut, &RecordController::finished);
  CHECK(sut.start(blocked).isEmpty());
  CHECK(sut.active());
  CHECK(sut.folder() == blocked);
  CHECK_FALSE(sut.start().isEmpty());  // one recording at a time
  REQUIRE(finished.wait(FAILURE_WAIT_MS));
  CHECK(sut.state() == RecordController::Idle);
  CHECK(sut.status() == ModelStatus::Error);
  CHECK_MESSAGE(sut.lastResult().startsWith("vcu record failed (exit 1)"), sut.lastResult().toStdString());
  CHECK_MESSAGE(sut.lastResult().contains(blocked), sut.lastResult().toStdString());  // vcu's stderr
  CHECK_MESSAGE(sut.lastResult().contains("not a directory"), sut.lastResult().toStdString());
  CHECK(sut.recordedLogs().isEmpty());
}

TEST_CASE("a vcu program that does not exist is reported, and the controller can start again") {
  QTemporaryDir data;
  auto stack = openStack(data.path().toStdString());
  RecordController sut;
  sut.setProgram(data.filePath("no-such-vcu"));
  QSignalSpy finished(&sut, &RecordController::finished);
  CHECK(sut.start().isEmpty());
  REQUIRE((finished.count() > 0 || finished.wait(FAILURE_WAIT_MS)));
  CHECK(sut.state() == RecordController::Idle);
  CHECK(sut.status() == ModelStatus::Error);
  CHECK_MESSAGE(sut.lastResult().startsWith("cannot start " + data.filePath("no-such-vcu")),
                sut.lastResult().toStdString());
  sut.stop();  // nothing running: no effect
  CHECK(sut.state() == RecordController::Idle);
}

TEST_CASE("a Stop before vcu record has begun ends in Error saying so, with nothing to analyse") {
  QTemporaryDir data;
  auto stack = openStack(data.path().toStdString());
  RecordController sut;
  QSignalSpy finished(&sut, &RecordController::finished);
  CHECK(sut.start(data.filePath("early")).isEmpty());
  REQUIRE(sut.state() == RecordController::Starting);
  sut.stop();  // SIGTERM while vcu record still loads the configuration
  REQUIRE((finished.count() > 0 || finished.wait(FAILURE_WAIT_MS)));
  CHECK(sut.status() == ModelStatus::Error);
  CHECK_MESSAGE(sut.lastResult().startsWith("vcu record stopped before the recording began"),
                sut.lastResult().toStdString());
  CHECK(sut.recordedLogs().isEmpty());
}

TEST_CASE("a recorder that ignores SIGTERM is killed after the stop timeout and the page says so") {
  QTemporaryDir data;
  auto stack = openStack(data.path().toStdString());
  // says it records, then ignores SIGTERM and SIGINT as a hung recorder would
  const QString hung = data.filePath("hung-vcu");
  QFile script(hung);
  REQUIRE(script.open(QIODevice::WriteOnly));
  script.write("#!/bin/sh\ntrap '' TERM INT\necho 'recording fake (Ctrl-C to stop)' >&2\nexec sleep 30\n");
  script.close();
  REQUIRE(script.setPermissions(QFileDevice::ReadOwner | QFileDevice::WriteOwner | QFileDevice::ExeOwner));
  constexpr int SHORT_STOP_TIMEOUT_MS = 300;
  RecordController sut;
  sut.setProgram(hung);
  sut.setStopTimeout(SHORT_STOP_TIMEOUT_MS);
  QSignalSpy finished(&sut, &RecordController::finished);
  const QString folder = data.filePath("hung");
  CHECK(sut.start(folder).isEmpty());
  REQUIRE(QTest::qWaitFor([&] { return sut.state() == RecordController::Recording; }, FAILURE_WAIT_MS));
  sut.stop();
  REQUIRE((finished.count() > 0 || finished.wait(FAILURE_WAIT_MS)));
  CHECK(sut.status() == ModelStatus::Error);
  CHECK_MESSAGE(sut.lastResult().startsWith("vcu record did not end within 0.3 s of SIGTERM and was killed; " + folder +
                                            " may be incomplete"),
                sut.lastResult().toStdString());
  CHECK(sut.recordedLogs().isEmpty());
}
