// `vcu safety campaign`: the command line. The description and footer are its manual.
#include "safety_commands.hpp"

#include <CLI/CLI.hpp>
#include <memory>

namespace openvcu::cli {
namespace {

constexpr const char* SAFETY_DESCRIPTION = "The vehicle's safety case (safety.json) run against a running stack";
constexpr const char* CAMPAIGN_DESCRIPTION =
    "Inject each hazard's faults into a running stack and measure the reaction against its FTTI";
constexpr const char* CAMPAIGN_FOOTER =
    "For each hazard of the safety case (--hazard: only these) and each repetition:\n"
    "  1. the vehicle is brought to a state of the hazard's \"during\" list: operator signals\n"
    "     (internal.operator.*) are set as the transitions of fsm.json ask, step by step (a\n"
    "     step that does not fire is avoided and another path taken), then --settle s pass;\n"
    "  2. its faults are injected as `vcu inject` does (frame faults by vcu-ecu-sim, SIGSTOP or\n"
    "     SIGKILL of a process, a GPIO input stuck on the simulated chip); the time stamp taken\n"
    "     just before the first one is time 0;\n"
    "  3. every item of the safe state and every detection is watched until all were seen or\n"
    "     twice the FTTI passed: the FSM state (internal.fsm.state), each bus command in the\n"
    "     frames of the simulated bus (decoded with the DBC), each GPIO level\n"
    "     (internal.gpio.LINE), each detection's fault event (LCM: service_silent.SERVICE,\n"
    "     rx_timeout.BUS.MESSAGE, j1939_76.MESSAGE, j1939_address_lost.BUS, a dtc's fault), each\n"
    "     service restarted (beating again from a new process);\n"
    "  4. the faults are cleared (SIGCONT, --off, the line restored) and the vehicle is brought\n"
    "     back to the state it was in (fault reset as fsm.json allows).\n"
    "A hazard passes only if every item of every repetition was seen within its FTTI. One line\n"
    "per repetition, then per hazard min / median / p99 / max per item, the misses and the\n"
    "coverage (safe FSM states reached, detection kinds exercised). A hazard whose faults the\n"
    "campaign cannot inject (or of which nothing can be observed) is NOT RUN with the reason.\n"
    "\n"
    "Examples:\n"
    "  vcu safety campaign --config config/hhea/vehicle.json\n"
    "  vcu safety campaign --hazard H-FSM-HANG --repeat 30 --html report.html --junit junit.xml\n"
    "Exit: 0 every hazard run passed, 1 a miss (or a hazard named with --hazard, or any with\n"
    "--strict, that cannot run), 2 usage error.\n";

}  // namespace

void registerSafetyCommands(CLI::App& app, CommandContext& context) {
  CLI::App* group = app.add_subcommand("safety", SAFETY_DESCRIPTION);
  auto options = std::make_shared<SafetyCampaignOptions>();
  CLI::App* campaign = group->add_subcommand("campaign", CAMPAIGN_DESCRIPTION);
  campaign->footer(CAMPAIGN_FOOTER);
  campaign->add_option("--safety", options->safetyFile, "the safety case (default: vehicle.json's \"safety\")");
  campaign->add_option("--hazard", options->hazards, "run only this hazard (repeatable)");
  campaign->add_option("--repeat", options->repeat, "injections per hazard")->check(CLI::Range(1, 1000));
  campaign->add_option("--json", options->jsonFile, "write the results as JSON to this file");
  campaign->add_option("--junit", options->junitFile, "write JUnit XML (one testcase per hazard) to this file");
  campaign->add_option("--html", options->htmlFile, "write a self-contained HTML evidence report to this file");
  campaign
      ->add_option("--step-timeout", options->stepTimeoutSeconds,
                   "seconds one FSM step may take while bringing the vehicle to a state")
      ->check(CLI::PositiveNumber);
  campaign
      ->add_option("--settle", options->settleSeconds,
                   "seconds the vehicle stays in the reached state before the injection (default 1)")
      ->check(CLI::NonNegativeNumber);
  campaign->add_flag("--strict", options->strict, "a hazard that cannot run fails the campaign");
  addStackOptions(*campaign, options->stack);
  campaign->callback([options, &context] { context.exitCode = runSafetyCampaign(*options, context.streams); });
  group->require_subcommand(1);
}

}  // namespace openvcu::cli
