#pragma once
// What vcu-gpio does with its lines, with time passed in (tests drive it with a fake clock):
//   - outputs follow the commanded value (override, else command) of their bound signal with
//     an on-delay and an off-delay: a line switches to level L once L has been commanded
//     continuously for delay(L), measured from the command's own time stamp (a command that
//     flips back within the delay never reaches the line);
//   - inputs: an edge makes a new raw level; it is accepted once it stayed for the debounce
//     time, and then written to the bound signal (bus plane, writer 4) and the line's status;
//   - every line's level goes to "internal.gpio.<line>" (bus plane) and every change is
//     logged and counted.
// Start: an output resumes the level its status key says vcu-gpio drove last (a restart after
// a crash: no glitch on the relay), else its initial level; inputs start at what they read.
// safeState() drives every output to its safe level (SIGTERM).
//
//   auto controllerResult = gpio::Controller::create(map, catalog, table, chip, log);
//   controller.start(now);
//   output thread: controller.updateOutputs(now); sleep until nextOutputDeadlineNs() or a table change
//   input thread:  controller.onEvent(event); controller.updateInputs(now); sleep until nextInputDeadlineNs() or an
//   event

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "chip.hpp"
#include "openvcu/config/services.hpp"
#include "openvcu/schedule/schedule_config.hpp"
#include "openvcu/signals/writer_watch.hpp"

namespace openvcu::gpio {

inline constexpr signals::WriterId GPIO_WRITER = config::writerOf(config::ServiceId::Gpio);
inline constexpr std::int64_t NO_DEADLINE = std::numeric_limits<std::int64_t>::max();
/// After a failed set(), the next attempt comes this much later (no retry storm).
inline constexpr std::int64_t RETRY_NS = 1'000'000'000;

struct GpioCounters {
  std::atomic<std::int64_t> outputSwitches{};
  std::atomic<std::int64_t> inputChanges{};  ///< accepted (debounced) input changes
  std::atomic<std::int64_t> inputEdges{};    ///< raw edges seen
  std::atomic<std::int64_t> inputBounces{};  ///< raw levels that went back before their debounce ended
  std::atomic<std::int64_t> setFailures{};
};

/// One log line: `error` true for failures.
using LogSink = std::function<void(bool error, const std::string& line)>;
/// A watched writer was lost (`lost`) or is back; called on the output thread.
using WriterSink = std::function<void(const schedule::WatchedWriter& writer, bool lost)>;

/// @note restricted thread-safe: start/safeState on one thread while no other runs;
///       updateOutputs/nextOutputDeadlineNs on one thread, onEvent/updateInputs/
///       nextInputDeadlineNs on another (they touch disjoint lines); levels() from any.
class Controller {
 public:
  /// `writers`: whose heartbeats the outputs depend on (schedule.json "writers", the list
  /// and timeouts vcu-can-tx watches); `onWriter` hears of their losses and returns.
  static Result<std::unique_ptr<Controller>> create(const config::GpioMap& map, const signals::Catalog& catalog,
                                                    signals::SignalTable& table, Chip& chip, LogSink log,
                                                    std::vector<schedule::WatchedWriter> writers = {},
                                                    WriterSink onWriter = {});
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;

  /// Requests the lines (see the file comment) and writes every status key.
  Status start(std::int64_t nowNs);

  /// Reads the watched writers' heartbeats first: while one is lost (no beat for its
  /// timeout), every output is at its safe level at once (no on/off-delay) and commands are
  /// not followed; once it beats again they are, each delay counted from its return. A
  /// writer silent when vcu-gpio starts holds the outputs at their start levels until it
  /// beats (lost after its timeout from the start).
  void updateOutputs(std::int64_t nowNs);
  /// The next delay end, retry, or moment a watched writer would count as lost.
  [[nodiscard]] std::int64_t nextOutputDeadlineNs() const noexcept;
  /// true while the outputs follow their commands (no watched writer lost or awaited).
  [[nodiscard]] bool followingCommands() const noexcept { return m_following.load(std::memory_order_relaxed); }

  void onEvent(const LineEvent& event);
  void updateInputs(std::int64_t nowNs);
  [[nodiscard]] std::int64_t nextInputDeadlineNs() const noexcept;

  /// Every output to its safe level (logged), status keys written.
  void safeState(std::int64_t nowNs);
  /// After the signal table lost its values (docs/design/signal-table.md, "Damage"): every
  /// line's status, and the bound value of every input, written again.
  void republish(std::int64_t nowNs) noexcept;

  /// The level of `line` as vcu-gpio last drove or accepted it.
  [[nodiscard]] bool level(std::size_t line) const noexcept { return m_levels[line].load(std::memory_order_relaxed); }
  [[nodiscard]] GpioCounters& counters() noexcept { return m_counters; }
  /// How often a watched writer was lost since the start.
  [[nodiscard]] std::int64_t writersLost() const noexcept { return m_writersLost.load(std::memory_order_relaxed); }
  [[nodiscard]] const config::GpioMap& map() const noexcept { return *m_map; }

 private:
  struct LineState {
    signals::SignalIndex status{};
    signals::SignalIndex bound{};
    // outputs
    bool target{};
    std::int64_t targetSinceNs{};
    std::int64_t retryAtNs{};
    // inputs
    bool raw{};
    std::int64_t rawSinceNs{};
  };

  Controller(const config::GpioMap& map, signals::SignalTable& table, Chip& chip, LogSink log,
             std::vector<LineState> lines, std::vector<schedule::WatchedWriter> writers, WriterSink onWriter) noexcept;
  [[nodiscard]] bool output(std::size_t line) const noexcept;
  [[nodiscard]] std::int64_t dueNs(std::size_t line) const noexcept;
  void drive(std::size_t line, bool level, std::int64_t nowNs, const std::string& why);
  void watchWriters(std::int64_t nowNs);
  void driveSafe(std::int64_t nowNs);
  void writeStatus(std::size_t line, std::int64_t nowNs) noexcept;

  const config::GpioMap* m_map;
  signals::SignalTable* m_table;
  Chip* m_chip;
  LogSink m_log;
  std::vector<LineState> m_lines;
  std::unique_ptr<std::atomic<bool>[]> m_levels;  // per line: driven or accepted level
  GpioCounters m_counters;
  // Watched writers (output thread): m_watches and m_confirmed per writer, made by start().
  std::vector<schedule::WatchedWriter> m_writers;
  WriterSink m_onWriter;
  std::vector<signals::WriterWatch> m_watches;
  std::vector<char> m_confirmed;  ///< beat within its timeout at the start, or since the start
  std::int64_t m_startNs{};
  std::int64_t m_releasedNs{};  ///< when the outputs last began to follow commands again
  std::string m_lostReason;     ///< "writer fsm lost", in the log line of a safe drive
  std::atomic<bool> m_following{true};
  std::atomic<std::int64_t> m_writersLost{};
};

/// "2 s", "150 ms", "0 s".
std::string formatDelay(std::int64_t ns);

}  // namespace openvcu::gpio
