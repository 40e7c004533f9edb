#pragma once
// `vcu inject ...`: faults injected from outside the VCU's code paths, each acknowledged
// with its CLOCK_MONOTONIC and CLOCK_REALTIME time stamps (a campaign measures reaction
// times from them).
//   - frame faults, applied by vcu-ecu-sim to what the simulated vehicle sends
//     (CommandKind::SimFault with the key "KIND.TARGET[=PARAM]", services/ecu-sim/README.md):
//       vcu inject silence HVESSD2_PGN61585        vcu inject delay VIC --ms 300
//       vcu inject corrupt PDU_Tx_1 [--xor FF00]   vcu inject replay VIC --age 2000
//       vcu inject spoof PDU --from 0x30           vcu inject claim 0x21
//       vcu inject babble vehicle --load 30        ... --off clears it
//   - GPIO: an input line of the simulated chip stuck at 0 or 1 (vcu inject gpio LINE --level 1)
//   - process faults: SIGSTOP, SIGCONT or SIGKILL of a running service, found by its
//     executable's name among this user's processes:
//       vcu inject process stop fsm                vcu inject process kill roudi --pid 4242

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "cli.hpp"
#include "command_request.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

/// A frame fault for vcu-ecu-sim: `kind` ("silent", "delay", "corrupt", "replay", "spoof",
/// "claim", "babble"), its target (a DBC message, a node, an address or a bus) and its
/// parameter (empty when it has none, or when clearing).
struct FrameInjectOptions {
  StackOptions stack;
  std::string kind;
  std::string target;
  std::string parameter;
  bool off{};
  bool json{};
  double timeoutSeconds{DEFAULT_ACK_TIMEOUT_SECONDS};
};

/// The SimFault key of a frame fault: "delay.VIC=300"; "delay.VIC" when clearing.
[[nodiscard]] std::string frameFaultKey(const FrameInjectOptions& options);

ExitCode runFrameInject(const FrameInjectOptions& options, Streams streams);

/// An input line of the simulated GPIO chip held at `level` (an override of
/// internal.gpio.sim.<line>, answered by vcu-gpio), or released (`off`).
struct GpioInjectOptions {
  StackOptions stack;
  std::string line;
  int level{-1};
  bool off{};
  bool json{};
  double timeoutSeconds{DEFAULT_ACK_TIMEOUT_SECONDS};
};

ExitCode runGpioInject(const GpioInjectOptions& options, Streams streams);

struct ProcessInjectOptions {
  std::string action;   ///< stop, cont, kill
  std::string service;  ///< "fsm" (vcu-fsm), "roudi" (iox-roudi), "supervisor" (supervisord)
  std::optional<std::int32_t> pid;
  bool json{};
};

/// The pids of this user's processes running `service` (its executable vcu-<service>,
/// iox-roudi for "roudi", supervisord for "supervisor"), this process excluded, ascending.
[[nodiscard]] std::vector<std::int32_t> findServiceProcesses(const std::string& service);

ExitCode runProcessInject(const ProcessInjectOptions& options, Streams streams);

/// Adds `inject` and its subcommands to `app`.
void registerInjectCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
