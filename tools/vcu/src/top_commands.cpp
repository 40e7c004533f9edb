// `vcu top`. The description and footer are its manual.
#include "top_commands.hpp"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "cli_checks.hpp"
#include "diagnostics.hpp"
#include "openvcu/config/dashboard.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/display/health.hpp"
#include "openvcu/display/values.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/service/process_stats.hpp"
#include "openvcu/signals/table.hpp"
#include "stop_signal.hpp"
#include "text_table.hpp"

namespace openvcu::cli {
namespace {

/// A percentile of vcu-can-tx's error histograms (tx.<Msg>.period_err_p99_us) as text, with
/// the resolution it has: 1 us up to 2,048 us, then 32 buckets per doubling (the middle of
/// its bucket, within 1.6 %) up to 2^24 us; a percentile beyond that reads as 2^24 us and
/// means "at least 16.8 s" (services/can-tx/src/error_histogram.hpp, issue 27).
std::string txPercentileText(std::int64_t micros) {
  constexpr std::int64_t LINEAR_US = 2048;
  constexpr std::int64_t RANGE_US = std::int64_t{1} << 24;
  if (micros >= RANGE_US) return "beyond the histogram's 16.8 s range (see the max)";
  if (micros >= LINEAR_US) return std::to_string(micros) + " us (+-1.6 %)";
  return std::to_string(micros) + " us";
}

constexpr const char* TOP_DESCRIPTION = "Live view of a running stack: services, FSM state, key signals, faults";
constexpr const char* TOP_FOOTER =
    "Refreshes once a second until Ctrl-C (or --for SECONDS): the services heard on the\n"
    "heartbeat channel (pid, uptime, restarts seen while top runs, heartbeat age, CPU %\n"
    "since the last table (\"-\" until two samples of it lie 0.2 s apart) and RSS of local\n"
    "processes, status; the stack's own services and every service whose heartbeat slot in\n"
    "the signal table was written are listed even when not heard: 'silent for N s' once\n"
    "they beat before and not for 2.5 s, 'not heard' when they never did), the FSM state\n"
    "and how long it has held (while vcu-fsm is silent: the last state, marked as not\n"
    "current: 'Driving — vcu-fsm silent 4.02 s'), the\n"
    "vehicle's key signals from its dashboard.json (BATTERY: SOC, voltage, current,\n"
    "charger; STATUS: the HMI's status keys), the GPIO lines, each bus's load, can-tx's\n"
    "worst period error p99 and the active faults (LCM fault events since top started,\n"
    "and service_silent.<name> (source heartbeats) for every silent service no event\n"
    "names).\n"
    "--once prints one snapshot\n"
    "after 1.5 s without clearing the screen.\n"
    "The stack: --config FILE or $OPENVCU_CONFIG, --instance NAME.\n"
    "\n"
    "Examples:\n"
    "  vcu top --config config/hhea/vehicle.json\n"
    "  vcu top --once --config config/hhea/vehicle.json\n"
    "Exit: 0 shown, 1 configuration error or no stack heard, 2 usage error.\n";

struct ServiceView {
  ipc::Heartbeat last;
  std::int32_t firstPid{};
  int restarts{};
  std::int64_t cpuTicks{-1};
  double cpuPercent{};
  bool cpuMeasured{};  ///< cpuPercent spans two samples of this pid (else the table says "-")
  std::chrono::steady_clock::time_point cpuAt;
};

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << value;
  return out.str();
}

class Top {
 public:
  Top(const Stack& stack, Streams streams)
      : m_stack(stack),
        m_streams(streams),
        m_health(display::expectedServices(), display::HEARTBEAT_STALE_NS),
        m_slots(stack.catalog) {
    loadStateNames();
    loadDashboard();
  }

  Status open() {
    auto events = ipc::EventBus::open(m_stack.config.lcmUrl, m_stack.config.instance);
    if (!events) return events.error();
    m_events.emplace(std::move(*events));
    auto heartbeats = m_events->onHeartbeat([this](const ipc::Heartbeat& beat) { onHeartbeat(beat); });
    auto faults = m_events->onFault([this](const ipc::FaultEvent& fault) {
      if (fault.active) {
        m_faults[fault.name] = fault;
      } else {
        m_faults.erase(fault.name);
      }
    });
    // can-tx's per-message timing, for the TX TIMING line
    auto stats = m_events->onStats([this](const ipc::Stats& part) {
      if (part.service != "vcu-can-tx") return;
      if (part.pid != m_txStatsPid) m_txStats.clear();
      m_txStatsPid = part.pid;
      for (const ipc::Counter& counter : part.counters) m_txStats[counter.name] = counter.value;
    });
    if (!heartbeats) return heartbeats.error();
    if (!stats) return stats.error();
    if (!faults) return faults.error();
    return {};
  }

  /// Handles events for `duration` (or until a stop is requested).
  void listen(std::chrono::milliseconds duration) {
    const auto end = std::chrono::steady_clock::now() + duration;
    while (!stopRequested()) {
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
      if (left.count() <= 0) break;
      if (m_events->handle(left) == ipc::HandleResult::Failed) break;
    }
  }

  /// A heartbeat heard, or a beat in a heartbeat slot of the table.
  [[nodiscard]] bool heardAny() const {
    return std::any_of(m_health.services().begin(), m_health.services().end(),
                       [](const display::ServiceHealth& service) { return service.lastBeatMonoNs >= 0; });
  }

  std::string render() {
    if (!m_table) {
      auto table = signals::SignalTable::open(m_stack.catalog, m_stack.config.instance, signals::OpenMode::AttachOnly);
      if (table) m_table.emplace(std::move(*table));
    }
    if (m_table) m_slots.feed(m_health, *m_table);
    std::string out =
        "openvcu top: instance " + m_stack.config.instance + ", " + formatUtc(clock::realtimeNs()) + "\n\n";
    services(out);
    out += "\n";
    vehicle(out);
    faults(out);
    return out;
  }

 private:
  void onHeartbeat(const ipc::Heartbeat& beat) {
    m_health.onHeartbeat(beat, clock::monotonicNs());
    ServiceView& view = m_services[beat.service];
    if (view.firstPid == 0) view.firstPid = beat.pid;
    if (view.last.pid != 0 && view.last.pid != beat.pid) ++view.restarts;
    if (view.last.pid != beat.pid) {
      view.cpuMeasured = false;
      // the first CPU sample when a process is first heard, so that the next table (--once:
      // at 1.5 s) can already give its CPU
      view.cpuTicks = service::processCpuTicks(beat.pid);
      view.cpuAt = std::chrono::steady_clock::now();
    }
    view.last = beat;
  }

  [[nodiscard]] std::string livenessText(const display::ServiceHealth& service, std::int64_t nowMono) const {
    return cli::livenessText(m_health, service, nowMono);
  }

  void services(std::string& out) {
    const std::int64_t nowMono = clock::monotonicNs();
    const auto clock = std::chrono::steady_clock::now();
    const double ticksPerSecond = service::clockTicksPerSecond();
    TextTable table({"SERVICE", "PID", "UPTIME", "RESTARTS", "BEAT", "CPU %", "RSS MB", "STATUS"});
    for (const display::ServiceHealth& health : m_health.services()) {
      const std::string liveness = livenessText(health, nowMono);
      const std::string beat = health.lastBeatMonoNs >= 0
                                   ? formatDuration(std::max<std::int64_t>(0, nowMono - health.lastBeatMonoNs)) +
                                         (liveness.empty() ? "" : " SILENT")
                                   : "never";
      const auto found = m_services.find(health.name);
      if (found == m_services.end()) {  // known from the table or the configuration only
        table.addRow(
            {health.name, "-", "-", "-", beat, "-", "-", liveness.empty() ? "beating (table slot only)" : liveness});
        continue;
      }
      ServiceView& view = found->second;
      const std::int64_t ticks = liveness.empty() ? service::processCpuTicks(view.last.pid) : -1;
      if (ticks >= 0 && view.cpuTicks >= 0) {
        const double seconds = std::chrono::duration<double>(clock - view.cpuAt).count();
        if (seconds > 0.2) {
          view.cpuPercent = static_cast<double>(ticks - view.cpuTicks) / ticksPerSecond / seconds * 100;
          view.cpuMeasured = true;
          view.cpuTicks = ticks;
          view.cpuAt = clock;
        }
      } else if (ticks >= 0) {
        view.cpuTicks = ticks;
        view.cpuAt = clock;
      }
      const double rss = service::processRssMb(view.last.pid);
      std::string status = view.last.status.empty() ? "-" : view.last.status;
      if (!liveness.empty()) status = liveness + " (last: " + status + ")";
      table.addRow({health.name, std::to_string(view.last.pid), formatDuration(view.last.uptimeMs * 1'000'000),
                    std::to_string(view.restarts), beat,
                    ticks >= 0 && view.cpuMeasured ? fixed(view.cpuPercent, 1) : "-", rss >= 0 ? fixed(rss, 1) : "-",
                    status});
    }
    table.appendTo(out);
  }

  /// "60 %" or the value text, or "-" when unknown; `stale` marks old bus values.
  std::string value(const std::string& key) const {
    const auto index = m_stack.catalog.indexOf(key);
    if (!m_table || !index) return "-";
    const auto slot = m_table->read(*index);
    if (!slot) return "-";
    // two decimals are enough on a status screen (650.35 V, not 650.3500000000001 V)
    const auto shown = [](double value) { return std::round(value * 100) / 100; };
    if (const auto command = signals::effectiveCommand(*slot))
      return formatValue(m_stack.catalog[*index], shown(command->value));
    if (slot->bus.updates == 0) return "never";
    std::string text = formatValue(m_stack.catalog[*index], shown(slot->bus.value));
    if (slot->bus.quality != signals::Quality::Valid)
      text += " (" + std::string(signals::qualityName(slot->bus.quality)) + ")";
    return text;
  }

  void vehicle(std::string& out) {
    if (!m_table) {
      out += "(no signal table yet)\n";
      return;
    }
    std::string state = "-";
    if (const auto index = m_stack.catalog.indexOf("internal.fsm.state")) {
      if (const auto bus = m_table->readBus(*index); bus && bus->updates > 0) {
        const auto number = static_cast<std::size_t>(bus->value);
        state = number < m_stateNames.size() ? m_stateNames[number] : std::to_string(number);
        const display::ServiceHealth* fsm = m_health.find("vcu-fsm");
        const std::string liveness = fsm != nullptr ? livenessText(*fsm, clock::monotonicNs()) : "not heard";
        if (liveness.empty()) {
          state += " (for " + formatDuration(clock::monotonicNs() - bus->timestampNs) + ")";
        } else {  // the last state of a writer that does not beat: not the current one
          state += " — vcu-fsm " + liveness + " (last state written, not current)";
        }
      }
    }
    out += "FSM         " + state + "\n";
    keySignals(out);
    std::string gpio;
    for (const config::GpioLine& lineSpec : m_stack.config.gpio.lines) {
      gpio += lineSpec.name + " " + value(lineSpec.statusKey()) + "   ";
    }
    if (!gpio.empty()) out += "GPIO        " + gpio + "\n";
    std::string buses;
    for (const config::BusConfig& bus : m_stack.config.buses) {
      buses += bus.name + " load " + value("internal.bus." + bus.name + ".load") + ", " +
               value("internal.bus." + bus.name + ".state") + "   ";
    }
    out += "BUSES       " + buses + "\n";
    {
      std::int64_t worst = -1;
      std::string which;
      for (const auto& [name, micros] : m_txStats) {
        if (name.ends_with(".period_err_p99_us") && micros > worst) {
          worst = micros;
          which = name.substr(3, name.size() - 3 - std::string(".period_err_p99_us").size());
        }
      }
      if (worst >= 0) out += "TX TIMING   worst period error p99 " + txPercentileText(worst) + " (" + which + ")\n";
    }
  }

  /// The vehicle's key signals from its dashboard (dashboard.json beside vehicle.json, as
  /// vcu-hmi shows them): BATTERY = the header's SOC, the voltage and current dials and the
  /// charger; STATUS = the Vehicle tab's status keys, labelled as the dashboard's items (else
  /// transmitter and signal), wrapped at about 100 columns. Nothing here names one vehicle's signal.
  void keySignals(std::string& out) {
    if (!m_dashboardError.empty()) {
      out += "DASHBOARD   not loaded: " + m_dashboardError + "\n";
      return;
    }
    if (!m_dashboard) return;
    std::string battery;
    for (const auto& [name, key] :
         {std::pair{"SOC", &m_dashboard->socKey}, std::pair{"U", &m_dashboard->voltageKey},
          std::pair{"I", &m_dashboard->currentKey}, std::pair{"charger", &m_dashboard->chargerKey}}) {
      if (!key->empty()) battery += std::string(name) + " " + value(*key) + "   ";
    }
    if (!battery.empty()) out += "BATTERY     " + battery + "\n";
    std::string line;
    const char* label = "STATUS      ";
    for (const std::string& key : m_dashboard->statusKeys) {
      const std::string item = statusLabel(key) + " " + value(key) + "   ";
      if (!line.empty() && line.size() + item.size() > 88) {
        out += label + line + "\n";
        label = "            ";
        line.clear();
      }
      line += item;
    }
    if (!line.empty()) out += label + line + "\n";
  }

  /// A status key's label: the dashboard item's for the same key, else transmitter and
  /// signal as vcu-hmi's Vehicle tab labels it ("HVLP_SA72 InverterStatus", "relay Cl15"):
  /// several senders of one message name stay apart.
  [[nodiscard]] std::string statusLabel(const std::string& key) const {
    for (const config::DashboardItem& item : m_dashboard->items) {
      if (item.key == key) return item.label;
    }
    return display::shortLabel(key);
  }

  void loadDashboard() {
    const std::string path = config::dashboardBeside(m_stack.config.path);
    if (path.empty()) return;
    auto dashboard = config::loadDashboardConfig(path, m_stack.catalog);
    if (!dashboard) {
      m_dashboardError = formatDiagnostic(dashboard.error());
      return;
    }
    m_dashboard.emplace(std::move(*dashboard));
  }

  /// The fault events heard, then service_silent.<name> of every silent service no event
  /// names (vcu-watchdog raises the same name when it runs).
  void faults(std::string& out) {
    out += "\nFAULTS      ";
    std::vector<ipc::FaultEvent> shown;
    for (const auto& [name, fault] : m_faults) shown.push_back(fault);
    for (ipc::FaultEvent& silent : m_health.silentFaults(clock::monotonicNs(), clock::realtimeNs())) {
      if (!display::namesFault(shown, silent.name)) shown.push_back(std::move(silent));
    }
    if (shown.empty()) {
      out += "none active\n";
      return;
    }
    out += "\n";
    for (const ipc::FaultEvent& fault : shown) {
      out += "  " + fault.name + " (" + fault.source + ", " + std::string(display::faultSeverityName(fault.severity)) +
             ", since " + formatDuration(std::max<std::int64_t>(0, clock::realtimeNs() - fault.timestampNs)) +
             "): " + fault.text + "\n";
    }
  }

  void loadStateNames() {
    if (m_stack.config.fsmFile.empty()) return;
    auto json = config::readJsonFile(m_stack.config.fsmFile);
    if (!json || !json->is_object() || !json->contains("states") || !(*json)["states"].is_array()) return;
    for (const auto& state : (*json)["states"]) {
      m_stateNames.push_back(state.is_object() && state.contains("name") && state["name"].is_string()
                                 ? state["name"].get<std::string>()
                                 : "?");
    }
  }

  const Stack& m_stack;
  Streams m_streams;
  std::optional<ipc::EventBus> m_events;
  std::optional<signals::SignalTable> m_table;
  std::map<std::string, ServiceView> m_services;
  display::HealthTracker m_health;  ///< every service's liveness, from heartbeats and the table's slots
  display::HeartbeatSlots m_slots;
  std::map<std::string, std::int64_t> m_txStats;  ///< vcu-can-tx's latest statistics by name
  std::int32_t m_txStatsPid{};
  std::map<std::string, ipc::FaultEvent> m_faults;
  std::vector<std::string> m_stateNames;
  std::optional<config::DashboardConfig> m_dashboard;
  std::string m_dashboardError;  ///< why dashboard.json did not load
};

}  // namespace

ExitCode runTop(const TopOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  Top top(*maybeStack, streams);
  if (Status opened = top.open(); !opened) {
    reportError(streams.err, opened.error().message);
    return ExitCode::Failure;
  }
  const StopSignalScope stopScope;
  if (options.once) {
    top.listen(std::chrono::milliseconds(750));
    (void)top.render();  // the first CPU sample
    top.listen(std::chrono::milliseconds(750));
    streams.out.write(top.render());
    if (!top.heardAny()) {
      reportError(streams.err,
                  "no heartbeat within 1.5 s (is the stack running? events: " + maybeStack->config.lcmUrl + ")");
      return ExitCode::Failure;
    }
    return ExitCode::Ok;
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                          std::chrono::duration<double>(options.forSeconds));
  while (!stopRequested() && (options.forSeconds <= 0 || std::chrono::steady_clock::now() < end)) {
    top.listen(std::chrono::milliseconds(1000));
    streams.out.write("\x1b[H\x1b[2J" + top.render() + "\n(Ctrl-C to stop)\n");
  }
  return ExitCode::Ok;
}

void registerTopCommands(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<TopOptions>();
  CLI::App* top = app.add_subcommand("top", TOP_DESCRIPTION);
  top->footer(TOP_FOOTER);
  top->add_flag("--once", options->once, "one snapshot after 1.5 s, then exit");
  top->add_option("--for", options->forSeconds, "stop after SECONDS")->check(nonNegativeNumber());
  addStackOptions(*top, options->stack);
  top->callback([options, &context] { context.exitCode = runTop(*options, context.streams); });
}

}  // namespace openvcu::cli
