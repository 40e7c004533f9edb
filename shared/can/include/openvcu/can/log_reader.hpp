#pragma once
// Streaming reader for recorded CAN traffic: candump (-L and the default/-t* console
// formats, auto-detected per line) and Vector ASC. Constant memory whatever the log size:
// one fixed read buffer, lines are parsed in place, records point into that buffer.
//
//   "(1436509052.249713) can0 18FEF100#0102030405060708"
//     -> LogRecord{frame{id 0x18FEF100, FLAG_EXTENDED, length 8, data 01..08,
//                  timestampNs 1436509052249713000}, channel "can0",
//                  timeSeconds 1436509052.249713, hasTime true, line 1, direction 0}
//
//   auto openResult = LogReader::open("drive.log");
//   if (!openResult) { std::cerr << openResult.error().toString() << '\n'; return 1; }
//   while (auto maybeRecord = openResult->next()) { use(maybeRecord->frame); }
//   if (openResult->errorCount() > 0) { ... openResult->lastError()->toString() ... }
//
// Malformed lines never stop the reader and never throw: each one is counted, kept as
// lastError() ("drive.log:12:30: data length 9 exceeds 8 for a classic frame"), passed to
// the error handler if one is set, and reading continues with the next line.
// The formats and their rules are written down in docs/design/can-logs.md.

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "openvcu/can/frame.hpp"
#include "openvcu/core/error.hpp"
#include "openvcu/core/result.hpp"

namespace openvcu::can {

/// Log formats the reader understands.
enum class LogFormat : std::uint8_t {
  Auto,       ///< ASC when the first non-blank lines are ASC headers (or the file ends in .asc), else candump
  Candump,    ///< candump -L and the console formats, detected line by line
  VectorAsc,  ///< Vector ASC (CANalyzer/CANoe ASCII logging)
};

/// One frame read from a log.
struct LogRecord {
  Frame frame{};             ///< timestampNs: ns since 1970 (UTC) or since the start, as logged
  std::string_view channel;  ///< "can0", or the ASC channel number "1"; valid until the next next()
  double timeSeconds{};      ///< the time as written in the log, in seconds (0 when !hasTime)
  bool hasTime{};            ///< false when the line carried no timestamp
  std::uint64_t line{};      ///< 1-based line number in the input
  char direction{};          ///< 'R' received, 'T' transmitted, 0 when the log does not say
};

/// Reads CAN frames one at a time from a log.
/// @note not thread-safe (one thread per reader); next() allocates nothing once the
///       first lines have been read, except to format an error for a malformed line.
class LogReader {
 public:
  /// Lines longer than this are reported as errors and skipped (a valid CAN FD candump
  /// line is under 300 characters; ASC CANFD lines under 600).
  static constexpr std::size_t MAX_LINE_LENGTH = 4096;

  using ErrorHandler = std::function<void(const Error&)>;

  /// Opens a log file. Auto picks ASC for a ".asc" name or ASC header lines.
  /// The file is opened and read under the input-file rule (openvcu/core/input_file.hpp):
  /// a regular file of at most 64 GiB (input::CAN_LOG), so a directory, FIFO or device
  /// fails here ("/dev/zero: not a regular file (character device)"); a SIGTERM/SIGINT
  /// pending while reading ends the input (reported like a read error).
  /// Fails (Error with the file name and the reason) when the file cannot be opened.
  [[nodiscard]] static Result<LogReader> open(const std::string& path, LogFormat format = LogFormat::Auto);

  /// Reads from `input`, which must outlive the reader; `sourceName` names it in errors.
  /// For std::cin call std::ios::sync_with_stdio(false) first: the synchronised stdin
  /// delivers one byte per call (about 9x slower).
  explicit LogReader(std::istream& input, std::string sourceName = "<stream>", LogFormat format = LogFormat::Auto);

  LogReader(LogReader&&) noexcept;
  LogReader& operator=(LogReader&&) noexcept;
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;
  ~LogReader();

  /// The next frame, or empty at the end of the input (or after a read error, which is
  /// reported like a malformed line). Blank lines, `#` and `//` comments are skipped
  /// silently; malformed lines are reported and skipped.
  [[nodiscard]] std::optional<LogRecord> next();

  /// Called once per malformed line, before next() carries on. Optional.
  void setErrorHandler(ErrorHandler handler);

  /// The most recent problem (file, line, column, reason), empty when there was none.
  [[nodiscard]] const std::optional<Error>& lastError() const noexcept;
  /// Malformed lines (and read errors) seen so far.
  [[nodiscard]] std::uint64_t errorCount() const noexcept;
  /// Frames returned so far.
  [[nodiscard]] std::uint64_t recordCount() const noexcept;
  /// Lines consumed so far (the line number of the last line read).
  [[nodiscard]] std::uint64_t lineCount() const noexcept;
  /// The format in use: Auto until the first line that decides it.
  [[nodiscard]] LogFormat format() const noexcept;

 private:
  struct Impl;
  explicit LogReader(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> m_impl;  // on the heap so that moving keeps `channel` views valid
};

}  // namespace openvcu::can
