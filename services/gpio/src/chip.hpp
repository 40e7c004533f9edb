#pragma once
// The one small interface vcu-gpio drives lines through, with two back ends:
//   - SimChip: the lines live in the signal table. Inputs read "internal.gpio.sim.<line>"
//     (the electrical level that tests, the simulated vehicle or the HMI command); outputs
//     exist only as the level vcu-gpio reports in "internal.gpio.<line>".
//   - GpiodChip (when built with libgpiod): libgpiod v1 (Debian 12's 1.6) on the kernel's
//     GPIO character devices; every line requested once and held until release().
// Levels are logical (1 = active; the back end applies active-low). Input changes arrive as
// events on file descriptors the caller polls: no back end is ever polled on a timer.
//
//   auto chipResult = gpio::openChip(map, table, catalog);
//   (*chipResult)->request(startLevels);                 // outputs at these levels
//   poll on (*chipResult)->eventFds(), then readEvents(fd, batch)

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "openvcu/config/gpio.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::gpio {

/// An input line changed to `level` at `monotonicNs` (CLOCK_MONOTONIC).
struct LineEvent {
  std::size_t line{};  ///< index into GpioMap::lines
  bool level{};
  std::int64_t monotonicNs{};
};

/// @note restricted thread-safe: request/release on one thread; afterwards set() on one
///       thread and readEvents() on one (possibly another) thread.
class Chip {
 public:
  virtual ~Chip() = default;
  /// Requests every line of the map: outputs driven at `levels[i]` (logical; entries of
  /// inputs are ignored), inputs with both-edge events. Error: which chip and line, and why.
  virtual Status request(std::span<const bool> levels) = 0;
  /// Drives output `line` (logical level). Error: why, the line keeps its level.
  virtual Status set(std::size_t line, bool level) = 0;
  /// The current logical level of `line`.
  virtual Result<bool> get(std::size_t line) = 0;
  /// Readable when events are waiting (valid after request()).
  [[nodiscard]] virtual std::vector<int> eventFds() const = 0;
  /// Reads up to out.size() waiting events of `fd`; 0 when none. Never blocks.
  virtual std::size_t readEvents(int fd, std::span<LineEvent> out) = 0;
  /// The sim chip looks at its input keys (called when the table changed); others: nothing.
  virtual void tableChanged() {}
  /// Releases every line (the kernel then leaves an output as the driver does).
  virtual void release() noexcept = 0;
  /// "sim" or "gpiod".
  [[nodiscard]] virtual std::string_view kind() const noexcept = 0;
};

/// The back end the map asks for. Error when it is "gpiod" and this build has no libgpiod.
Result<std::unique_ptr<Chip>> openChip(const config::GpioMap& map, signals::SignalTable& table,
                                       const signals::Catalog& catalog);

/// true when this build has the libgpiod back end.
[[nodiscard]] bool haveGpiod() noexcept;

Result<std::unique_ptr<Chip>> openSimChip(const config::GpioMap& map, signals::SignalTable& table,
                                          const signals::Catalog& catalog);
Result<std::unique_ptr<Chip>> openGpiodChip(const config::GpioMap& map);

}  // namespace openvcu::gpio
