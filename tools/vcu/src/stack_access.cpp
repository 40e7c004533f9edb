#include "stack_access.hpp"

#include <dirent.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "cli_checks.hpp"
#include "diagnostics.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/display/health.hpp"
#include "openvcu/ipc/command_socket.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::cli {

namespace {

/// The NUL-separated strings of a /proc file (cmdline, environ); empty when unreadable.
std::vector<std::string> readProcStrings(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  std::vector<std::string> strings;
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\0', begin);
    if (end == std::string::npos) end = text.size();
    strings.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return strings;
}

/// The value of -c/--config in a service's arguments (CLI11's forms: "--config F",
/// "--config=F", "-c F", "-cF"), or empty.
std::string configArgument(const std::vector<std::string>& argv) {
  for (std::size_t i = 1; i < argv.size(); ++i) {
    const std::string& argument = argv[i];
    if ((argument == "--config" || argument == "-c") && i + 1 < argv.size()) return argv[i + 1];
    if (argument.rfind("--config=", 0) == 0) return argument.substr(9);
    if (argument.size() > 2 && argument.rfind("-c", 0) == 0 && argument[2] != '-') return argument.substr(2);
  }
  return {};
}

/// The pid serving a Unix seqpacket socket, or empty when nobody answers (a socket left by
/// a crashed service) or we may not connect.
std::optional<pid_t> socketServer(const std::string& path) {
  sockaddr_un address{};
  if (path.size() >= sizeof(address.sun_path)) return std::nullopt;
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  if (fd < 0) return std::nullopt;
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  std::optional<pid_t> pid;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) == 0) {
    ucred credentials{};
    socklen_t size = sizeof(credentials);
    if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &credentials, &size) == 0 && credentials.pid > 0) {
      pid = credentials.pid;
    }
  }
  ::close(fd);
  return pid;
}

/// The configuration the process `pid` runs with: --config (relative to its working
/// folder) or its $OPENVCU_CONFIG. Empty with *problem set when it cannot be told.
std::string processConfig(pid_t pid, const std::string& who, std::string* problem) {
  const std::string proc = "/proc/" + std::to_string(pid);
  std::string path = configArgument(readProcStrings(proc + "/cmdline"));
  if (path.empty()) {
    const std::string prefix = std::string(CONFIG_ENVIRONMENT_VARIABLE) + "=";
    for (const std::string& variable : readProcStrings(proc + "/environ")) {
      if (variable.rfind(prefix, 0) == 0) path = variable.substr(prefix.size());
    }
  }
  if (path.empty()) {
    *problem = who + " has no --config and its environment cannot be read";
    return {};
  }
  if (path.front() != '/') {
    std::error_code error;
    const std::filesystem::path cwd = std::filesystem::read_symlink(proc + "/cwd", error);
    if (error) {
      *problem = who + " was given the relative path '" + path + "' and its working folder cannot be read";
      return {};
    }
    path = (cwd / path).lexically_normal().string();
  }
  return path;
}

}  // namespace

std::vector<RunningStack> findRunningStacks(std::vector<std::string>* problems) {
  const std::string root = ipc::commandRoot();
  std::vector<RunningStack> stacks;
  DIR* rootDir = ::opendir(root.c_str());
  if (rootDir == nullptr) return stacks;
  std::vector<std::string> instances;
  while (const dirent* entry = ::readdir(rootDir)) {
    if (config::validInstanceName(entry->d_name)) instances.emplace_back(entry->d_name);
  }
  ::closedir(rootDir);
  std::sort(instances.begin(), instances.end());
  for (const std::string& instance : instances) {
    const std::string folder = root + "/" + instance;
    struct stat info {};
    if (::stat(folder.c_str(), &info) != 0 || !S_ISDIR(info.st_mode)) continue;
    if ((info.st_mode & S_IWOTH) != 0) {  // the rule of ipc::CommandClient: not to be trusted
      if (problems) problems->push_back(folder + " is writable by others: ignored");
      continue;
    }
    DIR* dir = ::opendir(folder.c_str());
    if (dir == nullptr) {
      if (problems) problems->push_back("cannot read " + folder + ": " + std::strerror(errno));
      continue;
    }
    std::vector<std::string> sockets;
    while (const dirent* entry = ::readdir(dir)) {
      const std::string name = entry->d_name;
      if (name.size() > 5 && name.compare(name.size() - 5, 5, ".sock") == 0) sockets.push_back(name);
    }
    ::closedir(dir);
    std::sort(sockets.begin(), sockets.end());
    std::string problem;
    for (const std::string& socket : sockets) {
      const auto pid = socketServer(folder + "/" + socket);
      if (!pid) continue;
      const std::string who = socket.substr(0, socket.size() - 5) + " (pid " + std::to_string(*pid) + ")";
      std::string path = processConfig(*pid, who, &problem);
      if (path.empty()) continue;
      stacks.push_back(RunningStack{instance, std::move(path), who});
      problem.clear();
      break;
    }
    if (!problem.empty() && problems) problems->push_back("instance '" + instance + "': " + problem);
  }
  return stacks;
}

std::optional<std::string> resolveConfigPath(const StackOptions& options, Sink& err, ExitCode* exitCode,
                                             std::string* foundInstance) {
  if (!options.configPath.empty()) return options.configPath;
  if (const char* fromEnvironment = std::getenv(std::string(CONFIG_ENVIRONMENT_VARIABLE).c_str())) {
    if (fromEnvironment[0] != '\0') return std::string(fromEnvironment);
  }
  std::vector<std::string> problems;
  const std::vector<RunningStack> stacks = findRunningStacks(&problems);
  *exitCode = ExitCode::Usage;
  const std::string advice = "give --config FILE or set " + std::string(CONFIG_ENVIRONMENT_VARIABLE);
  if (stacks.size() == 1) {
    if (foundInstance) *foundInstance = stacks.front().instance;
    return stacks.front().configPath;
  }
  if (stacks.empty()) {
    std::string message = "no configuration: " + advice + " (no running stack found in " + ipc::commandRoot();
    for (const std::string& problem : problems) message += "; " + problem;
    reportError(err, message + ")");
    return std::nullopt;
  }
  std::string message = std::to_string(stacks.size()) + " stacks are running (";
  for (std::size_t i = 0; i < stacks.size(); ++i) {
    message += (i > 0 ? ", " : "") + stacks[i].instance + ": " + stacks[i].configPath;
  }
  reportError(err, message + "): " + advice);
  return std::nullopt;
}

void addStackOptions(CLI::App& command, StackOptions& options) {
  command
      .add_option("-c,--config", options.configPath,
                  "the vehicle configuration (default: $OPENVCU_CONFIG, else the one running stack's)")
      ->option_text("FILE");
  command.add_option("--instance", options.instance, "stack instance; overrides the configuration's")
      ->option_text("NAME");
}

std::optional<Stack> loadStack(const StackOptions& options, Sink& err, ExitCode* exitCode) {
  std::string foundInstance;
  const auto maybePath = resolveConfigPath(options, err, exitCode, &foundInstance);
  if (!maybePath) return std::nullopt;
  *exitCode = ExitCode::Failure;
  // a folder stands for its vehicle.json, as in `vcu check PATH`
  const Result<std::string> file = vehicleFileOf(*maybePath);
  if (!file) {
    report(err, file.error());
    return std::nullopt;
  }
  const std::string& path = *file;
  auto configResult = config::loadVehicleConfig(path);
  if (!configResult) {
    report(err, configResult.error());
    return std::nullopt;
  }
  Stack stack;
  stack.config = std::move(*configResult);
  if (!options.instance.empty()) {
    if (!config::validInstanceName(options.instance)) {
      reportError(err, "--instance '" + options.instance + "': must be 1-32 letters, digits, '-' or '_'");
      *exitCode = ExitCode::Usage;
      return std::nullopt;
    }
    stack.config.instance = options.instance;
  } else if (!foundInstance.empty()) {
    stack.config.instance = foundInstance;  // started with --instance: its sockets' folder says so
  }
  auto catalogResult = config::buildCatalog(stack.config);
  if (!catalogResult) {
    reportError(err, path + ": " + catalogResult.error().message);
    return std::nullopt;
  }
  stack.catalog = std::move(*catalogResult);
  *exitCode = ExitCode::Ok;
  return stack;
}

std::string formatNumber(double value) {
  std::array<char, 32> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{}) return "?";
  return std::string(text.data(), end);
}

std::string formatValue(const signals::SignalInfo& signal, double value) {
  std::string text = formatNumber(value);
  if (const auto maybeText = valueText(signal, value)) return text + " \"" + *maybeText + "\"";
  if (!signal.unit.empty()) text += " " + signal.unit;
  return text;
}

Result<double> parseValue(const signals::SignalInfo& signal, std::string_view text) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  if (const auto [ptr, ec] = std::from_chars(text.data(), end, value); ec == std::errc{} && ptr == end) return value;
  for (const auto& [number, name] : signal.valueTexts) {
    if (name == text) return static_cast<double>(number);
  }
  std::string message = "'" + std::string(text) + "' is not a number";
  if (!signal.valueTexts.empty()) {
    message += " nor a value of '" + signal.key + "' (";
    for (std::size_t i = 0; i < signal.valueTexts.size(); ++i) {
      if (i > 0) message += ", ";
      message += std::to_string(signal.valueTexts[i].first) + " " + signal.valueTexts[i].second;
    }
    message += ")";
  }
  return Error{message};
}

std::int64_t monotonicToRealtimeNs(std::int64_t monotonicNs) noexcept {
  return clock::realtimeNs() - (clock::monotonicNs() - monotonicNs);
}

std::string formatDuration(std::int64_t nanoseconds) {
  const double seconds = static_cast<double>(nanoseconds) / 1e9;
  std::array<char, 48> text{};
  if (seconds < 60.0) {
    std::snprintf(text.data(), text.size(), "%.2f s", seconds);
  } else if (seconds < 3600.0) {
    const auto whole = static_cast<long>(seconds);
    std::snprintf(text.data(), text.size(), "%ld min %ld s", whole / 60, whole % 60);
  } else {
    const auto whole = static_cast<long>(seconds);
    std::snprintf(text.data(), text.size(), "%ld h %ld min", whole / 3600, (whole % 3600) / 60);
  }
  return text.data();
}

std::string livenessText(const display::HealthTracker& health, const display::ServiceHealth& service,
                         std::int64_t nowMonoNs) {
  const auto silentNs = health.silentFor(service, nowMonoNs);
  switch (health.livenessOf(service, nowMonoNs)) {
    case display::Liveness::Silent:
      return "silent for " + formatDuration(silentNs.value_or(0));
    case display::Liveness::Stopped:
      return "stopped " + formatDuration(silentNs.value_or(0)) + " ago";
    case display::Liveness::NotHeard:
      return "not heard";
    default:
      return {};
  }
}

/// How long a new sim link may take to be connected (normally < 0.1 s).
constexpr auto SIM_CONNECT_TIMEOUT = std::chrono::seconds(2);

/// Why a fresh sim link may need a wait: a frame published before the link's publisher
/// is connected to a peer is not delivered to it (sim_link.hpp), and the Link interface
/// has no peer count. The frame-stream contract allows ~100 ms for the connection. (RouDi
/// 2.0.3 connects a new port to the existing ones before create() returns; its periodic
/// discovery pass, which catches anything left over, handles the publishers it finds
/// before the subscribers.) Either way a probe publisher on the same wire topic, created
/// after the link, gets its first subscriber (at least the link's own receive side) no
/// earlier than the link's publisher was connected to every subscriber that existed
/// before it. So the wait is a readiness signal, not a guessed sleep (on RouDi 2.0.3 it
/// ends at the first look). The probe never publishes and is gone when this returns.
Status waitUntilSimLinkConnected(const std::string& simBus) {
  auto probeResult = ipc::FramePublisher::create(ipc::FrameTopic{"sim", simBus, ipc::FrameStream::SimWire});
  if (!probeResult) return probeResult.error();
  if (!probeResult->waitForSubscribers(SIM_CONNECT_TIMEOUT)) {
    return Error{"sim:" + simBus + ": iox-roudi did not connect the link within " +
                 std::to_string(std::chrono::milliseconds(SIM_CONNECT_TIMEOUT).count()) + " ms"};
  }
  return {};
}

int spawnProcess(const std::vector<std::string>& argv, std::initializer_list<int> defaults, bool searchPath,
                 pid_t* pid) {
  std::vector<char*> args;
  for (const std::string& argument : argv) args.push_back(const_cast<char*>(argument.c_str()));
  args.push_back(nullptr);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaultSet;
  sigemptyset(&defaultSet);
  for (const int signal : defaults) sigaddset(&defaultSet, signal);
  posix_spawnattr_setsigdefault(&attributes, &defaultSet);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
  const int rc = searchPath ? ::posix_spawnp(pid, argv.front().c_str(), nullptr, &attributes, args.data(), environ)
                            : ::posix_spawn(pid, argv.front().c_str(), nullptr, &attributes, args.data(), environ);
  posix_spawnattr_destroy(&attributes);
  return rc;
}

}  // namespace openvcu::cli
