#include "openvcu/display/values.hpp"

#include <array>
#include <charconv>
#include <cstdio>

#include "openvcu/config/dashboard.hpp"

namespace openvcu::display {
namespace {

bool contains(std::string_view text, std::string_view part) {
  return text.find(part) != std::string_view::npos;
}

}  // namespace

std::string_view statusName(ValueStatus status) noexcept {
  switch (status) {
    case ValueStatus::Ready:
      return "Ready";
    case ValueStatus::Stale:
      return "Stale";
    case ValueStatus::NotConnected:
      return "NotConnected";
    case ValueStatus::Error:
      return "Error";
  }
  return "Error";
}

ValueStatus classify(const signals::SlotSnapshot& slot, std::int64_t nowNs, std::int64_t staleAfterNs) noexcept {
  if (slot.bus.updates > 0) {
    if (slot.bus.quality != signals::Quality::Valid) return ValueStatus::Stale;
    if (staleAfterNs > 0 && nowNs - slot.bus.timestampNs > staleAfterNs) return ValueStatus::Stale;
    return ValueStatus::Ready;
  }
  if (slot.command.updates > 0 || slot.override.active) return ValueStatus::Ready;
  return ValueStatus::NotConnected;
}

std::optional<double> shownValue(const signals::SignalInfo& signal, const signals::SlotSnapshot& slot) noexcept {
  if (slot.bus.updates > 0) return slot.bus.value;
  if (signal.direction == signals::SignalDirection::Received) return std::nullopt;
  if (const auto command = signals::effectiveCommand(slot)) return command->value;
  return std::nullopt;
}

std::optional<ShownSample> shownSample(const signals::SignalInfo& signal, const signals::SlotSnapshot& slot) noexcept {
  const auto value = shownValue(signal, slot);
  if (!value) return std::nullopt;
  std::int64_t at = slot.bus.updates > 0 ? slot.bus.timestampNs : slot.command.timestampNs;
  if (slot.override.active) at = slot.override.timestampNs;
  return ShownSample{*value, at};
}

std::string formatValue(const signals::SignalInfo& signal, double value, std::string_view format) {
  if (auto maybeText = signals::valueText(signal, value)) return *maybeText;
  std::array<char, 64> text{};
  if (format.empty()) {
    const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size() - 1, value);
    if (ec != std::errc{}) return "?";
    *end = '\0';
  } else {
    const std::string spec = config::isSafeNumberFormat(format) ? std::string(format) : std::string("%g");
    std::snprintf(text.data(), text.size(), spec.c_str(), value);
  }
  std::string out = text.data();
  if (!signal.unit.empty()) out += " " + signal.unit;
  return out;
}

std::string shortLabel(std::string_view key) {
  // "HVLP_SA71.HS2_Status_Feedback.InverterStatus" -> "HVLP_SA71 InverterStatus";
  // "internal.relay.Cl15" -> "relay Cl15"
  const auto first = key.find('.');
  const auto last = key.rfind('.');
  if (first == std::string_view::npos) return std::string(key);
  if (key.starts_with("internal.")) {
    const auto previous = key.rfind('.', last - 1);
    return std::string(key.substr(previous + 1, last - previous - 1)) + " " + std::string(key.substr(last + 1));
  }
  return std::string(key.substr(0, first)) + " " + std::string(key.substr(last + 1));
}

TextTone toneOf(std::string_view text) noexcept {
  // the good words first: "No fault (Normal)" is good although it contains "fault"
  for (const std::string_view good :
       {"Normal", "normal", "No fault", "No error", "OK", "Ok", "Closed", "Connected", "Ready"}) {
    if (contains(text, good)) return TextTone::Good;
  }
  for (const std::string_view bad : {"Fault", "fault", "Error", "error", "Fail", "fail", "Alarm", "alarm"}) {
    if (contains(text, bad)) return TextTone::Bad;
  }
  return TextTone::Neutral;
}

std::int64_t staleAfterFor(const signals::SignalInfo& signal, std::int64_t busTimeoutNs) noexcept {
  return signal.kind == signals::SignalKind::Bus ? busTimeoutNs : 0;
}

}  // namespace openvcu::display
