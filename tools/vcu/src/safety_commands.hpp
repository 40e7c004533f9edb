#pragma once
// `vcu safety campaign`: runs the hazards of the vehicle's safety case (safety.json)
// against a running stack and measures each reaction from the injection's time stamp.
//
//   vcu safety campaign --config config/hhea/vehicle.json --repeat 3 --html report.html
//   H-BAT-TIMEOUT #1 PASS fsm Battery Timeout 3012 ms, fault rx_timeout.*.HVESSS1_PGN61590 612 ms (FTTI 4000 ms)
//   ...
//   campaign passed: 2 passed, 0 failed, 3 not run             (exit 0; a miss: exit 1)
//
// For each selected hazard and repetition: the vehicle is brought to a state of the
// hazard's "during" list (operator signals set as fsm.json's transitions ask), its faults
// are injected through the `vcu inject` code (frame faults by vcu-ecu-sim, process faults
// by signal, GPIO inputs on the simulated chip), and the safe state is watched until every
// item was seen or twice the FTTI passed: the FSM state (signal table), each bus command
// (frames of the simulated bus, decoded with the DBC), each GPIO level (internal.gpio.<line>),
// each detection's fault event (LCM), each service restarted (a new process beating). Then
// the faults are cleared and the vehicle is brought back (fault reset as fsm.json allows).

#include <string>
#include <vector>

#include "cli.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

struct SafetyCampaignOptions {
  StackOptions stack;
  std::string safetyFile;            ///< --safety; empty: vehicle.json's "safety"
  std::vector<std::string> hazards;  ///< --hazard; empty: every hazard
  int repeat{1};
  std::string jsonFile;
  std::string junitFile;
  std::string htmlFile;
  double stepTimeoutSeconds{15};  ///< --step-timeout: one FSM step of bringing the vehicle to a state
  double settleSeconds{1};        ///< --settle: time in the reached state before the injection
  bool strict{};                  ///< --strict: a hazard the campaign cannot run fails it too
};

/// Runs the campaign; 0 when every hazard run passed, 1 on a miss (or a selected hazard that
/// cannot run), 2 on a usage error.
ExitCode runSafetyCampaign(const SafetyCampaignOptions& options, Streams streams);

/// Adds `safety` and `safety campaign` to `app`.
void registerSafetyCommands(CLI::App& app, CommandContext& context);

}  // namespace openvcu::cli
