// `vcu signal list|get|set|watch` against a real running service (vcu-fixture-service) with
// real iox-roudi, LCM udpm and the shared-memory signal table, each case in its own sandbox.

#include <chrono>
#include <optional>

#include "integration_support.hpp"
#include "openvcu/ipc/command_socket.hpp"

namespace ipc = openvcu::ipc;

TEST_CASE("vcu signal set on an internal key is accepted by the fixture service and vcu signal get reads it back") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);

  const auto set = vcu(sut, {"signal", "set", "internal.operator.Start", "Start"});
  const auto get = vcu(sut, {"signal", "get", "internal.operator.Start"});

  CHECK_MESSAGE(set.exitCode() == 0, set.describe());
  CHECK(set.out == "accepted\n");
  CHECK_MESSAGE(get.exitCode() == 0, get.describe());
  CHECK_MESSAGE(contains(get.out, "command    1 \"Start\"  at "), get.out);
  CHECK_MESSAGE(contains(get.out, FIXTURE_WRITER_TEXT), get.out);
  CHECK_MESSAGE(contains(get.out, "effective  1 \"Start\"  (command)"), get.out);
  CHECK_MESSAGE(contains(get.out, "bus        never received"), get.out);
}

TEST_CASE("vcu signal set refuses an out-of-range value with the service's reason and nothing changes") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);

  const auto set = vcu(sut, {"signal", "set", "internal.test.level", "150"});
  const auto get = vcu(sut, {"signal", "get", "internal.test.level"});

  CHECK_MESSAGE(set.exitCode() == 1, set.describe());
  CHECK(set.out == "refused: value 150 is outside the range [0, 100] % of 'internal.test.level'\n");
  CHECK_MESSAGE(contains(get.out, "command    never commanded"), get.out);
}

TEST_CASE("a signal whose min equals its max takes any finite value") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);

  const auto set = vcu(sut, {"signal", "set", "internal.test.free", "-12345.5"});

  CHECK_MESSAGE(set.exitCode() == 0, set.describe());
}

TEST_CASE("vcu signal set answers an unknown key itself with a did-you-mean and sends nothing") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  // No service runs: an answer can only come from vcu itself.

  const auto set = vcu(sut, {"signal", "set", "internal.operator.Strat", "1"});

  CHECK_MESSAGE(set.exitCode() == 1, set.describe());
  CHECK_MESSAGE(contains(set.err, "unknown signal 'internal.operator.Strat' (did you mean 'internal.operator.Start'?)"),
                set.err);
}

TEST_CASE("the owning service refuses a request for an unknown key of its namespace with a did-you-mean") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);
  auto client = ipc::CommandClient::connect(INSTANCE);
  REQUIRE_STATUS(client);

  auto answer = client->send(ipc::CommandRequest{0, 0, "test_integration", ipc::CommandKind::SetSignal,
                                                 "internal.operator.Strat", 1.0, "typo on purpose"},
                             harness::READY_TIMEOUT);

  REQUIRE_STATUS(answer);
  CHECK_FALSE(answer->accepted);
  CHECK(answer->issuer == "test_integration");
  CHECK(answer->responder == "vcu-fixture-service");
  CHECK(answer->reason == "unknown signal 'internal.operator.Strat' (did you mean 'internal.operator.Start'?)");
}

TEST_CASE("an override is accepted, shown as active and effective, and cleared again") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);

  const auto command = vcu(sut, {"signal", "set", "internal.test.level", "20"});
  const auto override = vcu(sut, {"signal", "set", "--override", "internal.test.level", "50", "--note", "bench"});
  const auto whileOverridden = vcu(sut, {"signal", "get", "internal.test.level"});
  const auto clear = vcu(sut, {"signal", "set", "--clear-override", "internal.test.level"});
  const auto afterClear = vcu(sut, {"signal", "get", "internal.test.level"});

  CHECK_MESSAGE(command.exitCode() == 0, command.describe());
  CHECK_MESSAGE(override.exitCode() == 0, override.describe());
  CHECK_MESSAGE(contains(whileOverridden.out, "override   50 %  ACTIVE"), whileOverridden.out);
  CHECK_MESSAGE(contains(whileOverridden.out, "effective  50 %  (override)"), whileOverridden.out);
  CHECK_MESSAGE(clear.exitCode() == 0, clear.describe());
  CHECK_MESSAGE(contains(afterClear.out, "override   cleared"), afterClear.out);
  CHECK_MESSAGE(contains(afterClear.out, "effective  20 %  (command)"), afterClear.out);
}

TEST_CASE("the fixture's own veto refuses commands for heartbeat slots") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);

  const auto set = vcu(sut, {"signal", "set", "internal.service.fsm.heartbeat", "5"});

  CHECK_MESSAGE(set.exitCode() == 1, set.describe());
  CHECK(set.out == "refused: heartbeat counters are written by their service only\n");
}

TEST_CASE("vcu signal set says at once that no running service answers for a key nobody owns") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);  // the fixture owns internal.* only

  const auto started = std::chrono::steady_clock::now();
  const auto set = vcu(sut, {"signal", "set", "VCU.Command.Enable", "1", "--timeout", "5"});

  CHECK_MESSAGE(set.exitCode() == 1, set.describe());
  CHECK_MESSAGE(contains(set.err, "no running service answers for 'VCU.Command.Enable' (vcu-fixture-service: not theirs)"),
                set.err);
  CHECK(std::chrono::steady_clock::now() - started < 4s);  // every service said "not mine": no wait for the timeout
}

TEST_CASE("vcu signal set of a received signal says it is received from the bus and how to send it from the bench") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);

  const auto set = vcu(sut, {"signal", "set", "BMS.Status.SOC", "50"});

  CHECK_MESSAGE(set.exitCode() == 1, set.describe());
  CHECK_MESSAGE(contains(set.err, "'BMS.Status.SOC' is received from the bus (sent by BMS in Status): only signals of "
                                  "messages this VCU sends can be commanded (`vcu schedule add Status MS`"),
                set.err);
}

TEST_CASE("vcu signal set takes a value text or a number, and refuses other text before sending") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto set = vcu(sut, {"signal", "set", "internal.operator.Start", "Go"});

  CHECK_MESSAGE(set.exitCode() == 1, set.describe());
  CHECK_MESSAGE(contains(set.err, "'Go' is not a number nor a value of 'internal.operator.Start' (0 Stop, 1 Start)"),
                set.err);
}

TEST_CASE("vcu signal watch prints a change made by another process") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);
  auto watch = sut.start(
      {.name = "vcu-watch",
       .argv = {VCU, "signal", "watch", "internal.operator.*", "--count", "1", "--for", "20", "--config", CONFIG},
       .captureOutput = true});
  REQUIRE_STATUS(watch);
  REQUIRE((*watch)->waitForLine("watching 1 signal matching 'internal.operator.*'", harness::READY_TIMEOUT));

  const auto set = vcu(sut, {"signal", "set", "internal.operator.Start", "1"});
  const auto change = (*watch)->waitForLine("internal.operator.Start", harness::READY_TIMEOUT);
  const auto exit = (*watch)->waitForExit(harness::READY_TIMEOUT);

  CHECK_MESSAGE(set.exitCode() == 0, set.describe());
  REQUIRE_MESSAGE(change, (*watch)->output());
  CHECK_MESSAGE(contains(*change, "internal.operator.Start  command  1 \"Start\"  writer 240"), *change);
  REQUIRE(exit);
  CHECK(exit->exited);
  CHECK(exit->code == 0);
}

TEST_CASE("vcu signal watch stops with exit code 0 on SIGTERM") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;
  startStack(sut);
  auto watch = sut.start(
      {.name = "vcu-watch", .argv = {VCU, "signal", "watch", "internal.*", "--config", CONFIG}, .captureOutput = true});
  REQUIRE_STATUS(watch);
  REQUIRE((*watch)->waitForLine("watching", harness::READY_TIMEOUT));

  const auto exit = sut.stop(**watch);

  REQUIRE(exit);
  CHECK(exit->exited);
  CHECK(exit->code == 0);
}

TEST_CASE("vcu signal get without a running stack says that no table exists yet") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto get = vcu(sut, {"signal", "get", "internal.operator.Start"});

  CHECK_MESSAGE(get.exitCode() == 1, get.describe());
  CHECK_MESSAGE(contains(get.err, "no signal table 'openvcu-itest'"), get.err);
}

TEST_CASE("vcu signal list prints key, unit, range, kind, bus, direction and owner of the matching signals") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto list = vcu(sut, {"signal", "list", "*.test.*"});
  const auto bus = vcu(sut, {"signal", "list", "*.*.Enable"});
  const auto soc = vcu(sut, {"signal", "list", "BMS.Status.SOC"});
  const auto typo = vcu(sut, {"signal", "list", "BMS.Status.Soc"});

  CHECK_MESSAGE(list.exitCode() == 0, list.describe());
  CHECK(list.out ==
        "KEY                  UNIT  RANGE   KIND      BUS  DIRECTION  OWNER\n"
        "internal.test.level  %     0..100  Internal  -    internal   fsm\n"
        "internal.test.free   -     -       Internal  -    internal   fsm\n");
  CHECK_MESSAGE(contains(bus.out, "VCU.Command.Enable  -     0..3   Bus   vehicle  transmitted  can-tx\n"), bus.out);
  CHECK_MESSAGE(contains(soc.out, "vehicle  received   can-rx\n"), soc.out);
  CHECK(typo.exitCode() == 1);
  CHECK_MESSAGE(contains(typo.err, "did you mean 'BMS.Status.SOC'?"), typo.err);
}

TEST_CASE("vcu signal commands need a configuration: --config or OPENVCU_CONFIG") {
  SKIP_UNLESS_ISOLATED();
  harness::Harness sut;

  const auto without = sut.run({VCU, "signal", "list"});
  const auto fromEnvironment =
      sut.run({VCU, "signal", "list", "internal.test.level"}, harness::COMMAND_TIMEOUT, {"OPENVCU_CONFIG=" + CONFIG});

  CHECK_MESSAGE(without.exitCode() == 2, without.describe());
  CHECK_MESSAGE(contains(without.err, "no configuration: give --config FILE or set OPENVCU_CONFIG"), without.err);
  CHECK_MESSAGE(fromEnvironment.exitCode() == 0, fromEnvironment.describe());
}
