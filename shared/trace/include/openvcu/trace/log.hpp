#pragma once
// A CAN log in memory for viewing and analysis: loadLog() reads candump -L / candump /
// Vector ASC through shared/can's LogReader, keeps every frame with its DBC message and
// channel; appendLog()/exportLog() write it decoded through FrameWriter (the text
// `vcu dbc decode` writes for the same log and match mode); signalNames(), findSignal()
// and extractSamples() turn one signal into a SampleRing for a plot.
//
//   auto loadResult = loadLog("drive.log", decoder.matcher());
//   if (!loadResult) return loadResult.error();               // "drive.log: No such file ..."
//   exportLog("drive.csv", *loadResult, decoder, DecodeFormat::Csv);
//   auto ref = findSignal(database, "EEC1.EngineSpeed");      // message 3, signal 0
//   SampleRing speed = extractSamples(*loadResult, decoder, *ref);  // s from the first frame

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "openvcu/can/frame.hpp"
#include "openvcu/core/result.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/trace/frame_decoder.hpp"
#include "openvcu/trace/frame_writer.hpp"
#include "openvcu/trace/sample_ring.hpp"

namespace openvcu::trace {

/// One frame of a loaded log.
struct LogFrame {
  can::Frame frame{};        ///< timestampNs: as the log writes it (loggedTimeNs)
  std::int32_t message{-1};  ///< index into Database::messages, or FrameDecoder::NO_MATCH
  std::uint16_t channel{};   ///< index into LoadedLog::channels
  bool hasTime{};            ///< false when the line carried no timestamp
};
static_assert(sizeof(LogFrame) == 88, "a loaded log costs 88 bytes per frame");

/// The frames of one log and what went wrong while reading it.
struct LoadedLog {
  std::vector<LogFrame> frames;
  std::vector<std::string> channels;  ///< "can0", ASC "1": the names the frames index
  std::uint64_t malformedLines{};     ///< skipped lines
  std::string lastError;              ///< the last malformed line: "drive.log:12:30: reason"
  bool truncated{};                   ///< stopped at LoadOptions::maxFrames

  /// Seconds from the first frame to frame `row`.
  [[nodiscard]] double secondsFromStart(std::size_t row) const noexcept;
  /// Seconds from the first to the last frame (0 below two frames).
  [[nodiscard]] double duration() const noexcept;
  /// Frames matched to a DBC message.
  [[nodiscard]] std::size_t matchedCount() const noexcept;
};

struct LoadOptions {
  /// Frames kept from one log (88 bytes each: 1,000,000 frames = 88 MB).
  std::size_t maxFrames{1'000'000};
  /// Written with the fraction of lines read (0..1) while loading, when set (another
  /// thread may read it).
  std::atomic<double>* progress{nullptr};
};

/// Reads the log at `path` (format detected as LogReader does) and matches every frame
/// with `matcher`. Malformed lines are counted and skipped, never fatal; error frames are
/// kept. Fails only when the file cannot be opened (the Error names it).
/// @note allocates; loading path, not per frame. Any thread.
[[nodiscard]] Result<LoadedLog> loadLog(const std::string& path, const dbc::MessageMatcher& matcher,
                                        const LoadOptions& options = {});

/// Appends `log` decoded with `decoder` (the database the log was matched against):
/// FrameWriter's header, then every frame but error frames, as `vcu dbc decode` does.
void appendLog(std::string& out, const LoadedLog& log, FrameDecoder& decoder, DecodeFormat format);

/// appendLog() into the file at `path` (created or truncated). Fails with the path and
/// the reason when the file cannot be written.
[[nodiscard]] Status exportLog(const std::string& path, const LoadedLog& log, FrameDecoder& decoder,
                               DecodeFormat format);

/// One signal of a database: its message and its index in Message::signals.
struct SignalRef {
  std::int32_t message{};
  std::uint32_t signal{};
};

/// The signal named "Message.Signal" (message and signal names as in the DBC); empty when
/// there is none.
[[nodiscard]] std::optional<SignalRef> findSignal(const dbc::Database& database, std::string_view messageSignal);

/// "Message.Signal" of every decodable signal of the messages found in `log`, sorted.
[[nodiscard]] std::vector<std::string> signalNames(const LoadedLog& log, const dbc::Database& database);

/// The (seconds from the first frame, physical value) samples of `signal` in `log`, in a
/// ring sized to hold all of them. Decodes the frames of the signal's message only.
[[nodiscard]] SampleRing extractSamples(const LoadedLog& log, FrameDecoder& decoder, SignalRef signal);

}  // namespace openvcu::trace
