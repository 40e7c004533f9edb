// Injecting one fault of a safety case into a running stack, and taking it back (vcu safety campaign).
#include "safety_campaign_inject.hpp"

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <vector>

#include "inject_commands.hpp"
#include "openvcu/core/clock.hpp"
#include "sim_commands.hpp"

namespace openvcu::cli {
namespace {

/// `vcu inject` and `vcu sim fault` answer on captured streams; their text names a failure.
struct Captured {
  StringSink out;
  StringSink err;
  [[nodiscard]] Streams streams() { return Streams{out, err}; }
  [[nodiscard]] std::string failure(const std::string& what) const {
    std::string text = what + ": " + (err.text().empty() ? out.text() : err.text());
    while (!text.empty() && text.back() == '\n') text.pop_back();
    return text;
  }
};

}  // namespace

FaultInjector::FaultInjector(const Stack& stack, const StackOptions& stackOptions, StatePlanner& planner,
                             Sink& warnings)
    : m_stack(stack), m_stackOptions(stackOptions), m_planner(planner), m_warnings(warnings) {}

std::string FaultInjector::whyNot(const safety::Injection& fault) const {
  using safety::InjectKind;
  switch (fault.kind) {
    case InjectKind::Babble:
      for (const config::BusConfig& bus : m_stack.config.buses) {
        if (bus.name == fault.bus && bus.link.kind == config::LinkKind::Sim) {
          return "babble on bus " + bus.name +
                 ": the simulated bus does not arbitrate, so a babbling node delays no other frame (it raises only "
                 "the load the receivers compute); inject it on a SocketCAN bus";
        }
      }
      return {};
    case InjectKind::Silence:
    case InjectKind::Delay:
    case InjectKind::Replay:
    case InjectKind::Spoof:
    case InjectKind::AddressClaim:
    case InjectKind::BusOff:
    case InjectKind::Kill:
    case InjectKind::Stop:
    case InjectKind::GpioStuck:
    case InjectKind::SimFault:
      return {};
    case InjectKind::Corrupt:
      if (fault.validCrc.value_or(false))
        return "corrupt with a valid J1939-76 CRC: vcu inject corrupt has no such mode";
      return {};
    case InjectKind::FreezeCounter:
      return "freezeCounter: vcu inject has no frozen sequence counter";
    case InjectKind::Signal: {
      const auto index = m_stack.catalog.indexOf(fault.signal);
      if (!index) return "signal " + fault.signal + ": not a signal of this vehicle";
      const signals::SignalInfo& info = m_stack.catalog[*index];
      if (info.kind == signals::SignalKind::Bus && info.direction == signals::SignalDirection::Received) {
        return "signal " + fault.signal +
               ": another node sends it; the campaign cannot make a simulated node report "
               "a value";
      }
      if (info.reported) return "signal " + fault.signal + ": a status the stack reports; no command sets it";
      return {};
    }
  }
  return std::string(safety::injectKindName(fault.kind)) + ": unknown injection";
}

std::optional<AppliedFault> FaultInjector::inject(const safety::Injection& fault, InjectionStamp* stamp,
                                                  std::string* error) {
  using safety::InjectKind;
  Captured captured;
  auto failed = [&](const std::string& what) {
    *error = captured.failure(what);
    return std::nullopt;
  };
  if (fault.kind == InjectKind::Signal) return injectSignal(fault, stamp, error);
  if (fault.kind == InjectKind::Kill || fault.kind == InjectKind::Stop) {
    ProcessInjectOptions process;
    process.action = fault.kind == InjectKind::Kill ? "kill" : "stop";
    process.service = fault.service;
    process.json = true;
    if (runProcessInject(process, captured.streams()) != ExitCode::Ok)
      return failed("process " + process.action + " " + fault.service);
    const auto answer = nlohmann::json::parse(captured.out.text(), nullptr, false);
    if (answer.is_discarded()) return failed("process " + process.action);
    *stamp = InjectionStamp{answer.value("monotonicNs", std::int64_t{}), answer.value("realtimeNs", std::int64_t{})};
    const auto pid = answer.value("pid", std::int32_t{});
    const std::string executable = answer.value("executable", std::string());
    AppliedFault applied{std::string(fault.kind == InjectKind::Kill ? "SIGKILL " : "SIGSTOP ") + executable + " (pid " +
                             std::to_string(pid) + ")",
                         {}};
    if (fault.kind == InjectKind::Stop) {
      const std::string service = fault.service;
      applied.clear = [service, pid] {
        ProcessInjectOptions resume{.action = "cont", .service = service, .pid = pid, .json = true};
        StringSink ignoredOut;
        StringSink ignoredErr;
        (void)runProcessInject(resume, Streams{ignoredOut, ignoredErr});  // gone: killed and restarted
      };
    }
    return applied;
  }
  if (fault.kind == InjectKind::SimFault) {
    // `vcu sim fault NAME on`: a fault the simulated node detects and reports itself; its
    // answer carries no stamps, so the stamp is taken just before the request left
    SimFaultOptions sim;
    sim.stack.configPath = m_stack.config.path;
    sim.stack.instance = m_stack.config.instance;
    sim.name = fault.name;
    *stamp = InjectionStamp{clock::monotonicNs(), clock::realtimeNs()};
    if (runSimFault(sim, captured.streams()) != ExitCode::Ok) return failed("sim fault " + fault.name);
    return AppliedFault{"sim fault " + fault.name, [sim]() mutable {
                          sim.state = "off";
                          StringSink ignoredOut;
                          StringSink ignoredErr;
                          (void)runSimFault(sim, Streams{ignoredOut, ignoredErr});
                        }};
  }
  if (fault.kind == InjectKind::GpioStuck) {
    // `vcu inject gpio`: an override of the simulated input, released with --off
    GpioInjectOptions gpio;
    gpio.stack.configPath = m_stack.config.path;
    gpio.stack.instance = m_stack.config.instance;
    gpio.line = fault.line;
    gpio.level = fault.level.value_or(false) ? 1 : 0;
    gpio.json = true;
    if (runGpioInject(gpio, captured.streams()) != ExitCode::Ok) return failed("inject gpio " + fault.line);
    const auto answer = nlohmann::json::parse(captured.out.text(), nullptr, false);
    if (answer.is_discarded()) return failed("inject gpio " + fault.line);
    *stamp = InjectionStamp{answer.value("requestedMonotonicNs", std::int64_t{}),
                            answer.value("requestedRealtimeNs", std::int64_t{})};
    return AppliedFault{"gpio " + fault.line + "=" + std::to_string(gpio.level), [gpio]() mutable {
                          gpio.off = true;
                          StringSink ignoredOut;
                          StringSink ignoredErr;
                          (void)runGpioInject(gpio, Streams{ignoredOut, ignoredErr});
                        }};
  }
  FrameInjectOptions frame;
  frame.stack = m_stackOptions;
  frame.stack.configPath = m_stack.config.path;
  frame.stack.instance = m_stack.config.instance;
  frame.json = true;
  // a frame fault names one message, else every message of a node
  const std::string messageOrNode = fault.message.empty() ? fault.node : fault.message;
  switch (fault.kind) {
    case InjectKind::Silence:
      frame.kind = "silent";
      frame.target = messageOrNode;
      break;
    case InjectKind::Delay:
      frame.kind = "delay";
      frame.target = messageOrNode;
      frame.parameter = std::to_string(fault.delayMs.value_or(0));
      break;
    case InjectKind::Corrupt:
      frame.kind = "corrupt";
      frame.target = messageOrNode;
      break;
    case InjectKind::Replay:
      frame.kind = "replay";
      frame.target = fault.message;
      frame.parameter = std::to_string(fault.delayMs.value_or(2000));
      break;
    case InjectKind::Spoof:
      frame.kind = "spoof";
      frame.target = messageOrNode;
      frame.parameter = std::to_string(fault.address.value_or(0));
      break;
    case InjectKind::Babble:
      frame.kind = "babble";
      frame.target = fault.bus;
      frame.parameter = formatNumber(fault.loadPercent.value_or(100));
      break;
    case InjectKind::AddressClaim:
      frame.kind = "claim";
      frame.target = std::to_string(fault.address.value_or(0));
      break;
    case InjectKind::BusOff:
      // vcu-ecu-sim cuts the simulated bus both ways: no node's frame reaches the VCU, no
      // frame of the VCU reaches a node
      frame.kind = "busoff";
      frame.target = fault.bus;
      break;
    default:
      *error = std::string(safety::injectKindName(fault.kind)) + ": cannot be injected";
      return std::nullopt;
  }
  if (runFrameInject(frame, captured.streams()) != ExitCode::Ok) return failed("inject " + frameFaultKey(frame));
  const auto answer = nlohmann::json::parse(captured.out.text(), nullptr, false);
  if (answer.is_discarded()) return failed("inject " + frameFaultKey(frame));
  // the fault took effect between the request and the answer: the request is the earlier bound
  *stamp = InjectionStamp{answer.value("requestedMonotonicNs", std::int64_t{}),
                          answer.value("requestedRealtimeNs", std::int64_t{})};
  const std::string key = frameFaultKey(frame);
  if (frame.kind == "claim") return AppliedFault{key, [this] { restartCanTx(); }};
  return AppliedFault{key, [frame]() mutable {
                        frame.off = true;
                        StringSink ignoredOut;
                        StringSink ignoredErr;
                        (void)runFrameInject(frame, Streams{ignoredOut, ignoredErr});
                      }};
}

/// The signal's owner writes it (its writer id in the table, its ownership checks), as for
/// `vcu signal set`; cleared by writing back the value it had (or the FSM's initial value).
std::optional<AppliedFault> FaultInjector::injectSignal(const safety::Injection& fault, InjectionStamp* stamp,
                                                        std::string* error) {
  const auto index = m_stack.catalog.indexOf(fault.signal);
  if (!index) {
    *error = "signal " + fault.signal + ": not a signal of this vehicle";
    return std::nullopt;
  }
  const double value = fault.value.value_or(1);
  const double before = m_planner.valueOf(*index).value_or(0);
  const InjectionStamp requested{clock::monotonicNs(), clock::realtimeNs()};
  if (!m_planner.setSignal(fault.signal, value)) {
    *error = "signal " + fault.signal + " = " + formatNumber(value) + ": not accepted (see the warning above)";
    return std::nullopt;
  }
  // the owner answered once the value was in the table: its write stamp is when it took
  // effect (CLOCK_REALTIME moved on by the same amount since the request)
  *stamp = requested;
  if (const auto written = m_planner.read(*index);
      written && written->value == value && written->timestampNs >= requested.monotonicNs) {
    *stamp =
        InjectionStamp{written->timestampNs, requested.realtimeNs + (written->timestampNs - requested.monotonicNs)};
  }
  const std::string key = fault.signal;
  return AppliedFault{key + "=" + formatNumber(value), [this, key, before] { (void)m_planner.setSignal(key, before); }};
}

/// J1939-81 gives a node that lost its address no retry: vcu-can-tx claims again when it
/// starts. With a supervisord running it is killed and waited for until it beats again.
void FaultInjector::restartCanTx() {
  const std::string service = "can-tx";
  if (findServiceProcesses("supervisor").empty()) {
    m_warnings.write("vcu: warning: the VCU's J1939 address stays lost: no supervisord runs to start vcu-" + service +
                     " again (restart it by hand)\n");
    return;
  }
  const std::vector<std::int32_t> before = findServiceProcesses(service);
  ProcessInjectOptions kill{.action = "kill", .service = service, .pid = std::nullopt, .json = true};
  Captured captured;
  const std::int64_t killedNs = clock::monotonicNs();
  if (runProcessInject(kill, captured.streams()) != ExitCode::Ok) {
    m_warnings.write("vcu: warning: " + captured.failure("restarting vcu-" + service) + "\n");
    return;
  }
  const auto beat = m_stack.catalog.indexOf("internal.service." + service + ".heartbeat");
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                             std::chrono::duration<double>(RESTART_WAIT_SECONDS));
  const bool back = beat && m_planner.waitUntil(
                                [&] {
                                  const auto reading = m_planner.read(*beat);
                                  if (!reading || reading->timestampNs <= killedNs) return false;
                                  const auto now = findServiceProcesses(service);
                                  return std::any_of(now.begin(), now.end(), [&](std::int32_t pid) {
                                    return std::find(before.begin(), before.end(), pid) == before.end();
                                  });
                                },
                                deadline);
  if (!back) {
    m_warnings.write("vcu: warning: vcu-" + service + " did not beat again within " +
                     formatNumber(RESTART_WAIT_SECONDS) + " s of its restart\n");
  }
}

}  // namespace openvcu::cli
