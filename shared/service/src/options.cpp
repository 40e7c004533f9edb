#include "openvcu/service/options.hpp"

#include <CLI/CLI.hpp>
#include <array>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <vector>

namespace openvcu::service {

namespace {

struct LevelName {
  ipc::LogLevel level;
  std::string_view name;
};
constexpr std::array<LevelName, 6> LEVEL_NAMES = {{{ipc::LogLevel::Trace, "trace"},
                                                   {ipc::LogLevel::Debug, "debug"},
                                                   {ipc::LogLevel::Info, "info"},
                                                   {ipc::LogLevel::Warning, "warning"},
                                                   {ipc::LogLevel::Error, "error"},
                                                   {ipc::LogLevel::Critical, "critical"}}};

constexpr const char* FOOTER_TEMPLATE =
    "Configuration: --config FILE, or the file named by $OPENVCU_CONFIG.\n"
    "Readiness: with NOTIFY_SOCKET set (systemd Type=notify, the test harness), sends\n"
    "READY=1 once serving and STOPPING=1 on SIGTERM/SIGINT; also logs 'ready'.\n"
    "Exit: 0 stopped by SIGTERM/SIGINT, 1 start-up or configuration error, 2 usage error.\n";

}  // namespace

std::string ServiceInfo::programName() const {
  return program.empty() ? "vcu-" + name : program;
}

std::string_view logLevelName(ipc::LogLevel level) noexcept {
  for (const LevelName& entry : LEVEL_NAMES) {
    if (entry.level == level) return entry.name;
  }
  return "info";
}

std::optional<ipc::LogLevel> parseLogLevel(std::string_view name) noexcept {
  if (name == "warn") return ipc::LogLevel::Warning;
  for (const LevelName& entry : LEVEL_NAMES) {
    if (entry.name == name) return entry.level;
  }
  return std::nullopt;
}

struct CommandLineImpl {
  explicit CommandLineImpl(ServiceInfo serviceInfo)
      : info(std::move(serviceInfo)), app(info.description, info.programName()) {
    app.footer(FOOTER_TEMPLATE);
    const std::string version = info.version.empty() ? std::string(OPENVCU_VERSION) : info.version;
    app.set_version_flag("--version", info.programName() + " (openvcu) " + version);
    app.add_option("-c,--config", options.configPath, "the vehicle configuration (default: $OPENVCU_CONFIG)")
        ->option_text("FILE");
    app.add_option("--instance", options.instance, "stack instance; overrides the configuration's")
        ->option_text("NAME");
    std::vector<std::string> levelNames;
    for (const LevelName& entry : LEVEL_NAMES) levelNames.emplace_back(entry.name);
    app.add_option("--log-level", logLevelText, "lowest level logged (default info)")
        ->check(CLI::IsMember(levelNames))
        ->option_text("trace|debug|info|warning|error|critical");
  }

  ServiceInfo info;
  ServiceOptions options;
  std::string logLevelText{"info"};
  CLI::App app;
};

CommandLine::CommandLine(ServiceInfo info) : m_impl(std::make_unique<CommandLineImpl>(std::move(info))) {}
CommandLine::~CommandLine() = default;

void CommandLine::addOption(const std::string& names, std::string& target, const std::string& help) {
  m_impl->app.add_option(names, target, help);
}
void CommandLine::addOption(const std::string& names, double& target, const std::string& help) {
  m_impl->app.add_option(names, target, help);
}
void CommandLine::addOption(const std::string& names, std::int64_t& target, const std::string& help) {
  m_impl->app.add_option(names, target, help);
}
void CommandLine::addFlag(const std::string& names, bool& target, const std::string& help) {
  m_impl->app.add_flag(names, target, help);
}

ParseOutcome CommandLine::parse(std::span<const std::string> arguments, std::optional<std::string> environmentConfig) {
  CommandLineImpl& impl = *m_impl;
  ParseOutcome outcome;
  try {
    // CLI11 wants the arguments in reverse order when given as a vector.
    std::vector<std::string> reversed(arguments.rbegin(), arguments.rend());
    impl.app.parse(reversed);
  } catch (const CLI::ParseError& error) {
    std::ostringstream out;
    std::ostringstream err;
    if (error.get_exit_code() == 0) {  // --help, --version
      impl.app.exit(error, out, err);
      outcome.exitCode = static_cast<int>(ExitCode::Ok);
      outcome.text = out.str() + err.str();
      return outcome;
    }
    outcome.exitCode = static_cast<int>(ExitCode::Usage);
    outcome.text = impl.info.programName() + ": error: " + error.what() + " (see --help)\n";
    outcome.isError = true;
    return outcome;
  }
  if (impl.options.configPath.empty() && environmentConfig && !environmentConfig->empty()) {
    impl.options.configPath = *environmentConfig;
  }
  if (impl.options.configPath.empty()) {
    outcome.exitCode = static_cast<int>(ExitCode::Usage);
    outcome.text = impl.info.programName() + ": error: no configuration: give --config FILE or set " +
                   std::string(CONFIG_ENVIRONMENT_VARIABLE) + " (see --help)\n";
    outcome.isError = true;
    return outcome;
  }
  impl.options.logLevel = parseLogLevel(impl.logLevelText).value_or(ipc::LogLevel::Info);
  return outcome;
}

std::optional<int> CommandLine::parseOrExit(int argc, const char* const* argv) {
  std::vector<std::string> arguments;
  for (int i = 1; i < argc; ++i) arguments.emplace_back(argv[i]);
  std::optional<std::string> environmentConfig;
  if (const char* value = std::getenv(std::string(CONFIG_ENVIRONMENT_VARIABLE).c_str())) environmentConfig = value;
  ParseOutcome outcome;
  try {
    outcome = parse(arguments, environmentConfig);
  } catch (const std::exception& error) {  // CLI11 set-up errors (a service's duplicate option name)
    std::cerr << m_impl->info.programName() << ": internal error: " << error.what() << '\n';
    return static_cast<int>(ExitCode::Failure);
  }
  if (!outcome.exitCode) return std::nullopt;
  (outcome.isError ? std::cerr : std::cout) << outcome.text << std::flush;
  return outcome.exitCode;
}

const ServiceOptions& CommandLine::options() const noexcept {
  return m_impl->options;
}

const ServiceInfo& CommandLine::info() const noexcept {
  return m_impl->info;
}

}  // namespace openvcu::service
