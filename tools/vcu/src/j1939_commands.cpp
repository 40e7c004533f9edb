// `vcu j1939` (show) and the command registration; `vcu j1939 request` is in
// j1939_request.cpp. Each command's description and footer are its manual.
#include "j1939_commands.hpp"

#include <CLI/CLI.hpp>
#include <array>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <set>

#include "cli_checks.hpp"
#include "decode_output.hpp"
#include "diagnostics.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/ipc/event_bus.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/name.hpp"
#include "text_table.hpp"

namespace openvcu::cli {
namespace {

/// vcu-can-tx publishes every bus's view once a second: once one bus was heard, the others
/// follow within this long (why 1.2 s: one period plus room for a loaded machine).
constexpr auto OTHER_BUSES_WAIT = std::chrono::milliseconds(1200);

constexpr const char* SHOW_DESCRIPTION = "Show the J1939 networks: the VCU's address claim, the other nodes, its DTCs";
constexpr const char* SHOW_FOOTER =
    "Listens to vcu-can-tx's J1939 view (LCM, channel OPENVCU_<INSTANCE>_J1939, one\n"
    "message per J1939 bus once a second and at once after a change) and prints per bus:\n"
    "the VCU's address claim state (off, claiming, claimed, cannot claim), its address\n"
    "(hex and decimal) and 64-bit NAME with the NAME's J1939-81 fields; the other nodes that\n"
    "claimed an address (address, NAME, the DBC node whose NmStationAddress is that\n"
    "address); the VCU's own DTCs (J1939-73: name, SPN, FMI, occurrence count, active in DM1\n"
    "or previously active in DM2) and the DM1 lamps (protect, amber warning, red stop,\n"
    "malfunction).\n"
    "It stops when every bus with a \"j1939\" object in the configuration was heard (every\n"
    "bus when none has one), or 1.2 s after the first bus (can-tx sends all buses each\n"
    "second), or after --timeout seconds (default 3).\n"
    "--bus B waits for that bus only. --json prints one JSON document:\n"
    "  {\"instance\": \"hhea\", \"buses\": [{\"bus\": \"vehicle\", \"claimState\": \"claimed\", ...}]}\n"
    "The stack: --config FILE or $OPENVCU_CONFIG, --instance NAME.\n"
    "\n"
    "Examples:\n"
    "  vcu j1939\n"
    "  vcu j1939 --bus vehicle --json\n"
    "  vcu j1939 request 65242 --to 0x21\n"
    "Exit: 0 a view arrived, 1 none within --timeout or configuration error, 2 usage error.\n";

std::string hex(std::uint64_t value, int digits) {
  std::array<char, 24> text{};
  std::snprintf(text.data(), text.size(), "0x%0*llX", digits, static_cast<unsigned long long>(value));
  return text.data();
}

std::string lampsText(std::uint8_t lamps) {
  const auto status = [lamps](int shift) {
    return std::string(j1939::lampStatusName(static_cast<j1939::LampStatus>((lamps >> shift) & 0x3u)));
  };
  return "protect " + status(0) + ", amber warning " + status(2) + ", red stop " + status(4) + ", malfunction " +
         status(6);
}

void appendLampsJson(std::string& out, std::uint8_t lamps) {
  const auto status = [lamps](int shift) {
    return std::string(j1939::lampStatusName(static_cast<j1939::LampStatus>((lamps >> shift) & 0x3u)));
  };
  out += "{\"byte\": " + std::to_string(lamps) + ", \"protect\": ";
  appendJsonString(out, status(0));
  out += ", \"amberWarning\": ";
  appendJsonString(out, status(2));
  out += ", \"redStop\": ";
  appendJsonString(out, status(4));
  out += ", \"malfunction\": ";
  appendJsonString(out, status(6));
  out += '}';
}

std::string nameFieldsText(std::uint64_t name) {
  const j1939::Name fields = j1939::Name::fromValue(name);
  return "identity number " + std::to_string(fields.identityNumber) + ", manufacturer code " +
         std::to_string(fields.manufacturerCode) + ", ECU instance " + std::to_string(fields.ecuInstance) +
         ", function instance " + std::to_string(fields.functionInstance) + ", function " +
         std::to_string(fields.function) + ", vehicle system " + std::to_string(fields.vehicleSystem) +
         ", vehicle system instance " + std::to_string(fields.vehicleSystemInstance) + ", industry group " +
         std::to_string(fields.industryGroup) + ", arbitrary address capable " +
         (fields.arbitraryAddressCapable ? "yes" : "no");
}

void appendNameFieldsJson(std::string& out, std::uint64_t name) {
  const j1939::Name fields = j1939::Name::fromValue(name);
  out += "{\"identityNumber\": " + std::to_string(fields.identityNumber) +
         ", \"manufacturerCode\": " + std::to_string(fields.manufacturerCode) +
         ", \"ecuInstance\": " + std::to_string(fields.ecuInstance) +
         ", \"functionInstance\": " + std::to_string(fields.functionInstance) +
         ", \"function\": " + std::to_string(fields.function) +
         ", \"vehicleSystem\": " + std::to_string(fields.vehicleSystem) +
         ", \"vehicleSystemInstance\": " + std::to_string(fields.vehicleSystemInstance) +
         ", \"industryGroup\": " + std::to_string(fields.industryGroup) +
         ", \"arbitraryAddressCapable\": " + (fields.arbitraryAddressCapable ? "true" : "false") + "}";
}

void appendNetworkText(std::string& out, const ipc::J1939Network& network, const config::VehicleConfig& config) {
  out += "bus " + network.bus + ": " + std::string(ipc::claimStateName(network.claimState));
  if (network.claimState == ipc::ClaimState::Off) {
    out += " (no address claim configured)";
  } else {
    out += ", address " + formatJ1939Address(network.address) + ", NAME " + hex(network.name, 16) + "\n";
    out += "  NAME fields: " + nameFieldsText(network.name);
  }
  out += "\n";
  if (network.nodes.empty()) {
    out += "  other nodes: none claimed an address\n";
  } else {
    out += "  other nodes:\n";
    TextTable nodes({"ADDRESS", "NAME", "DBC NODE"});
    for (const ipc::J1939Node& node : network.nodes) {
      const std::string dbcNode = dbcNodeAt(config, node.address);
      nodes.addRow({formatJ1939Address(node.address), hex(node.name, 16), dbcNode.empty() ? "-" : dbcNode});
    }
    nodes.appendTo(out, "    ");
  }
  out += "  DM1 lamps: " + lampsText(network.lamps) + "\n";
  if (network.dtcs.empty()) {
    out += "  DTCs: none\n";
    return;
  }
  out += "  DTCs:\n";
  TextTable dtcs({"NAME", "SPN", "FMI", "OCCURRENCES", "STATE"});
  for (const ipc::J1939Dtc& dtc : network.dtcs) {
    dtcs.addRow({dtc.name, std::to_string(dtc.spn), std::to_string(dtc.fmi), std::to_string(dtc.occurrences),
                 dtc.active ? "active" : "previously active"});
  }
  dtcs.appendTo(out, "    ");
}

void appendNetworkJson(std::string& out, const ipc::J1939Network& network, const config::VehicleConfig& config) {
  out += "{\"bus\": ";
  appendJsonString(out, network.bus);
  out += ", \"service\": ";
  appendJsonString(out, network.service);
  out += ", \"pid\": " + std::to_string(network.pid) + ", \"claimState\": ";
  appendJsonString(out, ipc::claimStateName(network.claimState));
  out += ", \"address\": " + std::to_string(network.address) + ", \"name\": ";
  appendJsonString(out, hex(network.name, 16));
  out += ", \"nameFields\": ";
  appendNameFieldsJson(out, network.name);
  out += ", \"nodes\": [";
  for (std::size_t i = 0; i < network.nodes.size(); ++i) {
    const ipc::J1939Node& node = network.nodes[i];
    out += i == 0 ? "" : ", ";
    out += "{\"address\": " + std::to_string(node.address) + ", \"name\": ";
    appendJsonString(out, hex(node.name, 16));
    out += ", \"nameFields\": ";
    appendNameFieldsJson(out, node.name);
    out += ", \"dbcNode\": ";
    const std::string dbcNode = dbcNodeAt(config, node.address);
    if (dbcNode.empty()) {
      out += "null";
    } else {
      appendJsonString(out, dbcNode);
    }
    out += '}';
  }
  out += "], \"dtcs\": [";
  for (std::size_t i = 0; i < network.dtcs.size(); ++i) {
    const ipc::J1939Dtc& dtc = network.dtcs[i];
    out += i == 0 ? "{\"name\": " : ", {\"name\": ";
    appendJsonString(out, dtc.name);
    out += ", \"spn\": " + std::to_string(dtc.spn) + ", \"fmi\": " + std::to_string(dtc.fmi) +
           ", \"occurrences\": " + std::to_string(dtc.occurrences) +
           ", \"active\": " + (dtc.active ? "true" : "false") + "}";
  }
  out += "], \"lamps\": ";
  appendLampsJson(out, network.lamps);
  out += '}';
}

void addShowOptions(CLI::App& command, J1939ShowOptions& options) {
  command.add_option("-b,--bus", options.bus, "only this bus (default: every bus heard)")->option_text("BUS");
  command.add_flag("--json", options.json, "one JSON document instead of text");
  command.add_option("--timeout", options.timeoutSeconds, "seconds to wait for the view (default 3)")
      ->check(CLI::PositiveNumber)
      ->option_text("SECONDS");
  addStackOptions(command, options.stack);
}

}  // namespace

namespace {

/// An unsigned number, decimal or 0x hex, at most `maximum`; else empty.
std::optional<std::uint32_t> parseUnsigned(std::string_view text, std::uint32_t maximum) noexcept {
  int base = 10;
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
    text.remove_prefix(2);
    base = 16;
  }
  if (text.empty() || text.size() > 10) return std::nullopt;
  std::uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value, base);
  if (error != std::errc{} || end != text.data() + text.size() || value > maximum) return std::nullopt;
  return static_cast<std::uint32_t>(value);
}

}  // namespace

std::optional<std::uint32_t> parsePgn(std::string_view text) noexcept {
  return parseUnsigned(text, j1939::PGN_MASK);
}

std::optional<std::uint8_t> parseJ1939Address(std::string_view text) noexcept {
  const auto value = parseUnsigned(text, 0xFF);
  if (!value) return std::nullopt;
  return static_cast<std::uint8_t>(*value);
}

std::string formatJ1939Address(std::uint8_t address) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "0x%02X (%u)", static_cast<unsigned>(address),
                static_cast<unsigned>(address));
  return text.data();
}

std::string dbcNodeAt(const config::VehicleConfig& config, std::uint8_t address) {
  for (const dbc::Node& node : config.database.nodes) {
    if (config::nodeAddress(config.database, node) == address) return node.name;
  }
  return {};
}

const config::BusConfig* findJ1939Bus(const config::VehicleConfig& config, const std::string& name, Sink& err) {
  if (const config::BusConfig* bus = config.findBus(name)) return bus;
  std::vector<std::string> names;
  for (const config::BusConfig& bus : config.buses) names.push_back(bus.name);
  std::string message = "unknown bus '" + name + "'";
  if (const auto maybeSuggestion = text::didYouMean(name, names)) {
    message += " (did you mean '" + *maybeSuggestion + "'?)";
  } else {
    std::string list;
    for (const std::string& bus : names) list += (list.empty() ? "" : ", ") + bus;
    message += " (the buses of " + config.path + ": " + list + ")";
  }
  reportError(err, message);
  return nullptr;
}

ExitCode runJ1939Show(const J1939ShowOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::VehicleConfig& config = maybeStack->config;
  if (!options.bus.empty() && findJ1939Bus(config, options.bus, streams.err) == nullptr) return ExitCode::Failure;
  auto eventsResult = ipc::EventBus::open(config.lcmUrl, config.instance);
  if (!eventsResult) {
    reportError(streams.err, eventsResult.error().message);
    return ExitCode::Failure;
  }
  ipc::EventBus& events = *eventsResult;
  // Every view heard is shown (can-tx may publish a bus without a claim: its DTCs); the
  // wait ends once each bus with a "j1939" object was heard (every bus when none has one).
  std::map<std::string, ipc::J1939Network> latest;  // by bus, sorted for the output
  auto subscribed = events.onJ1939Network([&](const ipc::J1939Network& network) {
    if (!options.bus.empty() && network.bus != options.bus) return;
    if (config.findBus(network.bus) == nullptr) return;  // another configuration's bus
    auto& slot = latest[network.bus];
    if (network.timestampNs >= slot.timestampNs) slot = network;
  });
  if (!subscribed) {
    reportError(streams.err, subscribed.error().message);
    return ExitCode::Failure;
  }
  std::set<std::string> expected;
  for (const config::BusConfig& bus : config.buses) {
    if (bus.j1939 && options.bus.empty()) expected.insert(bus.name);
  }
  if (!options.bus.empty()) {
    expected.insert(options.bus);
  } else if (expected.empty()) {
    for (const config::BusConfig& bus : config.buses) expected.insert(bus.name);
  }
  const auto allHeard = [&] {
    for (const std::string& bus : expected) {
      if (latest.count(bus) == 0) return false;
    }
    return true;
  };
  auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                         std::chrono::duration<double>(options.timeoutSeconds));
  bool firstHeard = false;
  while (!allHeard()) {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    if (events.handle(left) == ipc::HandleResult::Failed) break;
    if (!firstHeard && !latest.empty()) {
      firstHeard = true;
      deadline = std::min(deadline, std::chrono::steady_clock::now() + OTHER_BUSES_WAIT);
    }
  }
  if (latest.empty()) {
    const std::string which = options.bus.empty() ? std::string() : " for bus '" + options.bus + "'";
    reportError(streams.err, "no J1939 view from vcu-can-tx" + which + " within " +
                                 formatNumber(options.timeoutSeconds) + " s on " +
                                 events.channel(ipc::EventKind::J1939) +
                                 ": is it running, does vehicle.json give a bus a \"j1939\" object?");
    return ExitCode::Failure;
  }
  std::string out;
  if (options.json) {
    out += "{\"instance\": ";
    appendJsonString(out, config.instance);
    out += ", \"buses\": [";
    bool first = true;
    for (const auto& [bus, network] : latest) {
      out += first ? "" : ", ";
      first = false;
      appendNetworkJson(out, network, config);
    }
    out += "]}\n";
  } else {
    bool first = true;
    for (const auto& [bus, network] : latest) {
      if (!first) out += '\n';
      first = false;
      appendNetworkText(out, network, config);
    }
  }
  streams.out.write(out);
  return ExitCode::Ok;
}

void registerJ1939Commands(CLI::App& app, CommandContext& context) {
  auto showOptions = std::make_shared<J1939ShowOptions>();
  CLI::App* j1939 = app.add_subcommand("j1939", SHOW_DESCRIPTION);
  j1939->footer(SHOW_FOOTER);
  addShowOptions(*j1939, *showOptions);
  CLI::App* show = j1939->add_subcommand("show", SHOW_DESCRIPTION);
  show->footer(SHOW_FOOTER);
  addShowOptions(*show, *showOptions);
  show->callback([showOptions, &context] { context.exitCode = runJ1939Show(*showOptions, context.streams); });
  addJ1939Request(*j1939, context);
  // `vcu j1939` alone shows; with a subcommand, that subcommand's callback ran instead.
  j1939->require_subcommand(0, 1);
  j1939->final_callback([j1939, showOptions, &context] {
    if (j1939->get_subcommands().empty()) context.exitCode = runJ1939Show(*showOptions, context.streams);
  });
}

}  // namespace openvcu::cli
