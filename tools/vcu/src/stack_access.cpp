#include "stack_access.hpp"

#include <time.h>

#include <CLI/CLI.hpp>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "diagnostics.hpp"
#include "openvcu/config/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::cli {

void addStackOptions(CLI::App& command, StackOptions& options) {
  command.add_option("-c,--config", options.configPath, "the vehicle configuration (default: $OPENVCU_CONFIG)")
      ->option_text("FILE");
  command.add_option("--instance", options.instance, "stack instance; overrides the configuration's")
      ->option_text("NAME");
}

std::optional<Stack> loadStack(const StackOptions& options, Sink& err, ExitCode* exitCode) {
  std::string path = options.configPath;
  if (path.empty()) {
    if (const char* fromEnvironment = std::getenv(std::string(CONFIG_ENVIRONMENT_VARIABLE).c_str()))
      path = fromEnvironment;
  }
  if (path.empty()) {
    reportError(err, "no configuration: give --config FILE or set " + std::string(CONFIG_ENVIRONMENT_VARIABLE));
    *exitCode = ExitCode::Usage;
    return std::nullopt;
  }
  *exitCode = ExitCode::Failure;
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

std::int64_t realtimeNowNs() noexcept {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

std::int64_t monotonicToRealtimeNs(std::int64_t monotonicNs) noexcept {
  return realtimeNowNs() - (signals::monotonicNowNs() - monotonicNs);
}

std::string formatUtc(std::int64_t realtimeNs) {
  const std::int64_t seconds =
      realtimeNs >= 0 ? realtimeNs / 1'000'000'000 : (realtimeNs - 999'999'999) / 1'000'000'000;
  const std::int64_t milliseconds = (realtimeNs - seconds * 1'000'000'000) / 1'000'000;
  const auto time = static_cast<time_t>(seconds);
  tm parts{};
  ::gmtime_r(&time, &parts);
  std::array<char, 96> text{};  // room for any int the compiler imagines
  std::snprintf(text.data(), text.size(), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", parts.tm_year + 1900, parts.tm_mon + 1,
                parts.tm_mday, parts.tm_hour, parts.tm_min, parts.tm_sec, static_cast<int>(milliseconds));
  return text.data();
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

}  // namespace openvcu::cli
