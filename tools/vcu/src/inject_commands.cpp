// `vcu inject`: frame faults through vcu-ecu-sim, process faults by signal. The descriptions
// and footers are its manual.
#include "inject_commands.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "diagnostics.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/command_socket.hpp"

namespace openvcu::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* INJECT_DESCRIPTION =
    "Inject a fault from outside the VCU's code paths: on the simulated bus (vcu-ecu-sim) or into a process";
constexpr const char* INJECT_FOOTER =
    "Frame faults change what the simulated vehicle (vcu-ecu-sim) sends, per DBC message or\n"
    "per node; the VCU's own frames are never touched. Each is a SimFault command with the\n"
    "key KIND.TARGET[=PARAM], acknowledged once vcu-ecu-sim has applied it (it logs and\n"
    "publishes the LCM fault sim.KIND.TARGET with the exact time). --off clears it.\n"
    "Every answer carries two time stamps, CLOCK_MONOTONIC and CLOCK_REALTIME in ns:\n"
    "'requested' (just before the command left) and 'acknowledged' (the answer came); the\n"
    "fault took effect between them. Process faults are stamped just before the signal.\n"
    "--json prints one JSON object instead of the text line.\n"
    "\n"
    "Examples:\n"
    "  vcu inject silence HVESSS1_PGN4336 --config config/hhea/vehicle.json\n"
    "  vcu inject delay VIC --ms 300          (every frame of the node 300 ms late)\n"
    "  vcu inject corrupt PDU_Tx_1 --xor 01   (bit 0 of byte 0 flipped)\n"
    "  vcu inject replay HVESSS1_PGN4336 --age 2000\n"
    "  vcu inject spoof PDU --from 0x30       vcu inject claim 0x21\n"
    "  vcu inject babble vehicle --load 30    vcu inject delay VIC --off\n"
    "  vcu inject process stop fsm --json     vcu inject process cont fsm\n"
    "Exit: 0 applied, 1 refused, no answer, no such process or configuration error, 2 usage error.\n";

constexpr const char* PROCESS_FOOTER =
    "SERVICE is a service name (fsm runs as vcu-fsm, can-tx as vcu-can-tx, ...), roudi\n"
    "(iox-roudi) or supervisor (supervisord). The process is found by its executable's name\n"
    "among this user's processes; several matches are refused with their pids unless --pid\n"
    "names one of them. Prints the pid and the time stamps taken just before the signal.\n"
    "\n"
    "Examples:\n"
    "  vcu inject process stop fsm            (SIGSTOP: the service hangs)\n"
    "  vcu inject process cont fsm            (SIGCONT)\n"
    "  vcu inject process kill can-rx --json  (SIGKILL)\n"
    "  vcu inject process stop roudi --pid 4242\n";

struct Stamp {
  std::int64_t monotonicNs{};
  std::int64_t realtimeNs{};
};

Stamp now() noexcept {
  return Stamp{clock::monotonicNs(), clock::realtimeNs()};
}

/// What a process runs as: "vcu-fsm" for "fsm".
std::string executableOf(const std::string& service) {
  if (service == "roudi") return "iox-roudi";
  if (service == "supervisor") return "supervisord";
  return "vcu-" + service;
}

/// The base names a process goes by: its executable's (" (deleted)" removed, as after a
/// rebuild) and its first two command-line words' (supervisord runs as `python3 supervisord`).
std::vector<std::string> processNames(const fs::path& folder) {
  std::vector<std::string> names;
  std::error_code error;
  std::string exe = fs::read_symlink(folder / "exe", error).string();
  if (!error) {
    constexpr std::string_view DELETED = " (deleted)";
    if (exe.ends_with(DELETED)) exe.resize(exe.size() - DELETED.size());
    names.push_back(fs::path(exe).filename().string());
  }
  std::ifstream in(folder / "cmdline", std::ios::binary);
  std::string word;
  for (int i = 0; i < 2 && std::getline(in, word, '\0'); ++i) names.push_back(fs::path(word).filename().string());
  return names;
}

bool validServiceName(const std::string& service) {
  return !service.empty() && std::all_of(service.begin(), service.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
  });
}

int signalOf(const std::string& action) {
  if (action == "stop") return SIGSTOP;
  if (action == "cont") return SIGCONT;
  if (action == "kill") return SIGKILL;
  return 0;
}

std::string pidList(const std::vector<std::int32_t>& pids) {
  std::string text;
  for (const std::int32_t pid : pids) text += (text.empty() ? "" : ", ") + std::to_string(pid);
  return text;
}

}  // namespace

std::vector<std::int32_t> findServiceProcesses(const std::string& service) {
  const std::string wanted = executableOf(service);
  const auto self = static_cast<std::int32_t>(::getpid());
  std::vector<std::int32_t> pids;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator("/proc", error)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || !std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; })) continue;
    struct stat info {};
    if (::stat(entry.path().c_str(), &info) != 0 || info.st_uid != ::getuid()) continue;
    const auto pid = static_cast<std::int32_t>(std::stol(name));
    if (pid == self) continue;
    const std::vector<std::string> names = processNames(entry.path());
    // the executable's name decides; the command line only for scripts (supervisord)
    const bool match = service == "supervisor" ? std::find(names.begin(), names.end(), wanted) != names.end()
                                               : !names.empty() && names.front() == wanted;
    if (match) pids.push_back(pid);
  }
  std::sort(pids.begin(), pids.end());
  return pids;
}

ExitCode runProcessInject(const ProcessInjectOptions& options, Streams streams) {
  const int signal = signalOf(options.action);
  if (signal == 0) {
    reportError(streams.err, "expected stop, cont or kill, not '" + options.action + "'");
    return ExitCode::Usage;
  }
  if (!validServiceName(options.service)) {
    reportError(streams.err, "'" + options.service + "' is not a service name (fsm, can-tx, roudi, supervisor, ...)");
    return ExitCode::Usage;
  }
  const std::string executable = executableOf(options.service);
  const std::vector<std::int32_t> pids = findServiceProcesses(options.service);
  std::int32_t pid = 0;
  if (options.pid) {
    if (std::find(pids.begin(), pids.end(), *options.pid) == pids.end()) {
      reportError(streams.err, "pid " + std::to_string(*options.pid) + " is not a process " + executable +
                                   " of this user" + (pids.empty() ? "" : " (those are: " + pidList(pids) + ")"));
      return ExitCode::Failure;
    }
    pid = *options.pid;
  } else if (pids.empty()) {
    reportError(streams.err, "no process " + executable + " of this user is running");
    return ExitCode::Failure;
  } else if (pids.size() > 1) {
    reportError(streams.err, std::to_string(pids.size()) + " processes " + executable + " are running (pids " +
                                 pidList(pids) + "); name one with --pid");
    return ExitCode::Failure;
  } else {
    pid = pids.front();
  }
  const Stamp at = now();
  if (::kill(pid, signal) != 0) {
    reportError(streams.err,
                "cannot signal " + executable + " (pid " + std::to_string(pid) + "): " + std::strerror(errno));
    return ExitCode::Failure;
  }
  if (options.json) {
    nlohmann::ordered_json out{
        {"action", options.action},         {"service", options.service},    {"executable", executable},   {"pid", pid},
        {"signal", ::sigabbrev_np(signal)}, {"monotonicNs", at.monotonicNs}, {"realtimeNs", at.realtimeNs}};
    streams.out.write(out.dump() + "\n");
  } else {
    streams.out.write(std::string("SIG") + ::sigabbrev_np(signal) + " sent to " + executable + " (pid " +
                      std::to_string(pid) + ") at monotonic " + std::to_string(at.monotonicNs) + " ns, realtime " +
                      std::to_string(at.realtimeNs) + " ns\n");
  }
  return ExitCode::Ok;
}

std::string frameFaultKey(const FrameInjectOptions& options) {
  std::string key = options.kind + "." + options.target;
  if (!options.off && !options.parameter.empty()) key += "=" + options.parameter;
  return key;
}

namespace {

/// Sends `request` to the stack, stamped just before it leaves and when the answer comes;
/// prints the answer with both stamps (text or JSON). `hint` is added when no service owns it.
ExitCode sendStamped(const config::VehicleConfig& config, ipc::CommandRequest request, bool off, bool json,
                     double timeoutSeconds, const std::string& hint, Streams streams) {
  auto clientResult = ipc::CommandClient::connect(config.instance);
  if (!clientResult) {
    reportError(streams.err, clientResult.error().message);
    return ExitCode::Failure;
  }
  request.issuer = std::string(COMMAND_ISSUER);
  const auto timeout =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(timeoutSeconds));
  const std::string key = request.key;
  const Stamp requested = now();
  auto answer = clientResult->send(std::move(request), timeout);
  const Stamp acknowledged = now();
  if (!answer) {
    const std::string& message = answer.error().message;
    reportError(streams.err, message.starts_with("no running service answers") ? message + "; " + hint : message);
    return ExitCode::Failure;
  }
  const std::string state = off ? "off" : "on";
  if (json) {
    nlohmann::ordered_json out{{"fault", key},
                               {"state", state},
                               {"accepted", answer->accepted},
                               {"responder", answer->responder},
                               {"requestedMonotonicNs", requested.monotonicNs},
                               {"requestedRealtimeNs", requested.realtimeNs},
                               {"acknowledgedMonotonicNs", acknowledged.monotonicNs},
                               {"acknowledgedRealtimeNs", acknowledged.realtimeNs}};
    if (!answer->accepted) out["reason"] = answer->reason;
    streams.out.write(out.dump() + "\n");
  } else if (answer->accepted) {
    streams.out.write("accepted: " + key + " " + state + "; requested at monotonic " +
                      std::to_string(requested.monotonicNs) + " ns (realtime " + std::to_string(requested.realtimeNs) +
                      "), acknowledged at monotonic " + std::to_string(acknowledged.monotonicNs) + " ns (realtime " +
                      std::to_string(acknowledged.realtimeNs) + ")\n");
  } else {
    streams.out.write("refused: " + answer->reason + "\n");
  }
  return answer->accepted ? ExitCode::Ok : ExitCode::Failure;
}

}  // namespace

ExitCode runFrameInject(const FrameInjectOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  ipc::CommandRequest request;
  request.kind = ipc::CommandKind::SimFault;
  request.key = frameFaultKey(options);
  request.value = options.off ? 0 : 1;
  return sendStamped(maybeStack->config, std::move(request), options.off, options.json, options.timeoutSeconds,
                     "is vcu-ecu-sim running (frame faults need the simulated vehicle)?", streams);
}

ExitCode runGpioInject(const GpioInjectOptions& options, Streams streams) {
  if (!options.off && options.level != 0 && options.level != 1) {
    reportError(streams.err, "--level must be 0 or 1 (or --off to clear)");
    return ExitCode::Usage;
  }
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::GpioMap& map = maybeStack->config.gpio;
  const auto line = std::find_if(map.lines.begin(), map.lines.end(),
                                 [&](const config::GpioLine& l) { return l.name == options.line; });
  if (line == map.lines.end()) {
    std::string known;
    for (const config::GpioLine& l : map.lines) known += (known.empty() ? "" : ", ") + l.name;
    reportError(streams.err, "no GPIO line '" + options.line + "' (lines: " + (known.empty() ? "none" : known) + ")");
    return ExitCode::Failure;
  }
  if (line->direction == config::LineDirection::Output) {
    reportError(streams.err, "line " + options.line +
                                 " is an output: only inputs can be held stuck (the simulated chip keeps no level "
                                 "of its own for outputs)");
    return ExitCode::Failure;
  }
  if (map.backend != config::GpioBackend::Sim) {
    reportError(streams.err,
                "the GPIO map uses a real chip: stuck-at works on the simulated chip (\"backend\": \"sim\")");
    return ExitCode::Failure;
  }
  ipc::CommandRequest request;
  request.kind = options.off ? ipc::CommandKind::ClearOverride : ipc::CommandKind::SetOverride;
  request.key = "internal.gpio.sim." + options.line;
  request.value = options.off ? 0 : options.level;
  request.text = "vcu inject gpio";
  return sendStamped(maybeStack->config, std::move(request), options.off, options.json, options.timeoutSeconds,
                     "is vcu-gpio running?", streams);
}

void registerInjectCommands(CLI::App& app, CommandContext& context) {
  CLI::App* group = app.add_subcommand("inject", INJECT_DESCRIPTION);
  group->footer(INJECT_FOOTER);

  struct FrameKind {
    const char* command;
    const char* kind;
    const char* help;
    const char* targetHelp;
    const char* parameter;  ///< the option carrying PARAM, or nullptr
    const char* parameterHelp;
  };
  static constexpr FrameKind FRAME_KINDS[] = {
      {"silence", "silent", "the node or message stops sending", "a DBC message or a node", nullptr, nullptr},
      {"delay", "delay", "every frame of the node or message is sent N ms late", "a DBC message or a node", "--ms",
       "the delay in ms (1..10000)"},
      {"corrupt", "corrupt", "payload bits flipped (XOR) in every frame of the node or message",
       "a DBC message or a node", "--xor", "hex bytes XORed into the payload from byte 0 (default: every bit)"},
      {"replay", "replay", "the frame sent N ms ago is sent again in place of every new one", "a DBC message", "--age",
       "how old the replayed frame is, ms (1..10000)"},
      {"spoof", "spoof", "the node's or message's frames go out from another source address",
       "a DBC message or a node (29-bit identifiers)", "--from", "the source address, 0..253 (0x.. hex too)"},
      {"claim", "claim", "one Address Claimed for ADDRESS with a NAME of higher priority than the VCU's",
       "the address, 0..253 (0x21 or 33)", nullptr, nullptr},
      {"babble", "babble", "a node sends frames at priority 0 filling N % of the bus's bit rate", "a bus name",
       "--load", "the bus load in % (above 0, at most 100)"},
  };
  for (const FrameKind& kind : FRAME_KINDS) {
    auto options = std::make_shared<FrameInjectOptions>();
    options->kind = kind.kind;
    CLI::App* command = group->add_subcommand(kind.command, kind.help);
    command->footer(INJECT_FOOTER);
    command->add_option("TARGET", options->target, kind.targetHelp)->required();
    if (kind.parameter != nullptr) command->add_option(kind.parameter, options->parameter, kind.parameterHelp);
    command->add_flag("--off", options->off, "clear this fault");
    command->add_flag("--json", options->json, "print the answer and its time stamps as one JSON object");
    command->add_option("--timeout", options->timeoutSeconds, "seconds to wait for the acknowledgement")
        ->check(CLI::PositiveNumber);
    addStackOptions(*command, options->stack);
    const bool needsParameter = kind.parameter != nullptr && std::string_view(kind.kind) != "corrupt";
    const std::string parameterName = kind.parameter != nullptr ? kind.parameter : "";
    command->callback([options, &context, needsParameter, parameterName] {
      if (needsParameter && !options->off && options->parameter.empty()) {
        reportError(context.streams.err, parameterName + " is required (or --off to clear)");
        context.exitCode = ExitCode::Usage;
        return;
      }
      context.exitCode = runFrameInject(*options, context.streams);
    });
  }

  auto gpio = std::make_shared<GpioInjectOptions>();
  CLI::App* gpioCommand = group->add_subcommand("gpio", "an input line of the simulated GPIO chip stuck at 0 or 1");
  gpioCommand->footer(
      "Holds the electrical level of an input line of the simulated chip (internal.gpio.sim.LINE)\n"
      "with an operator override that vcu-gpio answers, until --off clears it. Outputs and real\n"
      "chips are refused. Prints the requested and acknowledged time stamps.\n"
      "\n"
      "Examples:\n"
      "  vcu inject gpio ContactorFault --level 1\n"
      "  vcu inject gpio ContactorFault --off\n");
  gpioCommand->add_option("LINE", gpio->line, "the line's name in gpio.json")->required();
  gpioCommand->add_option("--level", gpio->level, "the stuck level, 0 or 1");
  gpioCommand->add_flag("--off", gpio->off, "release the line");
  gpioCommand->add_flag("--json", gpio->json, "print the answer and its time stamps as one JSON object");
  gpioCommand->add_option("--timeout", gpio->timeoutSeconds, "seconds to wait for the acknowledgement")
      ->check(CLI::PositiveNumber);
  addStackOptions(*gpioCommand, gpio->stack);
  gpioCommand->callback([gpio, &context] { context.exitCode = runGpioInject(*gpio, context.streams); });

  auto process = std::make_shared<ProcessInjectOptions>();
  CLI::App* processCommand =
      group->add_subcommand("process", "SIGSTOP (hang), SIGCONT or SIGKILL a service, iox-roudi or supervisord");
  processCommand->footer(PROCESS_FOOTER);
  processCommand->add_option("ACTION", process->action, "stop, cont or kill")->required();
  processCommand->add_option("SERVICE", process->service, "fsm, can-rx, ..., roudi, supervisor")->required();
  processCommand->add_option("--pid", process->pid, "the process, when several run");
  processCommand->add_flag("--json", process->json, "print the pid and time stamps as one JSON object");
  processCommand->callback([process, &context] { context.exitCode = runProcessInject(*process, context.streams); });
  group->require_subcommand(1);
}

}  // namespace openvcu::cli
