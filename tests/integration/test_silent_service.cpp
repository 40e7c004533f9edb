// A service that stops beating (SIGSTOP: a hang) as the displays of a terminal show it:
// the real vcu-fsm on the HHEA configuration in the sandbox, `vcu status` and `vcu top`.
//   - `vcu status` keeps listing vcu-fsm, as "silent for N s", and exits 1;
//   - `vcu top` shows the FSM state as the last one of a silent writer, not as current,
//     vcu-fsm's row as silent and the fault service_silent.fsm.
// The bound: a display calls a service silent HEARTBEAT_STALE_NS (2.5 s) after its last
// beat, which lies before the SIGSTOP, so within 2.5 s of it; the checks allow 3.5 s for the
// `vcu` start-ups on a busy machine.

#include <doctest/doctest.h>

#include <chrono>
#include <csignal>
#include <string>

#include "integration_support.hpp"

namespace {

const std::string FSM = FSM_BINARY;
constexpr auto SILENT_BOUND = std::chrono::milliseconds(3500);

}  // namespace

TEST_CASE("a SIGSTOPped vcu-fsm is silent in vcu status and vcu top, its state not shown as current") {
  SKIP_UNLESS_ISOLATED();
  ConfiguredStack stack(copyHheaConfig(fs::temp_directory_path() / "hhea"));
  harness::Process& fsm = stack.startService("fsm", FSM);
  stack.openTable();
  REQUIRE(waitForBus(*stack.table, stack.index("internal.fsm.state"), hheaStateIndex("Standby"), 5s));
  const auto beating = stack.vcu({"status", "--wait", "1.2"});
  REQUIRE_MESSAGE(beating.exitCode() == 0, beating.describe());
  REQUIRE_MESSAGE(contains(beating.out, "vcu-fsm "), beating.out);

  REQUIRE(fsm.signal(SIGSTOP));
  const auto stoppedAt = std::chrono::steady_clock::now();
  harness::CommandResult status;
  do {
    status = stack.vcu({"status", "--wait", "0.3"});
  } while (!contains(status.out, "silent for") && std::chrono::steady_clock::now() - stoppedAt < 2 * SILENT_BOUND);
  const auto statusAfter = std::chrono::steady_clock::now() - stoppedAt;
  const auto top = stack.vcu({"top", "--once"});
  REQUIRE(fsm.signal(SIGKILL));
  (void)fsm.waitForExit(5s);

  MESSAGE("vcu status said silent " << std::chrono::duration_cast<std::chrono::milliseconds>(statusAfter).count()
                                    << " ms after the SIGSTOP");
  CHECK_MESSAGE(contains(status.out, "vcu-fsm "), status.describe());
  CHECK_MESSAGE(contains(status.out, "silent for"), status.describe());
  CHECK_MESSAGE(status.exitCode() == 1, status.describe());
  CHECK_MESSAGE(contains(status.err, "vcu-fsm"), status.describe());
  CHECK(statusAfter < SILENT_BOUND);
  CHECK_MESSAGE(contains(top.out, "Standby — vcu-fsm silent"), top.out);
  CHECK_MESSAGE(!contains(top.out, "Standby (for"), top.out);
  CHECK_MESSAGE(contains(top.out, "service_silent.fsm"), top.out);
  CHECK_MESSAGE(!contains(top.out, "none active"), top.out);
}
