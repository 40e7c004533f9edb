#pragma once
// The `replay:FILE` link: a recorded log (candump -L, candump console formats, Vector ASC;
// see log_reader.hpp) played as a bus, with its original timing.
//
//   (1.000000) can0 123#11      -> due at T (T = the first receive() call)
//   (1.020000) can0 123#22      -> due at T + 20 ms (speed 1), T + 10 ms (speed 2)
//   (1.010000) can0 123#33      -> back in time: due at once (T + 20 ms), counted
//     can0  124   [1]  44       -> no timestamp: due at once after the previous frame
//
// Timing: frame i is due at T + (t_i - t_0) / replaySpeed, an absolute deadline on
// CLOCK_MONOTONIC, so waiting never accumulates drift. The wait handle is a timerfd armed
// (TIMER_ABSTIME) at the next frame's due time; receive() returns every frame due by now.
// replaySpeed 0 plays as fast as possible: every frame is due at once, receive() fills
// `out` and the handle stays readable while frames remain.
// ReceivedFrame.frame.timestampNs is the logged time; monotonicNs the due time (speed 0:
// the time of the receive() call that delivered it).
//
// Timestamps that go back: played at once after the previous frame and counted
// (backwardTimestamps()). The schedule stays anchored to the first frame, so small
// reorderings (channels merged into one log) cost no drift; a step back of more than
// REBASE_BACKSTEP_NS is taken as a new recording (logs joined end to end), and the frames
// after it keep their own spacing from there.
//
// End of the log: with replayLoop, a ReplayRestarted event and the log plays again from
// the top with a new time base (its first frame is due at once, no catch-up burst);
// without, a ReplayFinished event, up() turns false and the wait handle stays quiet.
//
// Design: docs/design/replay-and-bus-load.md.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "openvcu/can/link.hpp"
#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::can {

/// A log played as a bus. The counters below are what a replay adds to Link.
/// @note restricted thread-safe: one thread at a time. receive(), send() and nextEvent()
///       are noexcept, never block and allocate nothing per frame; at the end of a looping
///       log receive() reopens the file (one allocation per pass).
class ReplayLink : public Link {
 public:
  /// A step back in logged time larger than this starts a new time base: 1 s.
  static constexpr std::int64_t REBASE_BACKSTEP_NS = 1'000'000'000;
  /// Records receive() may skip (other channels, rejected by the filters) in one call
  /// before it returns to the event loop, the wait handle left readable.
  static constexpr std::size_t SKIP_BUDGET = 4096;

  /// Opens `path` and reads ahead to the first frame of options.replayChannel (any
  /// channel when empty). Fails, naming "replay:PATH" and the reason, when the file cannot
  /// be opened, holds no such frame, replaySpeed is negative or not a number, or the
  /// timerfd cannot be created. The first frame is due at the first receive() call; the
  /// wait handle is readable from the start.
  [[nodiscard]] static Result<std::unique_ptr<ReplayLink>> open(const std::string& path, const LinkOptions& options);

  /// Lines the log reader skipped as malformed, over every pass of a looping replay.
  [[nodiscard]] virtual std::uint64_t malformedLines() const noexcept = 0;
  /// Frames whose logged time was earlier than the previous frame's (played at once).
  [[nodiscard]] virtual std::uint64_t backwardTimestamps() const noexcept = 0;
  /// Times a looping replay started again from the top.
  [[nodiscard]] virtual std::uint64_t restarts() const noexcept = 0;
  /// The most recent problem with the log ("drive.log:12:30: invalid hex digit 'G' in
  /// data", or why it could not be reopened), empty when there was none. Copies (allocates).
  [[nodiscard]] virtual std::optional<Error> lastLogError() const = 0;
};

/// ReplayLink::open() as a Link, for openLink().
[[nodiscard]] Result<std::unique_ptr<Link>> openReplayLink(const std::string& path, const LinkOptions& options);

}  // namespace openvcu::can
