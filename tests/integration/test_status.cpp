// `vcu status` and `vcu spy` against the sandboxed stack.

#include "integration_support.hpp"

TEST_CASE("vcu status lists the fixture service with its pid, status and counters") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  harness::Process& fixture = startStack(sut);
  const auto set = vcu(sut, {"signal", "set", "internal.operator.Start", "1"});
  REQUIRE_MESSAGE(set.exitCode() == 0, set.describe());

  const auto status = vcu(sut, {"status"});

  CHECK_MESSAGE(status.exitCode() == 0, status.describe());
  CHECK_MESSAGE(contains(status.out, "SERVICE              PID"), status.out);
  CHECK_MESSAGE(contains(status.out, "vcu-fixture-service  " + std::to_string(fixture.pid()) + " "), status.out);
  CHECK_MESSAGE(contains(status.out, " ready "), status.out);
  CHECK_MESSAGE(contains(status.out, "commands_accepted=1"), status.out);
  CHECK_MESSAGE(contains(status.out, "frames_rx=0"), status.out);
}

TEST_CASE("vcu status says so and exits 1 when no service beats") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto status = vcu(sut, {"status", "--wait", "0.3"});

  CHECK_MESSAGE(status.exitCode() == 1, status.describe());
  CHECK_MESSAGE(contains(status.err, "no heartbeat on OPENVCU_ITEST_HEARTBEAT within 0.3 s"), status.err);
}

TEST_CASE("vcu spy --dry-run shows lcm-spy.sh with the configuration's URL as an argument list") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto spy = vcu(sut, {"spy", "--dry-run"});
  const auto explicitUrl = sut.run({VCU, "spy", "--dry-run", "--lcm-url", "memq://", "--types", "/x/types.jar"});

  CHECK_MESSAGE(spy.exitCode() == 0, spy.describe());
  CHECK_MESSAGE(contains(spy.out, "shared/ipc/lcm-spy.sh --lcm-url 'udpm://239.255.76.67:7667?ttl=0'"), spy.out);
  CHECK_MESSAGE(explicitUrl.out.ends_with("lcm-spy.sh --lcm-url memq:// --types /x/types.jar\n"), explicitUrl.out);
}
