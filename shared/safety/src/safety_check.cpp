// checkSafety(): safety.json against the vehicle it belongs to (safety_case.hpp).
#include <algorithm>

#include "openvcu/config/json.hpp"
#include "openvcu/config/simulation.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/safety/safety_case.hpp"

namespace openvcu::safety {
namespace {

using config::JsonChecker;

class Checker {
 public:
  Checker(const SafetyCase& safetyCase, const config::VehicleConfig& vehicle, const signals::Catalog& catalog,
          const std::vector<std::string>* fsmStates)
      : m_case(safetyCase), m_vehicle(vehicle), m_catalog(catalog), m_fsmStates(fsmStates) {}

  std::vector<Error> run() {
    for (std::size_t h = 0; h < m_case.hazards.size(); ++h) {
      const Hazard& hazard = m_case.hazards[h];
      const std::string path = JsonChecker::join("/hazards", h);
      for (std::size_t i = 0; i < hazard.during.size(); ++i) {
        fsmState(hazard.during[i], JsonChecker::join(path + "/during", i));
      }
      safeState(hazard.safeState, path + "/safeState");
      for (std::size_t i = 0; i < hazard.detection.size(); ++i) {
        detection(hazard, hazard.detection[i], JsonChecker::join(path + "/detection", i));
      }
      for (std::size_t i = 0; i < hazard.faults.size(); ++i) {
        injection(hazard.faults[i], JsonChecker::join(path + "/faults", i));
      }
      if (hazard.faults.empty()) {
        warning(path, "hazard '" + hazard.id + "' lists no fault to inject: a campaign cannot show its reaction");
      }
    }
    return std::move(m_out);
  }

 private:
  void error(const std::string& path, std::string message) {
    m_out.push_back(Error{std::move(message), Location::json(m_case.path, path)});
  }
  void warning(const std::string& path, std::string message) {
    m_out.push_back(Error{std::move(message), Location::json(m_case.path, path), Severity::Warning});
  }

  static std::string suggest(const std::string& word, const std::vector<std::string>& names) {
    if (auto suggestion = text::didYouMean(word, names)) return "; did you mean '" + *suggestion + "'?";
    return {};
  }

  void fsmState(const std::string& name, const std::string& path) {
    if (m_fsmStates == nullptr) return;
    if (std::find(m_fsmStates->begin(), m_fsmStates->end(), name) != m_fsmStates->end()) return;
    const std::string where = m_vehicle.fsmFile.empty() ? std::string("the vehicle has no FSM") : m_vehicle.fsmFile;
    error(path, "no FSM state '" + name + "' in " + where + suggest(name, *m_fsmStates));
  }

  /// The line named `name`, or nullptr with an error.
  const config::GpioLine* gpioLine(const std::string& name, const std::string& path) {
    std::vector<std::string> names;
    for (const config::GpioLine& line : m_vehicle.gpio.lines) {
      if (line.name == name) return &line;
      names.push_back(line.name);
    }
    const std::string where =
        m_vehicle.gpioFile.empty() ? std::string("the vehicle has no GPIO map") : m_vehicle.gpioFile;
    error(path, "no GPIO line '" + name + "' in " + where + suggest(name, names));
    return nullptr;
  }

  void gpioLine(const std::string& name, config::LineDirection direction, const std::string& path) {
    const config::GpioLine* line = gpioLine(name, path);
    if (line == nullptr || line->direction == direction) return;
    error(path, "GPIO line '" + name + "' is an " + std::string(config::lineDirectionName(line->direction)) +
                    "; expected an " + std::string(config::lineDirectionName(direction)));
  }

  void signal(const std::string& key, const std::string& path) {
    if (m_catalog.indexOf(key)) return;
    std::string message = "no signal '" + key + "' in the DBC or the internal signals";
    if (auto suggestion = m_catalog.suggest(key)) message += "; did you mean '" + *suggestion + "'?";
    error(path, std::move(message));
  }

  void message(const std::string& name, const std::string& path) {
    const dbc::Message* found = m_vehicle.database.findMessage(name);
    if (found != nullptr && !found->pseudo) return;
    std::vector<std::string> names;
    for (const dbc::Message& m : m_vehicle.database.messages) {
      if (!m.pseudo) names.push_back(m.name);
    }
    error(path, "no message '" + name + "' in the DBC" + suggest(name, names));
  }

  void node(const std::string& name, const std::string& path) {
    if (m_vehicle.database.findNode(name) != nullptr) return;
    std::vector<std::string> names;
    for (const dbc::Node& n : m_vehicle.database.nodes) names.push_back(n.name);
    error(path, "no node '" + name + "' in the DBC's BU_ list" + suggest(name, names));
  }

  const config::BusConfig* bus(const std::string& name, const std::string& path) {
    if (const config::BusConfig* found = m_vehicle.findBus(name)) return found;
    std::vector<std::string> names;
    for (const config::BusConfig& b : m_vehicle.buses) names.push_back(b.name);
    error(path, "no bus '" + name + "' in " + m_vehicle.path + suggest(name, names));
    return nullptr;
  }

  void safeState(const SafeState& state, const std::string& path) {
    for (std::size_t i = 0; i < state.fsmStates.size(); ++i) {
      fsmState(state.fsmStates[i], JsonChecker::join(path + "/fsmStates", i));
    }
    for (std::size_t i = 0; i < state.gpio.size(); ++i) {
      gpioLine(state.gpio[i].line, config::LineDirection::Output, JsonChecker::join(path + "/gpio", i) + "/line");
    }
    for (std::size_t i = 0; i < state.bus.size(); ++i) {
      signal(state.bus[i].signal, JsonChecker::join(path + "/bus", i) + "/signal");
    }
    for (std::size_t i = 0; i < state.restarted.size(); ++i) {
      const std::string where = JsonChecker::join(path + "/restarted", i);
      if (!m_case.watchdog) {
        error(where, "a restarted service needs the \"watchdog\" section that restarts it");
        continue;
      }
      const auto& watched = m_case.watchdog->services;
      if (std::find(watched.begin(), watched.end(), state.restarted[i]) == watched.end()) {
        error(where, "service '" + state.restarted[i] + "' is not in /watchdog/services: nothing restarts it");
      } else if (!m_case.watchdog->restart) {
        error(where, "/watchdog/restart is false: the watchdog restarts no service");
      }
    }
  }

  void detection(const Hazard& hazard, const Detection& mechanism, const std::string& path) {
    if (!mechanism.message.empty()) message(mechanism.message, path + "/message");
    if (!mechanism.signal.empty()) signal(mechanism.signal, path + "/signal");
    if (!mechanism.node.empty()) node(mechanism.node, path + "/node");
    if (!mechanism.line.empty()) gpioLine(mechanism.line, config::LineDirection::Input, path + "/line");
    if (!mechanism.bus.empty()) {
      const config::BusConfig* found = bus(mechanism.bus, path + "/bus");
      if (found != nullptr && !found->j1939) {
        error(path + "/bus", "bus '" + mechanism.bus + "' has no J1939 address claim (\"j1939\" in " + m_vehicle.path +
                                 "): no address to lose");
      }
    }
    if (mechanism.kind != DetectionKind::ServiceWatchdog) return;
    const std::string where = path + "/service";
    if (!m_case.watchdog) {
      error(where, "a serviceWatchdog detection needs the \"watchdog\" section");
      return;
    }
    const auto& watched = m_case.watchdog->services;
    if (std::find(watched.begin(), watched.end(), mechanism.service) == watched.end()) {
      error(where, "service '" + mechanism.service + "' is not in /watchdog/services: nothing detects its silence");
    }
    if (m_case.watchdog->silentAfterMs >= hazard.fttiMs) {
      error(where, "the watchdog counts a service silent after " + std::to_string(m_case.watchdog->silentAfterMs) +
                       " ms (/watchdog/silentAfterMs): not inside this hazard's FTTI of " +
                       std::to_string(hazard.fttiMs) + " ms");
    }
  }

  void injection(const Injection& fault, const std::string& path) {
    if (!fault.node.empty()) node(fault.node, path + "/node");
    if (!fault.message.empty()) message(fault.message, path + "/message");
    if (!fault.signal.empty()) signal(fault.signal, path + "/signal");
    if (!fault.line.empty()) gpioLine(fault.line, path + "/line");
    if (!fault.bus.empty()) bus(fault.bus, path + "/bus");
    if (fault.kind == InjectKind::SimFault) simFault(fault.name, path + "/name");
  }

  /// A named fault of the simulated vehicle: "silent.<NODE>" for a DBC node, or one of the
  /// simulation file's faults (generic model). The HHEA model's own names are vcu-ecu-sim's
  /// (services/ecu-sim), not checked here: vcu-ecu-sim refuses an unknown one with the list.
  void simFault(const std::string& name, const std::string& path) {
    if (m_vehicle.simulationFile.empty()) {
      error(path,
            "the vehicle has no simulation (\"simulation\" in " + m_vehicle.path + ") to inject '" + name + "' into");
      return;
    }
    if (name.rfind("silent.", 0) == 0) {
      node(name.substr(7), path);
      return;
    }
    if (!m_simulationLoaded) {
      m_simulationLoaded = true;
      if (auto simulation = config::loadSimConfig(m_vehicle.simulationFile, m_vehicle)) {
        if (simulation->model == config::SimModel::Generic) {
          m_simulationFaults.emplace();
          for (const config::SimFault& known : simulation->rules.faults) m_simulationFaults->push_back(known.name);
        }
      }
    }
    if (!m_simulationFaults) return;  // the HHEA model, or a simulation file that does not load (its own error)
    if (std::find(m_simulationFaults->begin(), m_simulationFaults->end(), name) != m_simulationFaults->end()) return;
    error(path, "no fault '" + name + "' in " + m_vehicle.simulationFile + " (nor silent.<NODE>)" +
                    suggest(name, *m_simulationFaults));
  }

  const SafetyCase& m_case;
  const config::VehicleConfig& m_vehicle;
  const signals::Catalog& m_catalog;
  const std::vector<std::string>* m_fsmStates;
  std::vector<Error> m_out;
  bool m_simulationLoaded{false};
  std::optional<std::vector<std::string>> m_simulationFaults;  ///< the generic model's fault names
};

}  // namespace

std::vector<Error> checkSafety(const SafetyCase& safetyCase, const config::VehicleConfig& vehicle,
                               const signals::Catalog& catalog, const std::vector<std::string>* fsmStates) {
  return Checker(safetyCase, vehicle, catalog, fsmStates).run();
}

}  // namespace openvcu::safety
