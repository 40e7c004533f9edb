// `vcu gpio`. The description and footer are its manual.
#include "gpio_commands.hpp"

#include <CLI/CLI.hpp>
#include <memory>

#include "diagnostics.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/signals/table.hpp"
#include "text_table.hpp"

namespace openvcu::cli {
namespace {

constexpr const char* GPIO_DESCRIPTION = "Show the GPIO lines: direction, level, command and bound signal";
constexpr const char* GPIO_FOOTER =
    "One row per line of the configuration's GPIO map (\"gpio\" in vehicle.json):\n"
    "  LINE, CHIP and WHERE (offset or line name), DIR and SETTINGS (active-low, bias,\n"
    "  debounce, on/off delays, safe level), LEVEL: what vcu-gpio drives or read, with\n"
    "  its age (internal.gpio.<line>), COMMAND: outputs: the bound signal's commanded value\n"
    "  (override marked); inputs on the sim back end: the simulated electrical level\n"
    "  (set it with 'vcu signal set internal.gpio.sim.<line> 1'), SIGNAL and its VALUE.\n"
    "The stack: --config FILE or $OPENVCU_CONFIG, --instance NAME.\n"
    "\n"
    "Example:\n"
    "  vcu gpio --config config/hhea/vehicle.json\n"
    "Exit: 0 shown, 1 no GPIO map, configuration error or no running stack (the map is\n"
    "still printed, levels as '-'), 2 usage error.\n";

std::string onOff(double value) { return value >= 0.5 ? "on" : "off"; }

/// "2 s", "20 ms", "1.5 ms".
std::string delayText(std::int64_t ns) {
  if (ns % 1'000'000'000 == 0) return std::to_string(ns / 1'000'000'000) + " s";
  if (ns % 1'000'000 == 0) return std::to_string(ns / 1'000'000) + " ms";
  return formatNumber(static_cast<double>(ns) / 1e6) + " ms";
}

std::string settings(const config::GpioLine& line) {
  std::string text;
  const auto add = [&text](const std::string& part) { text += (text.empty() ? "" : ", ") + part; };
  if (line.activeLow) add("active-low");
  if (line.bias != config::LineBias::AsIs) add(std::string(config::lineBiasName(line.bias)));
  if (line.direction == config::LineDirection::Input) {
    if (line.debounceNs > 0) add("debounce " + delayText(line.debounceNs));
  } else {
    if (line.onDelayNs > 0) add("on-delay " + delayText(line.onDelayNs));
    if (line.offDelayNs > 0) add("off-delay " + delayText(line.offDelayNs));
    add("safe " + onOff(line.safe ? 1 : 0));
  }
  return text.empty() ? "-" : text;
}

std::string levelText(const signals::SignalTable* table, const signals::Catalog& catalog, const std::string& key) {
  const auto index = catalog.indexOf(key);
  if (!table || !index) return "-";
  const auto bus = table->readBus(*index);
  if (!bus || bus->updates == 0) return "never";
  return onOff(bus->value) + " (" + formatDuration(clock::monotonicNs() - bus->timestampNs) + " ago)";
}

std::string commandText(const signals::SignalTable* table, const signals::Catalog& catalog,
                        const config::GpioMap& map, const config::GpioLine& line) {
  if (!table) return "-";
  const bool output = line.direction == config::LineDirection::Output;
  if (!output && map.backend != config::GpioBackend::Sim) return "-";
  const auto index = catalog.indexOf(output ? line.signal : line.simKey());
  if (!index) return "-";
  const auto slot = table->read(*index);
  if (!slot) return "-";
  if (const auto command = signals::effectiveCommand(*slot)) {
    return (output ? "" : "sim ") + onOff(command->value) + (command->overridden ? " (override)" : "");
  }
  return output ? "none" : "sim unset";
}

std::string valueText(const signals::SignalTable* table, const signals::Catalog& catalog, const std::string& key) {
  const auto index = catalog.indexOf(key);
  if (!table || !index) return "-";
  const auto slot = table->read(*index);
  if (!slot) return "-";
  if (const auto command = signals::effectiveCommand(*slot)) return formatValue(catalog[*index], command->value);
  if (slot->bus.updates > 0) return formatValue(catalog[*index], slot->bus.value);
  return "never";
}

}  // namespace

ExitCode runGpio(const GpioOptions& options, Streams streams) {
  ExitCode exitCode = ExitCode::Ok;
  const auto maybeStack = loadStack(options.stack, streams.err, &exitCode);
  if (!maybeStack) return exitCode;
  const config::GpioMap& map = maybeStack->config.gpio;
  if (map.empty()) {
    reportError(streams.err, "the configuration has no GPIO map (\"gpio\" in " + maybeStack->config.path + ")");
    return ExitCode::Failure;
  }
  auto tableResult = signals::SignalTable::open(maybeStack->catalog, maybeStack->config.instance,
                                                signals::OpenMode::AttachOnly);
  const signals::SignalTable* table = tableResult ? &*tableResult : nullptr;
  const signals::Catalog& catalog = maybeStack->catalog;
  TextTable rows({"LINE", "CHIP", "WHERE", "DIR", "SETTINGS", "LEVEL", "COMMAND", "SIGNAL", "VALUE"});
  for (const config::GpioLine& line : map.lines) {
    rows.addRow({line.name, map.chips[line.chip].describe(), line.describeLine(),
                 std::string(config::lineDirectionName(line.direction)), settings(line),
                 levelText(table, catalog, line.statusKey()), commandText(table, catalog, map, line), line.signal,
                 valueText(table, catalog, line.signal)});
  }
  std::string out = "GPIO back end: " + std::string(config::gpioBackendName(map.backend)) + " (" + map.file + ")\n";
  rows.appendTo(out);
  streams.out.write(out);
  if (!tableResult) {
    reportError(streams.err, tableResult.error().message + " (levels unknown: is the stack running?)");
    return ExitCode::Failure;
  }
  return ExitCode::Ok;
}

void registerGpioCommands(CLI::App& app, CommandContext& context) {
  auto options = std::make_shared<GpioOptions>();
  CLI::App* gpio = app.add_subcommand("gpio", GPIO_DESCRIPTION);
  gpio->footer(GPIO_FOOTER);
  addStackOptions(*gpio, options->stack);
  gpio->callback([options, &context] { context.exitCode = runGpio(*options, context.streams); });
}

}  // namespace openvcu::cli
