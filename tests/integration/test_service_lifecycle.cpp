// A service's life through openvcu::service, seen from outside: readiness, a SIGKILL and a
// restart that re-attaches to the same table, an orderly SIGTERM stop, start-up errors.

#include <signal.h>

#include <algorithm>
#include <charconv>
#include <string>

#include "integration_support.hpp"

namespace {

/// The bus value of the fixture's heartbeat slot as `vcu signal get` prints it, or -1.
double heartbeatCount(harness::Harness& sut) {
  const auto get = vcu(sut, {"signal", "get", "internal.service.fixture.heartbeat"});
  const std::string marker = "bus        ";
  const std::size_t at = get.out.find(marker);
  if (at == std::string::npos) return -1.0;
  double value = -1.0;
  const char* begin = get.out.data() + at + marker.size();
  std::from_chars(begin, get.out.data() + get.out.size(), value);
  return value;
}

}  // namespace

TEST_CASE("the fixture service announces readiness with READY=1, a 'ready' log line and heartbeat status") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  harness::Process& fixture = startStack(sut);

  const auto notifications = sut.notifications(fixture);
  CHECK(std::find(notifications.begin(), notifications.end(), std::string("STATUS=ready")) != notifications.end());
  CHECK(std::find(notifications.begin(), notifications.end(), "MAINPID=" + std::to_string(fixture.pid())) !=
        notifications.end());
  CHECK_MESSAGE(contains(fixture.output(), "info vcu-fixture-service[" + std::to_string(fixture.pid()) + "]: ready"),
                fixture.output());
  CHECK(heartbeatCount(sut) >= 1.0);
}

TEST_CASE("a SIGKILLed fixture service restarts, re-attaches to the same table and finds the value set before") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  harness::Process& first = startStack(sut);
  const auto set = vcu(sut, {"signal", "set", "internal.test.level", "42"});
  REQUIRE_MESSAGE(set.exitCode() == 0, set.describe());
  const double beatsBefore = heartbeatCount(sut);

  REQUIRE(first.signal(SIGKILL));
  const auto killed = first.waitForExit(harness::STOP_TIMEOUT);
  auto restarted = sut.start(fixtureSpec());
  REQUIRE_STATUS(restarted);
  const auto get = vcu(sut, {"signal", "get", "internal.test.level"});

  REQUIRE(killed);
  CHECK(killed->signal == SIGKILL);
  CHECK_MESSAGE(contains((*restarted)->output(), "attached (created by pid " + std::to_string(first.pid()) + ")"),
                (*restarted)->output());
  CHECK_MESSAGE(contains(get.out, "command    42 %"), get.out);
  CHECK_MESSAGE(heartbeatCount(sut) > beatsBefore, "the heartbeat count continues after the restart");
  const auto again = vcu(sut, {"signal", "set", "internal.test.level", "43"});
  CHECK_MESSAGE(again.exitCode() == 0, again.describe());
}

TEST_CASE("a service outlives a dead iox-roudi and ends with exit code 75 once a new RouDi is up, saying why") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  harness::Process& fixture = startStack(sut);
  REQUIRE(sut.roudi()->signal(SIGKILL));
  REQUIRE(sut.roudi()->waitForExit(5s));
  // RouDi down, not yet back: nothing to restart against, the service keeps serving
  CHECK_FALSE(fixture.waitForExit(2500ms));
  CHECK(heartbeatCount(sut) >= 2.0);

  REQUIRE_STATUS(sut.startRoudi());
  // the next heartbeat tick (1 s) sees the new socket
  const auto ended = fixture.waitForExit(5s);
  REQUIRE_MESSAGE(ended, fixture.output());
  CHECK_MESSAGE((ended->exited && ended->code == 75), ended->toString());
  CHECK_MESSAGE(contains(fixture.output(), "iox-roudi was restarted"), fixture.output());

  // and a new process registers with the new RouDi as the supervisor would start it
  auto again = sut.start(fixtureSpec());
  CHECK_STATUS(again);
}

TEST_CASE("SIGTERM stops the fixture service in order: STOPPING=1, a log line and exit code 0") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  harness::Process& fixture = startStack(sut);

  const auto status = sut.stop(fixture);

  REQUIRE(status);
  CHECK_MESSAGE(status->exited, status->toString());
  CHECK(status->code == 0);
  CHECK(sut.waitForNotify(fixture, "STOPPING=1", harness::STOP_TIMEOUT));
  CHECK_MESSAGE(contains(fixture.output(), "stopping (SIGTERM)"), fixture.output());
}

TEST_CASE("SIGINT stops the fixture service like SIGTERM") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  harness::Process& fixture = startStack(sut);

  REQUIRE(fixture.signal(SIGINT));
  const auto status = fixture.waitForExit(harness::STOP_TIMEOUT);

  REQUIRE(status);
  CHECK(status->exited);
  CHECK(status->code == 0);
  CHECK_MESSAGE(contains(fixture.output(), "stopping (SIGINT)"), fixture.output());
}

TEST_CASE("the fixture service without iox-roudi fails with one clear line and exit code 1") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto run = sut.run({FIXTURE, "--config", CONFIG});

  CHECK_MESSAGE(run.exitCode() == 1, run.describe());
  CHECK_MESSAGE(contains(run.err, "vcu-fixture-service: error: iox-roudi is not running"), run.err);
}

TEST_CASE("--no-frames runs the fixture service without iox-roudi") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  auto fixture =
      sut.start({.name = "fixture", .argv = {FIXTURE, "--config", CONFIG, "--no-frames"}, .notifyReadiness = true});
  REQUIRE_STATUS(fixture);
  const auto set = vcu(sut, {"signal", "set", "internal.operator.Start", "1"});

  CHECK_MESSAGE(set.exitCode() == 0, set.describe());
}

TEST_CASE("a broken configuration stops the fixture service at start with the file and reason on one line") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  const std::string missing = sut.logDirectory() + "/missing.json";

  const auto run = sut.run({FIXTURE, "--config", missing, "--no-frames"});

  CHECK_MESSAGE(run.exitCode() == 1, run.describe());
  CHECK_MESSAGE(contains(run.err, "vcu-fixture-service: error: " + missing), run.err);
  CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
}

TEST_CASE("the fixture service answers --help and --version with exit code 0 and a usage error with 2") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto help = sut.run({FIXTURE, "--help"});
  const auto version = sut.run({FIXTURE, "--version"});
  const auto wrong = sut.run({FIXTURE, "--config", CONFIG, "--bogus"});

  CHECK(help.exitCode() == 0);
  CHECK(contains(help.out, "--log-level"));
  CHECK(contains(help.out, "--no-frames"));
  CHECK(version.exitCode() == 0);
  CHECK(contains(version.out, "vcu-fixture-service (openvcu)"));
  CHECK(wrong.exitCode() == 2);
  CHECK(contains(wrong.err, "--bogus"));
}
