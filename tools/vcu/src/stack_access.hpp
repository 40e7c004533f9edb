#pragma once
// What the commands that talk to a running stack share (`vcu signal ...`, `vcu status`,
// `vcu spy`): finding the configuration, the catalog, and turning table values and
// timestamps into text.
//
// The configuration: --config FILE, else the file named by $OPENVCU_CONFIG, else the
// configuration of the one stack running on this machine (issue 19): its services'
// command sockets (<root>/<instance>/<program>.sock, root $OPENVCU_RUN_DIR or
// /run/openvcu) are connected to, SO_PEERCRED names the process behind each, and
// /proc/<pid>/cmdline gives the `--config FILE` it was started with (a relative FILE
// resolved against /proc/<pid>/cwd; without --config its $OPENVCU_CONFIG from
// /proc/<pid>/environ). Nothing is written for this: what a service was started with is
// the truth, whoever started it (run.sh, supervisord, systemd, a shell), and a crashed
// stack leaves a socket nobody answers, which is skipped. Two stacks running, or none, is
// a usage error (exit 2) naming them. There is deliberately no built-in default: an
// installed `vcu` has no repository to be relative to, and guessing another vehicle's
// file would show or command the wrong signals. --instance overrides the configuration's
// instance, exactly as it does for the services; a stack found running keeps the
// instance of its socket folder.

#include <sys/types.h>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/service/logger.hpp"
#include "openvcu/signals/catalog.hpp"

namespace CLI {
class App;
}

namespace openvcu::display {
class HealthTracker;
struct ServiceHealth;
}  // namespace openvcu::display

namespace openvcu::cli {

inline constexpr std::string_view CONFIG_ENVIRONMENT_VARIABLE = "OPENVCU_CONFIG";

/// Where the stack is.
struct StackOptions {
  std::string configPath;  ///< --config; empty: $OPENVCU_CONFIG, else the running stack's
  std::string instance;    ///< --instance; empty: the configuration's
};

/// The loaded configuration (instance applied) and its catalog.
struct Stack {
  config::VehicleConfig config;
  signals::Catalog catalog;
};

/// A stack found through its command sockets.
struct RunningStack {
  std::string instance;    ///< the socket folder's name
  std::string configPath;  ///< absolute
  std::string foundBy;     ///< "vcu-fsm (pid 812)"
};

/// The stacks whose command sockets answer under ipc::commandRoot(), one per instance.
/// Instances with answering sockets whose configuration cannot be told (another user's
/// process without --config, an absent /proc) are not listed; why goes to *problems.
std::vector<RunningStack> findRunningStacks(std::vector<std::string>* problems);

/// Which configuration a command uses: --config, else $OPENVCU_CONFIG, else the single
/// running stack's (then *foundInstance is its instance). Empty with the reason reported
/// on err and *exitCode = Usage when there is none or more than one stack runs.
std::optional<std::string> resolveConfigPath(const StackOptions& options, Sink& err, ExitCode* exitCode,
                                             std::string* foundInstance = nullptr);

/// Adds -c/--config and --instance to a command.
void addStackOptions(CLI::App& command, StackOptions& options);

/// Loads the stack; on failure reports on err and sets *exitCode (Usage when no
/// configuration was named, Failure otherwise).
std::optional<Stack> loadStack(const StackOptions& options, Sink& err, ExitCode* exitCode);

/// Shortest text that reads back as the same number ("87.5", "1", "1e+20").
std::string formatNumber(double value);
/// "87.5 %" or "1 \"Start\"" (value text from the signal's value table) or "3".
std::string formatValue(const signals::SignalInfo& signal, double value);
/// The value-table text of a value (shared/signals).
using signals::valueText;
/// A number, or a value text of the signal ("Start"); else an error naming the choices.
Result<double> parseValue(const signals::SignalInfo& signal, std::string_view text);

/// "2026-11-21T06:00:01.234Z" for CLOCK_REALTIME ns (the log's time format).
using service::formatUtc;
/// A table time stamp (CLOCK_MONOTONIC ns) as CLOCK_REALTIME ns, through the current offset.
std::int64_t monotonicToRealtimeNs(std::int64_t monotonicNs) noexcept;
/// "0.52 s", "3 min 5 s", "2 h 4 min" for a duration in ns.
std::string formatDuration(std::int64_t nanoseconds);
/// "silent for 4.02 s", "stopped 4.02 s ago", "not heard"; empty while the service beats.
std::string livenessText(const display::HealthTracker& health, const display::ServiceHealth& service,
                         std::int64_t nowMonoNs);

/// Starts argv[0] with `argv` (from PATH when `searchPath`), the signals in `defaults` at
/// their default action in the child (a parent that ignores SIGINT must not pass that on).
/// 0 and the child's pid in *pid, else the posix_spawn error number.
int spawnProcess(const std::vector<std::string>& argv, std::initializer_list<int> defaults, bool searchPath,
                 pid_t* pid);

/// Waits until iox-roudi connected a sim link opened just now to its peers: a frame
/// published before that is not delivered (shared/can_links sim link). At most 2 s.
Status waitUntilSimLinkConnected(const std::string& simBus);

}  // namespace openvcu::cli
