#pragma once
// Injecting one fault of a safety case into a running stack, and taking it back (vcu safety
// campaign). Each kind goes the way an operator or a test would take:
//   - frame faults (silence, delay, corrupt, replay, spoof, claim, babble, busOff): the
//     SimFault command to vcu-ecu-sim, as `vcu inject` sends it ("busoff.vehicle");
//   - simFault: `vcu sim fault NAME on`; gpioStuck: `vcu inject gpio`;
//   - stop / kill: `vcu inject process`;
//   - signal: the signal's owner sets it through the command path `vcu signal set` and the
//     HMI use (internal.operator.* are vcu-fsm's, written with its writer id).
// Clearing undoes each: --off, SIGCONT, the signal's earlier value; a lost J1939 address
// comes back only when vcu-can-tx starts again (J1939-81 gives no retry), so clearing an
// address claim restarts vcu-can-tx when a supervisord runs to start it.
//
//   FaultInjector injector(stack, options.stack, planner, streams.err);
//   if (std::string why = injector.whyNot(fault); !why.empty()) -> listed "not injected"
//   auto applied = injector.inject(fault, &stamp, &error);   // stamp: when it took effect
//   applied->clear();
//
// @note blocks (commands, waits); one thread.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "openvcu/safety/safety_case.hpp"
#include "safety_campaign_plan.hpp"
#include "stack_access.hpp"

namespace openvcu::cli {

/// When a fault took effect: CLOCK_MONOTONIC and CLOCK_REALTIME ns (the clock of LCM events).
struct InjectionStamp {
  std::int64_t monotonicNs{};
  std::int64_t realtimeNs{};
};

/// A fault applied, and how to take it back (empty: nothing to take back).
struct AppliedFault {
  std::string label;  ///< "silent.VIC", "SIGSTOP vcu-fsm (pid 812)", "internal.operator.Crash=1"
  std::function<void()> clear;
};

class FaultInjector {
 public:
  /// Every reference must outlive the injector. Warnings (a clear that did not work) go to
  /// `warnings`.
  FaultInjector(const Stack& stack, const StackOptions& stackOptions, StatePlanner& planner, Sink& warnings);

  /// Why `fault` cannot be injected into this stack; empty when it can.
  [[nodiscard]] std::string whyNot(const safety::Injection& fault) const;
  /// Applies `fault`; *stamp is the moment it took effect (or the latest time stamp known
  /// before it). Empty and *error set when it was not applied.
  std::optional<AppliedFault> inject(const safety::Injection& fault, InjectionStamp* stamp, std::string* error);

  /// How long clearing an address claim waits for vcu-can-tx to beat again.
  static constexpr double RESTART_WAIT_SECONDS = 15.0;

 private:
  std::optional<AppliedFault> injectSignal(const safety::Injection& fault, InjectionStamp* stamp, std::string* error);
  void restartCanTx();

  const Stack& m_stack;
  const StackOptions& m_stackOptions;
  StatePlanner& m_planner;
  Sink& m_warnings;
};

}  // namespace openvcu::cli
