#pragma once
// The GPIO map ("gpio" in vehicle.json): which chip lines vcu-gpio requests, how, and the
// internal signal each one is bound to. Loaded with the vehicle configuration so that every
// process builds the same catalog (the line status keys below) and knows who answers
// commands for the bound signals. Reference: docs/gpio.md.
//
//   {
//     "backend": "sim",                                   // or "gpiod" (libgpiod, /dev/gpiochipN)
//     "chips": [{"id": "main", "device": "gpiochip0"}],   // or "label": "pinctrl-bcm2711"
//     "lines": [
//       {"name": "Cl15", "chip": "main", "offset": 17, "direction": "output",
//        "onDelay": "2s", "offDelay": "2s", "initial": 0, "safe": 0, "signal": "relay.Cl15"},
//       {"name": "ContactorFault", "chip": "main", "line": "GPIO27", "direction": "input",
//        "bias": "pull-down", "debounce": "20ms", "signal": "fault.Contactor"}
//     ]
//   }
//
// Every line gets the status key "internal.gpio.<name>" (its logical level as vcu-gpio last
// drove or read it, bus plane); every input also "internal.gpio.sim.<name>", the electrical
// level of the simulated chip, which tests, the simulated vehicle and the HMI command.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::config {

struct InternalSignal;

enum class GpioBackend : std::uint8_t {
  Sim,    ///< lines live in the signal table (internal.gpio.sim.*)
  Gpiod,  ///< libgpiod v1 on the kernel's GPIO character devices
};

enum class LineDirection : std::uint8_t { Input, Output };

enum class LineBias : std::uint8_t { AsIs, Disabled, PullUp, PullDown };

/// "sim"/"gpiod", "input"/"output", "as-is"/"disabled"/"pull-up"/"pull-down".
[[nodiscard]] std::string_view gpioBackendName(GpioBackend backend) noexcept;
[[nodiscard]] std::string_view lineDirectionName(LineDirection direction) noexcept;
[[nodiscard]] std::string_view lineBiasName(LineBias bias) noexcept;

struct GpioChip {
  std::string id;      ///< the name lines refer to ("main")
  std::string device;  ///< "gpiochip0" or "/dev/gpiochip0"; empty when found by label
  std::string label;   ///< the chip's label ("pinctrl-bcm2711"); empty when found by device
  /// "gpiochip0" or "label 'pinctrl-bcm2711'".
  [[nodiscard]] std::string describe() const;
};

struct GpioLine {
  std::string name;     ///< letters, digits, '_': "Cl15"
  std::size_t chip{};   ///< index into GpioMap::chips
  std::optional<std::uint32_t> offset;  ///< the line by offset ...
  std::string lineName;                 ///< ... or by its name on the chip ("GPIO17")
  LineDirection direction{LineDirection::Input};
  bool activeLow{};
  LineBias bias{LineBias::AsIs};
  std::int64_t debounceNs{};   ///< inputs: a new level counts once stable this long
  std::int64_t onDelayNs{};    ///< outputs: switch on once commanded on this long
  std::int64_t offDelayNs{};   ///< outputs: switch off once commanded off this long
  bool initial{};              ///< outputs: the level of a fresh start (no earlier state)
  bool safe{};                 ///< outputs: the level on SIGTERM
  std::string signal;          ///< bound signal key: "internal.relay.Cl15"
  std::string comment;

  /// "offset 17" or "line 'GPIO17'".
  [[nodiscard]] std::string describeLine() const;
  [[nodiscard]] std::string statusKey() const { return "internal.gpio." + name; }
  [[nodiscard]] std::string simKey() const { return "internal.gpio.sim." + name; }
};

struct GpioMap {
  std::string file;  ///< resolved path; empty when the configuration has no GPIO map
  GpioBackend backend{GpioBackend::Sim};
  std::vector<GpioChip> chips;
  std::vector<GpioLine> lines;

  [[nodiscard]] bool empty() const noexcept { return lines.empty(); }
  /// The input line bound to `key`, or nullptr.
  [[nodiscard]] const GpioLine* inputBoundTo(std::string_view key) const noexcept;
};

/// Loads and checks a GPIO map. `declared`: the configuration's internal signals, which
/// every bound signal must be one of (outputs: 0/1 commanded by the FSM or an operator;
/// inputs: written by vcu-gpio). Errors and warnings (file and JSON path) go to
/// `diagnostics`; the map is returned only when there is no error.
std::optional<GpioMap> loadGpioMap(const std::string& path, const std::vector<InternalSignal>& declared,
                                   std::vector<Error>& diagnostics);

}  // namespace openvcu::config
