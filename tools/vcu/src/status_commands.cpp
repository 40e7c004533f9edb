// `vcu status` and `vcu spy`. Each subcommand's description and footer are its manual.
#include "status_commands.hpp"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "diagnostics.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/display/health.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/signals/table.hpp"
#include "text_table.hpp"

extern char** environ;

namespace openvcu::cli {
namespace {

constexpr const char* STATUS_DESCRIPTION = "List the services of a running stack from their heartbeats";
constexpr const char* STATUS_FOOTER =
    "Listens to the heartbeats (LCM, channel OPENVCU_<INSTANCE>_HEARTBEAT) for --wait\n"
    "seconds (default 1.5; services beat once a second) and prints one line per service\n"
    "process heard: program, pid, uptime, age of its last heartbeat, its status line\n"
    "('starting', 'ready', 'stopping (SIGTERM)', or its own) and its counters.\n"
    "Services not heard are listed too, never dropped, in a section NOT HEARD below\n"
    "(indented, so that lines starting with 'vcu-' are the services heard): the stack's\n"
    "own (vcu-can-rx, vcu-can-tx, vcu-fsm, vcu-gpio, vcu-ecu-sim) and every service\n"
    "whose heartbeat slot (internal.service.<name>.heartbeat) in the signal table was\n"
    "ever written. One that beat before and not for 2.5 s is 'silent for N s' (hung,\n"
    "stopped or dead; 'stopped N s ago' when its last heartbeat said stopping); one that\n"
    "never beat is 'not heard'.\n"
    "--stats adds each process's per-bus and per-message statistics (channel\n"
    "OPENVCU_<INSTANCE>_STATS: 'vehicle.frames_rx', 'rx.EEC1.period_us', 'tx.CCVS1.missed').\n"
    "The stack: --config FILE or $OPENVCU_CONFIG, --instance NAME.\n"
    "\n"
    "Example:\n"
    "  vcu status --config config/hhea/vehicle.json --wait 3\n"
    "  vcu status --stats | tr ' ' '\\n' | grep '^tx\\.'\n"
    "Exit: 0 services heard and none of the stack's own silent, 1 one of the stack's own\n"
    "services (or one heard while listening) is silent or stopped, none heard, or a\n"
    "configuration error, 2 usage error.\n";

constexpr const char* SPY_DESCRIPTION = "Start lcm-spy with the project's event types";
constexpr const char* SPY_FOOTER =
    "Runs shared/ipc/lcm-spy.sh (java lcm.spy.Spy with lcm.jar, jchart2d.jar and the\n"
    "build's openvcu-lcm-types.jar) on the stack's LCM URL: every OPENVCU_* channel\n"
    "decoded. The command is built as an argument list, never through a shell.\n"
    "URL: --lcm-url, else the configuration's (--config or $OPENVCU_CONFIG), else\n"
    "udpm://239.255.76.67:7667?ttl=0. Types: --types JAR, else the build's jar, else\n"
    "what lcm-spy.sh finds ($OPENVCU_LCM_TYPES_JAR, build*/shared/ipc/).\n"
    "Needs a display: headless, run 'xvfb-run -a vcu spy'.\n"
    "\n"
    "Examples:\n"
    "  vcu spy --config config/hhea/vehicle.json\n"
    "  vcu spy --dry-run\n"
    "Exit: 0 lcm-spy closed normally, 1 it could not start or failed, 2 usage error.\n";

std::string counterText(const std::vector<ipc::Counter>& counters) {
  std::string text;
  for (const ipc::Counter& counter : counters) {
    if (!text.empty()) text += ' ';
    text += counter.name + "=" + std::to_string(counter.value);
  }
  return text.empty() ? "-" : text;
}

std::string shellQuoted(const std::string& argument) {
  if (!argument.empty() && argument.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                                      "_-./:=@%+,") == std::string::npos) {
    return argument;
  }
  std::string quoted = "'";
  for (const char c : argument) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

/// Ignores SIGINT and SIGQUIT while a foreground child runs (Ctrl-C is the child's), as
/// system(3) does; restores them afterwards.
class IgnoreInterruptsScope {
 public:
  IgnoreInterruptsScope() {
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigemptyset(&ignore.sa_mask);
    ::sigaction(SIGINT, &ignore, &m_previousInt);
    ::sigaction(SIGQUIT, &ignore, &m_previousQuit);
  }
  IgnoreInterruptsScope(const IgnoreInterruptsScope&) = delete;
  IgnoreInterruptsScope& operator=(const IgnoreInterruptsScope&) = delete;
  ~IgnoreInterruptsScope() {
    ::sigaction(SIGINT, &m_previousInt, nullptr);
    ::sigaction(SIGQUIT, &m_previousQuit, nullptr);
  }

 private:
  struct sigaction m_previousInt {};
  struct sigaction m_previousQuit {};
};

void addStatus(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<StatusOptions>();
  CLI::App* status = app.add_subcommand("status", STATUS_DESCRIPTION);
  status->footer(STATUS_FOOTER);
  status->add_option("-w,--wait", options->waitSeconds, "seconds to listen (default 1.5)")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  status->add_flag("--stats", options->stats, "also the per-bus and per-message statistics");
  addStackOptions(*status, options->stack);
  status->callback([options, &context] { context.exitCode = runStatus(*options, context.streams); });
}

void addSpy(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<SpyOptions>();
  CLI::App* spy = app.add_subcommand("spy", SPY_DESCRIPTION);
  spy->footer(SPY_FOOTER);
  spy->add_option("--lcm-url", options->lcmUrl, "LCM URL (default: the configuration's)")->option_text("URL");
  spy->add_option("--types", options->typesJar, "the LCM types jar (default: the build's)")->option_text("JAR");
  spy->add_flag("--dry-run", options->dryRun, "print the command instead of running it");
  addStackOptions(*spy, options->stack);
  spy->callback([options, &context] { context.exitCode = runSpy(*options, context.streams); });
}

}  // namespace

ExitCode runStatus(const StatusOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  auto eventsResult = ipc::EventBus::open(maybeStack->config.lcmUrl, maybeStack->config.instance);
  if (!eventsResult) {
    reportError(streams.err, eventsResult.error().message);
    return ExitCode::Failure;
  }
  ipc::EventBus& events = *eventsResult;
  std::map<std::pair<std::string, std::int32_t>, ipc::Heartbeat> latest;        // by (program, pid)
  std::map<std::pair<std::string, std::int32_t>, std::int64_t> receivedMonoNs;  // when `latest` arrived
  auto subscribed = events.onHeartbeat([&](const ipc::Heartbeat& heartbeat) {
    auto& slot = latest[{heartbeat.service, heartbeat.pid}];
    if (heartbeat.timestampNs >= slot.timestampNs) {
      slot = heartbeat;
      receivedMonoNs[{heartbeat.service, heartbeat.pid}] = clock::monotonicNs();
    }
  });
  if (!subscribed) {
    reportError(streams.err, subscribed.error().message);
    return ExitCode::Failure;
  }
  // (program, pid) -> name -> value, merged from the parts as they come
  std::map<std::pair<std::string, std::int32_t>, std::map<std::string, std::int64_t>> stats;
  if (options.stats) {
    auto statsSubscribed = events.onStats([&](const ipc::Stats& part) {
      auto& values = stats[{part.service, part.pid}];
      for (const ipc::Counter& counter : part.counters) values[counter.name] = counter.value;
    });
    if (!statsSubscribed) {
      reportError(streams.err, statsSubscribed.error().message);
      return ExitCode::Failure;
    }
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                               std::chrono::duration<double>(options.waitSeconds));
  while (true) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    if (events.handle(left) == ipc::HandleResult::Failed) break;
  }

  // Liveness from both planes: the heartbeats heard, then the table's heartbeat slots (which
  // also know the services that stopped beating before `vcu status` started).
  const std::vector<std::string> expected = display::expectedServices();
  display::HealthTracker health(expected, display::HEARTBEAT_STALE_NS);
  for (const auto& [key, heartbeat] : latest) health.onHeartbeat(heartbeat, receivedMonoNs[key]);
  if (auto table =
          signals::SignalTable::open(maybeStack->catalog, maybeStack->config.instance, signals::OpenMode::AttachOnly)) {
    display::HeartbeatSlots(maybeStack->catalog).feed(health, *table);
  }
  const bool anyBeat = std::any_of(health.services().begin(), health.services().end(),
                                   [](const display::ServiceHealth& service) { return service.lastBeatMonoNs >= 0; });
  if (!anyBeat) {
    reportError(streams.err, "no heartbeat on " + events.channel(ipc::EventKind::Heartbeat) + " within " +
                                 formatNumber(options.waitSeconds) +
                                 " s (is the stack running? events: " + maybeStack->config.lcmUrl + ")");
    return ExitCode::Failure;
  }
  const std::int64_t now = clock::realtimeNs();
  const std::int64_t nowMono = clock::monotonicNs();
  std::vector<std::string> silent;  // "vcu-fsm silent for 4.12 s": these make the exit code 1
  const auto livenessOf = [&](const display::ServiceHealth& service) { return livenessText(health, service, nowMono); };
  std::vector<std::vector<std::string>> rows;
  for (const auto& [key, heartbeat] : latest) {
    std::vector<ipc::Counter> counters = heartbeat.counters;
    if (const auto found = stats.find(key); found != stats.end()) {
      for (const auto& [name, value] : found->second) counters.push_back(ipc::Counter{name, value});
    }
    std::string statusText = heartbeat.status.empty() ? "-" : heartbeat.status;
    const display::ServiceHealth* service = health.find(heartbeat.service);
    if (service != nullptr && service->pid == heartbeat.pid && health.silentFor(*service, nowMono)) {
      statusText = livenessOf(*service) + " (last: " + statusText + ")";
      silent.push_back(heartbeat.service + " " + livenessOf(*service));
    }
    rows.push_back({heartbeat.service, std::to_string(heartbeat.pid), formatDuration(heartbeat.uptimeMs * 1'000'000),
                    formatDuration(std::max<std::int64_t>(0, now - heartbeat.timestampNs)) + " ago", statusText,
                    counterText(counters)});
  }
  // The services not heard while listening (silent, stopped, or never heard) in a section of
  // their own, indented: a line starting with "vcu-" is a service heard beating, as scripts
  // that count the beating services read it.
  TextTable notHeard({"  NOT HEARD", "LAST BEAT", "STATUS"});
  for (const display::ServiceHealth& service : health.services()) {
    const bool heard =
        std::any_of(latest.begin(), latest.end(), [&](const auto& entry) { return entry.first.first == service.name; });
    if (heard) continue;
    std::string statusText = livenessOf(service);
    if (statusText.empty()) statusText = "beating (its table slot counts; no LCM heartbeat heard)";
    const bool own = std::find(expected.begin(), expected.end(), service.name) != expected.end();
    if (own && health.silentFor(service, nowMono)) silent.push_back(service.name + " " + statusText);
    notHeard.addRow({"  " + service.name,
                     service.lastBeatMonoNs >= 0
                         ? formatDuration(std::max<std::int64_t>(0, nowMono - service.lastBeatMonoNs)) + " ago"
                         : "never",
                     statusText});
  }
  std::sort(rows.begin(), rows.end());
  std::string out;
  if (rows.empty()) {
    out += "(no heartbeat heard within " + formatNumber(options.waitSeconds) + " s)\n";
  } else {
    TextTable table({"SERVICE", "PID", "UPTIME", "LAST BEAT", "STATUS", "COUNTERS"});
    for (std::vector<std::string>& row : rows) table.addRow(std::move(row));
    table.appendTo(out);
  }
  if (!notHeard.empty()) {
    out += "\n";
    notHeard.appendTo(out);
  }
  streams.out.write(out);
  if (!silent.empty()) {
    std::string message;
    for (const std::string& line : silent) message += (message.empty() ? "" : ", ") + line;
    reportError(streams.err, message + " (no heartbeat on LCM or in the signal table)");
    return ExitCode::Failure;
  }
  return ExitCode::Ok;
}

ExitCode runSpy(const SpyOptions& options, Streams streams) {
  std::string url = options.lcmUrl;
  const bool configNamed =
      !options.stack.configPath.empty() || std::getenv(std::string(CONFIG_ENVIRONMENT_VARIABLE).c_str()) != nullptr;
  if (url.empty() && configNamed) {
    ExitCode exitCode = ExitCode::Ok;
    const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
    if (!maybeStack) return exitCode;
    url = maybeStack->config.lcmUrl;
  }
  if (url.empty()) url = std::string(ipc::DEFAULT_EVENT_URL);
  const std::string script = OPENVCU_LCM_SPY_SCRIPT;
  if (::access(script.c_str(), X_OK) != 0) {
    reportError(streams.err, "cannot run " + script + " (lcm-spy wrapper of shared/ipc)");
    return ExitCode::Failure;
  }
  std::string jar = options.typesJar;
  if (jar.empty() && ::access(OPENVCU_LCM_TYPES_JAR, R_OK) == 0) jar = OPENVCU_LCM_TYPES_JAR;
  std::vector<std::string> argv{script, "--lcm-url", url};
  if (!jar.empty()) {
    argv.emplace_back("--types");
    argv.push_back(jar);
  }
  if (options.dryRun) {
    std::string line;
    for (const std::string& argument : argv) line += (line.empty() ? "" : " ") + shellQuoted(argument);
    streams.out.write(line + "\n");
    return ExitCode::Ok;
  }
  streams.out.flush();
  streams.err.flush();
  const IgnoreInterruptsScope ignoreInterrupts;
  pid_t pid = -1;
  const int rc = spawnProcess(argv, {SIGINT, SIGQUIT}, false, &pid);
  if (rc != 0) {
    reportError(streams.err, "cannot start " + script + ": " + std::strerror(rc));
    return ExitCode::Failure;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return ExitCode::Ok;
  reportError(streams.err,
              "lcm-spy ended with " + (WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                                         : "signal " + std::to_string(WTERMSIG(status))));
  return ExitCode::Failure;
}

void registerStatusCommands(CLI::App& app, CommandContext& context) {
  addStatus(app, context);
  addSpy(app, context);
}

}  // namespace openvcu::cli
