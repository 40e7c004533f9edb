#pragma once
// What the commands that talk to a running stack share (`vcu signal ...`, `vcu status`,
// `vcu spy`): finding the configuration, the catalog, and turning table values and
// timestamps into text.
//
// The configuration: --config FILE, else the file named by $OPENVCU_CONFIG; neither is a
// usage error (exit 2). There is deliberately no built-in default: an installed `vcu` has
// no repository to be relative to, and guessing another vehicle's file would show or
// command the wrong signals. --instance overrides the configuration's instance, exactly
// as it does for the services.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "cli.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"

namespace CLI {
class App;
}

namespace openvcu::cli {

inline constexpr std::string_view CONFIG_ENVIRONMENT_VARIABLE = "OPENVCU_CONFIG";

/// Where the stack is.
struct StackOptions {
  std::string configPath;  ///< --config; empty: $OPENVCU_CONFIG
  std::string instance;    ///< --instance; empty: the configuration's
};

/// The loaded configuration (instance applied) and its catalog.
struct Stack {
  config::VehicleConfig config;
  signals::Catalog catalog;
};

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

/// "2026-11-21T06:00:01.234Z" for CLOCK_REALTIME ns.
std::string formatUtc(std::int64_t realtimeNs);
/// CLOCK_REALTIME ns now.
std::int64_t realtimeNowNs() noexcept;
/// A table time stamp (CLOCK_MONOTONIC ns) as CLOCK_REALTIME ns, through the current offset.
std::int64_t monotonicToRealtimeNs(std::int64_t monotonicNs) noexcept;
/// "0.52 s", "3 min 5 s", "2 h 4 min" for a duration in ns.
std::string formatDuration(std::int64_t nanoseconds);

}  // namespace openvcu::cli
