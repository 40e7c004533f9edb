// `vcu sim fault`. The description and footer are its manual.
#include "sim_commands.hpp"

#include <CLI/CLI.hpp>
#include <memory>

#include "diagnostics.hpp"

namespace openvcu::cli {
namespace {

constexpr const char* FAULT_DESCRIPTION = "Inject a fault into the simulated vehicle, or clear it";
constexpr const char* FAULT_FOOTER =
    "Sends a SimFault command to vcu-ecu-sim and waits for its acknowledgement; a name\n"
    "the simulated vehicle does not know is refused with the list of those it knows.\n"
    "The faults depend on simulation.json's model (services/ecu-sim/README.md):\n"
    "- \"generic\": the names under \"faults\" in simulation.json, and silent.<NODE>\n"
    "  (the node stops sending) for every simulated node.\n"
    "- \"hhea\" (config/hhea): battery (the VIC reports 14 and opens), isolation,\n"
    "  contactor_stuck, pdu, hvlp (inverter 0x71 status 1), hvlp_shutdown (13), editron\n"
    "  (st_mot_fault 2), obc, soc_low / soc_high (SOC jumps to the configured low / high\n"
    "  value; restored when cleared), shm_expectation (the simulated VIC expects another\n"
    "  CRC: it refuses every J1939-76 pair), silent.<NODE> (silent.VIC, silent.PDU, ...).\n"
    "Either model: silent.<NODE> or silent.<MESSAGE>, and the frame faults of `vcu inject`\n"
    "(delay, corrupt, replay, spoof, claim, babble), which also prints time stamps.\n"
    "The stack: --config FILE or $OPENVCU_CONFIG, --instance NAME.\n"
    "\n"
    "Examples:\n"
    "  vcu sim fault battery on --config config/hhea/vehicle.json\n"
    "  vcu sim fault silent.VIC on\n"
    "  vcu sim fault battery off\n"
    "Exit: 0 acknowledged, 1 refused, no answer or configuration error, 2 usage error.\n";

}  // namespace

ExitCode runSimFault(const SimFaultOptions& options, Streams streams) {
  if (options.state != "on" && options.state != "off") {
    reportError(streams.err, "expected on or off, not '" + options.state + "'");
    return ExitCode::Usage;
  }
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::SimFault;
  request.key = options.name;
  request.value = options.state == "on" ? 1 : 0;
  return sendCommandRequest(maybeStack->config, std::move(request), options.timeoutSeconds, streams);
}

void registerSimCommands(CLI::App& app, CommandContext& context) {
  CLI::App* group = app.add_subcommand("sim", "the simulated vehicle (vcu-ecu-sim): inject and clear faults");
  auto options = std::make_shared<SimFaultOptions>();
  CLI::App* fault = group->add_subcommand("fault", FAULT_DESCRIPTION);
  fault->footer(FAULT_FOOTER);
  fault->add_option("NAME", options->name, "the fault: a name from simulation.json (generic) or battery, pdu, ... (hhea); silent.<NODE>")->required();
  fault->add_option("STATE", options->state, "on (default) or off");
  fault->add_option("--timeout", options->timeoutSeconds, "seconds to wait for the acknowledgement")
      ->check(CLI::PositiveNumber);
  addStackOptions(*fault, options->stack);
  fault->callback([options, &context] { context.exitCode = runSimFault(*options, context.streams); });
  group->require_subcommand(1);
}

}  // namespace openvcu::cli
