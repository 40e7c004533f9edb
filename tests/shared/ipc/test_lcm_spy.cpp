// Integration tests of the Java side of the event plane: the generated types jar decodes the
// C++ side's messages, and lcm-spy starts with it (headless, under xvfb-run). Inside the
// sandbox of run_isolated.sh; skipped with a message when the build found no JDK.

#include <doctest/doctest.h>

#include "skip.hpp"
#include <unistd.h>

#include <filesystem>

#include "ipc_test_support.hpp"
#include "openvcu/ipc/event_bus.hpp"

namespace ipc = openvcu::ipc;
namespace ipctest = openvcu::ipctest;
using namespace std::chrono_literals;

namespace {

const std::string TYPES_JAR = OPENVCU_LCM_TYPES_JAR;  // empty: no JDK at configure time
const std::string PROBE_CLASSES = OPENVCU_LCM_PROBE_CLASSES;
const std::string LCM_JAR = "/usr/share/java/lcm.jar";
const std::string JCHART2D_JAR = "/usr/share/java/jchart2d.jar";
const std::string SPY_SCRIPT = std::string(OPENVCU_SOURCE_DIR) + "/shared/ipc/lcm-spy.sh";
constexpr auto HEARTBEAT_PERIOD = 100ms;

bool javaAvailable() {
  if (!ipctest::isolated()) {
    MESSAGE(ipctest::NOT_ISOLATED_MESSAGE);
    ++openvcu::testing::skippedCases();  // the caller returns: the case is skipped
    return false;
  }
  if (TYPES_JAR.empty() || !std::filesystem::exists(TYPES_JAR)) {
    MESSAGE("skipped: no JDK found at configure time, the LCM Java types jar was not built");
    ++openvcu::testing::skippedCases();
    return false;
  }
  return true;
}

ipc::Heartbeat testHeartbeat() {
  return ipc::Heartbeat{0, "vcu-can-rx", "test", 4711, 123456, {{"frames_rx", 99}, {"decode_errors", 2}}, "ok"};
}

}  // namespace

TEST_CASE("the generated Java types decode a heartbeat published by the C++ event bus") {
  if (!javaAvailable()) return;
  const std::string url(ipc::DEFAULT_EVENT_URL);
  auto events = ipc::EventBus::open(url, "test");
  REQUIRE_MESSAGE(events.ok(), (events.ok() ? "" : events.error().toString()));
  auto probe = ipctest::ChildProcess::spawn({"java", "-Djava.net.preferIPv4Stack=true", "-cp",
                                             LCM_JAR + ":" + TYPES_JAR + ":" + PROBE_CLASSES, "HeartbeatProbe", url,
                                             events->channel(ipc::EventKind::Heartbeat), "30000"});
  REQUIRE(probe);
  std::string transcript;
  REQUIRE_MESSAGE(probe->readUntil("READY", ipctest::READY_TIMEOUT, &transcript), transcript);

  // Heartbeats are periodic by nature: send them until the probe has decoded one.
  std::string decoded;
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (std::chrono::steady_clock::now() < deadline) {
    REQUIRE(events->publish(testHeartbeat()));
    if (probe->readUntil("END", HEARTBEAT_PERIOD, &decoded)) break;
  }
  CHECK(probe->wait(10s) == 0);
  INFO("probe output: " << transcript << decoded);
  CHECK(decoded.find("service=vcu-can-rx\n") != std::string::npos);
  CHECK(decoded.find("instance=test\n") != std::string::npos);
  CHECK(decoded.find("pid=4711\n") != std::string::npos);
  CHECK(decoded.find("uptime_ms=123456\n") != std::string::npos);
  CHECK(decoded.find("counter=frames_rx:99\ncounter=decode_errors:2\n") != std::string::npos);
  CHECK(decoded.find("status=ok\n") != std::string::npos);
}

TEST_CASE("lcm-spy starts headless with the project's types and stays up while heartbeats arrive") {
  if (!javaAvailable()) return;
  if (::access("/usr/bin/xvfb-run", X_OK) != 0 || !std::filesystem::exists(JCHART2D_JAR)) {
    OPENVCU_SKIP("skipped: xvfb-run or jchart2d.jar missing");
  }
  const std::string url(ipc::DEFAULT_EVENT_URL);
  auto events = ipc::EventBus::open(url, "test");
  REQUIRE_MESSAGE(events.ok(), (events.ok() ? "" : events.error().toString()));
  // Through the project's script (what `vcu spy` runs); its own process group so stop()
  // ends xvfb-run, Xvfb and the JVM together.
  auto spy = ipctest::ChildProcess::spawn(
      {"xvfb-run", "-a", "-s", "-screen 0 1024x768x24", SPY_SCRIPT, "--types", TYPES_JAR, "--lcm-url", url}, true);
  REQUIRE(spy);
  std::string transcript;
  const auto found = spy->readUntil("Found ", ipctest::READY_TIMEOUT, &transcript);
  REQUIRE_MESSAGE(found, transcript);
  // Spy scans its classpath for LCM types: it must find every type of shared/ipc's list.
  CHECK(*found == "Found " + std::to_string(OPENVCU_LCM_TYPE_COUNT) + " LCM types");

  // "A couple of seconds": publish heartbeats for 2 s and check it never exited.
  const auto until = std::chrono::steady_clock::now() + 2s;
  while (std::chrono::steady_clock::now() < until) {
    REQUIRE(events->publish(testHeartbeat()));
    if (auto line = spy->readLine(HEARTBEAT_PERIOD)) transcript += *line + "\n";
    REQUIRE_MESSAGE(spy->running(), "lcm-spy exited early: " << transcript << spy->pending());
  }
  CHECK(spy->running());
  CHECK(transcript.find("Exception") == std::string::npos);
  spy->stop();
}
