// vcu dbc decode: stream a CAN log through the DBC codec, constant memory.
#include <fstream>
#include <optional>

#include "dbc_commands.hpp"
#include "dbc_loading.hpp"
#include "diagnostics.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/trace/frame_decoder.hpp"

namespace openvcu::cli {
namespace {

/// Output is handed to the sink in chunks of about this size (why: one fwrite per
/// ~1000 frames instead of one per field).
constexpr std::size_t OUTPUT_CHUNK = 256 * 1024;

struct DecodeCounts {
  std::uint64_t frames{};       ///< frames written
  std::uint64_t matched{};      ///< ... of which matched a message
  std::uint64_t errorFrames{};  ///< SocketCAN error frames, skipped
};

constexpr std::string_view STANDARD_INPUT_NAME = "<stdin>";

/// Opens the log; "-" is standard input, read through /dev/stdin so that the reader gets a
/// buffered file rather than std::cin (which hands over one byte at a time).
std::optional<can::LogReader> openLog(const std::string& path, std::ifstream& standardInput, Sink& err) {
  if (path == "-") {
    standardInput.open("/dev/stdin", std::ios::binary);
    if (!standardInput.is_open()) {
      report(err, Error{"cannot open standard input", Location{std::string(STANDARD_INPUT_NAME), 0, 0, {}}});
      return std::nullopt;
    }
    return can::LogReader(standardInput, std::string(STANDARD_INPUT_NAME));
  }
  Result<can::LogReader> openResult = can::LogReader::open(path);
  if (!openResult) {
    report(err, openResult.error());
    return std::nullopt;
  }
  return std::move(*openResult);
}

}  // namespace

ExitCode runDecode(const DecodeOptions& options, Streams streams) {
  std::optional<dbc::Database> maybeDatabase = loadDatabase(options.dbcFiles, streams.err, false);
  if (!maybeDatabase) return ExitCode::Failure;
  const dbc::Database& database = *maybeDatabase;

  std::ifstream standardInput;
  std::optional<can::LogReader> maybeReader = openLog(options.logFile, standardInput, streams.err);
  if (!maybeReader) return ExitCode::Failure;
  can::LogReader& reader = *maybeReader;
  const std::string logName = options.logFile == "-" ? std::string(STANDARD_INPUT_NAME) : options.logFile;
  std::uint64_t reportedLines = 0;
  reader.setErrorHandler([&](const Error& error) {
    if (reportedLines < MAX_REPORTED_LOG_ERRORS) report(streams.err, error);
    ++reportedLines;
  });

  trace::FrameDecoder decoder(database, options.match);
  FrameWriter writer(database, options.format);
  std::string buffer;
  buffer.reserve(OUTPUT_CHUNK + OUTPUT_CHUNK / 4);
  writer.appendHeader(buffer);

  DecodeCounts counts;
  while (options.limit == 0 || counts.frames < options.limit) {
    std::optional<can::LogRecord> maybeRecord = reader.next();
    if (!maybeRecord) break;
    maybeRecord->frame.timestampNs = trace::loggedTimeNs(*maybeRecord, reader.format());  // ASC: the offset
    const can::Frame& frame = maybeRecord->frame;
    if ((frame.flags & can::FLAG_ERROR) != 0) {
      ++counts.errorFrames;
      continue;
    }
    const std::int32_t messageIndex = decoder.match(frame);
    if (messageIndex != trace::FrameDecoder::NO_MATCH) ++counts.matched;
    writer.appendFrame(buffer, *maybeRecord, messageIndex, decoder.decode(frame, messageIndex));
    ++counts.frames;
    if (buffer.size() >= OUTPUT_CHUNK) {
      streams.out.write(buffer);
      buffer.clear();
      if (streams.out.failed()) break;  // e.g. disk full: reading on is pointless
    }
  }
  streams.out.write(buffer);

  ExitCode exitCode = ExitCode::Ok;
  if (!streams.out.flush()) {
    reportError(streams.err, "cannot write the output: " + streams.out.errorMessage());
    exitCode = ExitCode::Failure;
  }
  const std::uint64_t malformed = reader.errorCount();
  if (malformed > 0) {
    std::string message =
        std::to_string(malformed) + (malformed == 1 ? " malformed line" : " malformed lines") + " skipped";
    if (malformed > MAX_REPORTED_LOG_ERRORS) {
      message += " (the first " + std::to_string(MAX_REPORTED_LOG_ERRORS) + " shown)";
    }
    report(streams.err, Error{std::move(message), Location{logName, 0, 0, {}}});
    exitCode = ExitCode::Failure;
  }
  if (options.stats) {
    streams.err.write(logName + ": " + std::to_string(counts.frames) + " frames, " + std::to_string(counts.matched) +
                      " matched, " + std::to_string(counts.frames - counts.matched) + " unknown, " +
                      std::to_string(counts.errorFrames) + " error frames skipped, " + std::to_string(malformed) +
                      " malformed lines, " + std::to_string(reader.lineCount()) + " lines read\n");
  }
  return exitCode;
}

}  // namespace openvcu::cli
