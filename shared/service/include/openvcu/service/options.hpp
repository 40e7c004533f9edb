#pragma once
// The command line every service shares, and who a service is.
//
//   vcu-fsm --config config/hhea/vehicle.json [--instance bench2] [--log-level debug]
//   vcu-fsm --help | --version
//
//   service::CommandLine commandLine(FSM_INFO);
//   commandLine.addOption("--fsm-file", fsmFile, "FSM file instead of the configuration's");
//   if (const auto maybeExit = commandLine.parseOrExit(argc, argv)) return *maybeExit;
//   // commandLine.options() holds --config, --instance and --log-level
//
// --config may be left out when OPENVCU_CONFIG names the file (the same rule as `vcu`).
// Exit codes of every service: 0 done (also after SIGTERM/SIGINT and for --help/--version),
// 1 start-up or configuration error (one line on stderr), 2 usage error.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "openvcu/ipc/events.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::service {

/// Process exit codes shared by every service.
enum class ExitCode : int {
  Ok = 0,       ///< stopped on request (SIGTERM, SIGINT) or --help/--version
  Failure = 1,  ///< start-up failed: configuration, table, event bus, RouDi
  Usage = 2,    ///< the command line itself was wrong
  /// iox-roudi was restarted under a running service: its iceoryx ports are cut off and
  /// cannot re-register, so it exits for the supervisor to start it again (EX_TEMPFAIL)
  RoudiRestarted = 75,
};

/// The environment variable naming the configuration when --config is not given.
inline constexpr std::string_view CONFIG_ENVIRONMENT_VARIABLE = "OPENVCU_CONFIG";

/// Who a service is. Fixed per binary (a constant in its main.cpp).
struct ServiceInfo {
  /// Short name: "can-rx", "fsm". Names the heartbeat slot "internal.service.<name>.heartbeat".
  std::string name;
  /// Installed name, used in logs, heartbeats and acknowledgements; empty: "vcu-<name>".
  std::string program;
  std::string description;  ///< one line for --help
  std::string version;      ///< for --version; empty: the openvcu version
  /// Stamped on this service's command and override writes (SignalTable writer id).
  signals::WriterId writerId{};
  /// true: open() registers with iox-roudi (needed for frame streams and ipc::Waiter);
  /// false: the service never touches iceoryx and survives a RouDi restart.
  bool usesFrameStreams{false};

  /// program, or "vcu-<name>" when program is empty.
  [[nodiscard]] std::string programName() const;
};

/// The common options, after parsing.
struct ServiceOptions {
  std::string configPath;  ///< --config, else $OPENVCU_CONFIG
  std::string instance;    ///< --instance; empty: the configuration's
  ipc::LogLevel logLevel{ipc::LogLevel::Info};
};

/// "trace", "debug", "info", "warning", "error", "critical".
[[nodiscard]] std::string_view logLevelName(ipc::LogLevel level) noexcept;
/// The inverse of logLevelName (also accepts "warn"); empty for anything else.
[[nodiscard]] std::optional<ipc::LogLevel> parseLogLevel(std::string_view name) noexcept;

/// What parse() decided.
struct ParseOutcome {
  /// Empty: carry on and run. Set: exit now with this code after printing `text`.
  std::optional<int> exitCode;
  std::string text;     ///< --help/--version text (for stdout) or the usage error (for stderr)
  bool isError{false};  ///< text belongs on stderr
};

struct CommandLineImpl;

/// The common options plus the service's own. Wraps CLI11 (services never see it).
/// @note not thread-safe; start-up only. The variables given to add*() must outlive parse().
class CommandLine {
 public:
  explicit CommandLine(ServiceInfo info);
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;
  ~CommandLine();

  /// Service-specific options. `names` in CLI11 form: "--fsm-file" or "-f,--fsm-file".
  void addOption(const std::string& names, std::string& target, const std::string& help);
  void addOption(const std::string& names, double& target, const std::string& help);
  void addOption(const std::string& names, std::int64_t& target, const std::string& help);
  void addFlag(const std::string& names, bool& target, const std::string& help);

  /// Parses the arguments after the program name. `environmentConfig` stands in for
  /// $OPENVCU_CONFIG (tests); parseOrExit reads the real environment.
  ParseOutcome parse(std::span<const std::string> arguments, std::optional<std::string> environmentConfig = {});

  /// main's form: parses argv; on help, version or a usage error prints (stdout / stderr)
  /// and returns the exit code to return from main; empty: run.
  std::optional<int> parseOrExit(int argc, const char* const* argv);

  [[nodiscard]] const ServiceOptions& options() const noexcept;
  [[nodiscard]] const ServiceInfo& info() const noexcept;

 private:
  std::unique_ptr<CommandLineImpl> m_impl;
};

}  // namespace openvcu::service
