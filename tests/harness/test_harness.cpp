// The harness itself: readiness through the notify socket (attributed by pid), early exits
// and silence reported promptly, commands run to completion, processes stopped by PID.

#include <doctest/doctest.h>

#include "skip.hpp"
#include <signal.h>

#include <algorithm>
#include <string>

#include "harness.hpp"

namespace harness = openvcu::harness;
using namespace std::chrono_literals;

namespace {

const std::string PEER = OPENVCU_HARNESS_TEST_PEER;
constexpr auto SHORT_READY_TIMEOUT = 500ms;

}  // namespace

TEST_CASE("start returns once the process sent READY=1, and a SIGTERM stop records STOPPING=1 and exit code 0") {
  if (!harness::isolated()) {
    OPENVCU_SKIP(harness::NOT_ISOLATED);
  }
  harness::Harness sut;
  auto started = sut.start({.name = "peer", .argv = {PEER, "ready"}, .notifyReadiness = true});
  REQUIRE_STATUS(started);
  harness::Process& peer = **started;
  CHECK(peer.running());

  const auto status = sut.stop(peer);

  REQUIRE(status);
  CHECK(status->exited);
  CHECK(status->code == 0);
  CHECK(sut.waitForNotify(peer, "STOPPING=1", 0ms));
  const auto notifications = sut.notifications(peer);
  CHECK(std::find(notifications.begin(), notifications.end(), std::string("STATUS=ready")) != notifications.end());
}

TEST_CASE("start fails at once with the exit status and the log when the process exits before READY=1") {
  if (!harness::isolated()) {
    OPENVCU_SKIP(harness::NOT_ISOLATED);
  }
  harness::Harness sut;
  const auto before = std::chrono::steady_clock::now();

  auto started = sut.start({.name = "quitter", .argv = {PEER, "exit", "3"}, .notifyReadiness = true});

  REQUIRE_FALSE(started.ok());
  CHECK(std::chrono::steady_clock::now() - before < harness::READY_TIMEOUT / 2);  // did not wait for the timeout
  CHECK(started.error().message.find("exit code 3 before READY=1") != std::string::npos);
  CHECK(started.error().message.find("giving up early") != std::string::npos);
}

TEST_CASE("start fails after the timeout when the process never sends READY=1") {
  if (!harness::isolated()) {
    OPENVCU_SKIP(harness::NOT_ISOLATED);
  }
  harness::Harness sut;

  auto started = sut.start({.name = "silent", .argv = {PEER, "silent"}, .notifyReadiness = true}, SHORT_READY_TIMEOUT);

  REQUIRE_FALSE(started.ok());
  CHECK(started.error().message.find("sent no READY=1") != std::string::npos);
}

TEST_CASE("READY=1 sent by another process (a child of the started one) does not count as its readiness") {
  if (!harness::isolated()) {
    OPENVCU_SKIP(harness::NOT_ISOLATED);
  }
  harness::Harness sut;

  auto started =
      sut.start({.name = "impostor", .argv = {PEER, "ready-from-child"}, .notifyReadiness = true}, SHORT_READY_TIMEOUT);

  REQUIRE_FALSE(started.ok());
  CHECK(started.error().message.find("sent no READY=1") != std::string::npos);
}

TEST_CASE("run captures stdout, stderr and the exit code of a command") {
  if (!harness::isolated()) {
    OPENVCU_SKIP(harness::NOT_ISOLATED);
  }
  harness::Harness sut;

  const harness::CommandResult result = sut.run({PEER, "echo", "hello"});

  CHECK_MESSAGE(result.exitCode() == 0, result.describe());
  CHECK(result.out == "hello\n");
  CHECK(result.err == "err\n");
}

TEST_CASE("run kills a command that outlives its timeout and reports it as timed out") {
  if (!harness::isolated()) {
    OPENVCU_SKIP(harness::NOT_ISOLATED);
  }
  harness::Harness sut;

  const harness::CommandResult result = sut.run({PEER, "silent"}, 200ms);

  CHECK_FALSE(result.status.has_value());
  CHECK(result.exitCode() == -1);
  CHECK(result.describe().find("timed out") != std::string::npos);
}

TEST_CASE("a captured process's output is readable line by line while it runs") {
  if (!harness::isolated()) {
    OPENVCU_SKIP(harness::NOT_ISOLATED);
  }
  harness::Harness sut;
  auto started = sut.start({.name = "talker", .argv = {PEER, "ready"}, .notifyReadiness = true, .captureOutput = true});
  REQUIRE_STATUS(started);

  const auto line = (*started)->waitForLine("READY", harness::READY_TIMEOUT);

  REQUIRE(line);
  CHECK(*line == "peer: sending READY=1");
}
