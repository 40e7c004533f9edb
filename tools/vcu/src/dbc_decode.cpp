// vcu dbc decode: stream a CAN log through the DBC codec, constant memory. J1939-21
// transport sessions are reassembled per channel (j1939::TpMonitor) and written as one more
// record after the TP.DT that completed them; sessions that end otherwise as a "tp_end"
// record; DM1/DM2 get their lamps and DTCs.
#include <fstream>
#include <limits>
#include <memory>
#include <optional>

#include "dbc_commands.hpp"
#include "dbc_loading.hpp"
#include "diagnostics.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/j1939/dm1.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/j1939/transport_monitor.hpp"
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
  std::uint64_t tpMessages{};   ///< messages reassembled from J1939-21 sessions
  std::uint64_t tpEnded[j1939::TP_OUTCOME_COUNT]{};  ///< session ends by outcome (tp_end records)
};

/// Priority of the identifier a reassembled message is written and matched with (J1939-21's
/// default for most PGNs; the J1939 matcher ignores it).
constexpr std::uint8_t REASSEMBLED_PRIORITY = 6;
constexpr std::int64_t NO_DEADLINE = std::numeric_limits<std::int64_t>::max();

bool isDm(std::uint32_t pgn) { return pgn == j1939::PGN_DM1 || pgn == j1939::PGN_DM2; }

/// Follows the J1939-21 sessions of every channel and writes what they produce into the
/// output buffer. Memory: one TpMonitor (256 sessions, ~0.6 MB) per channel, made when the
/// channel's first TP frame arrives.
class TransportWriter final : public j1939::TpMonitorSink {
 public:
  TransportWriter(const dbc::Database& database, const dbc::MessageMatcher& matcher, FrameWriter& writer,
                  std::string& out, DecodeCounts& counts)
      : m_matcher(matcher), m_codecs(database), m_writer(writer), m_out(out), m_counts(counts) {
    std::size_t most = 1;
    for (const dbc::Message& message : database.messages) most = std::max(most, message.signals.size());
    m_values.resize(most);
  }

  /// Applies the deadlines due by `nowNs` on every channel (timeouts become tp_end records).
  void poll(std::int64_t nowNs, bool hasTime) {
    if (nowNs < m_nextDeadlineNs) return;
    for (Channel& channel : m_channels) {
      select(channel, hasTime);
      channel.monitor->poll(nowNs, *this);
    }
    refreshDeadline();
  }

  /// One TP.CM / TP.DT frame of `record`'s channel.
  void onFrame(const can::LogRecord& record) {
    Channel& channel = channelOf(record.channel);
    select(channel, record.hasTime);
    channel.monitor->onFrame(record.frame.id, record.frame.payload(), record.frame.timestampNs, *this);
    refreshDeadline();
  }

  /// Sessions still open at the end of the log: tp_end records with outcome Incomplete.
  void finish(std::int64_t endNs, bool hasTime) {
    for (Channel& channel : m_channels) {
      select(channel, hasTime);
      channel.monitor->finish(endNs, *this);
    }
    refreshDeadline();
  }

  void completed(const j1939::TpMonitoredMessage& message) noexcept override {
    const j1939::TpSessionInfo& session = message.session;
    can::LogRecord record = recordFor(session, session.endNs);
    const std::int32_t messageIndex = m_matcher.match(record.frame.id, true);
    std::size_t decoded = 0;
    if (messageIndex != dbc::MessageMatcher::NO_MATCH) {
      m_codecs[static_cast<std::size_t>(messageIndex)].decode(
          message.data, [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
            m_values[decoded++] = trace::SignalValue{signalIndex, value};
          });
    }
    std::optional<j1939::Dm1> dm;
    if (isDm(session.pgn)) dm = j1939::decodeDm1(message.data);
    m_writer.appendTransportMessage(m_out, record, session, messageIndex, {m_values.data(), decoded},
                                    dm ? &*dm : nullptr, session.pgn == j1939::PGN_DM2);
    ++m_counts.tpMessages;
  }

  void ended(const j1939::TpSessionEnd& end) noexcept override {
    ++m_counts.tpEnded[static_cast<std::size_t>(end.outcome)];
    if (end.outcome == j1939::TpOutcome::Completed) return;  // its message was written at its last TP.DT
    const can::LogRecord record = recordFor(end.session, end.session.endNs);
    m_writer.appendTransportEnd(m_out, record, end, m_matcher.match(record.frame.id, true));
  }

 private:
  struct Channel {
    std::string name;
    std::unique_ptr<j1939::TpMonitor> monitor;
  };

  Channel& channelOf(std::string_view name) {
    if (m_last < m_channels.size() && m_channels[m_last].name == name) return m_channels[m_last];
    for (m_last = 0; m_last < m_channels.size(); ++m_last) {
      if (m_channels[m_last].name == name) return m_channels[m_last];
    }
    m_channels.push_back(Channel{std::string(name), std::make_unique<j1939::TpMonitor>()});
    return m_channels.back();
  }

  void select(const Channel& channel, bool hasTime) {
    m_channel = channel.name;
    m_hasTime = hasTime;
  }

  void refreshDeadline() {
    m_nextDeadlineNs = NO_DEADLINE;
    for (const Channel& channel : m_channels) {
      m_nextDeadlineNs = std::min(m_nextDeadlineNs, channel.monitor->nextDeadlineNs().value_or(NO_DEADLINE));
    }
  }

  /// The record a session's output is written as: the channel, the time, and the message's
  /// identifier (priority 6, PGN, source, destination).
  can::LogRecord recordFor(const j1939::TpSessionInfo& session, std::int64_t timeNs) const {
    can::LogRecord record;
    record.frame.id = j1939::Id::fromPgn(session.pgn, REASSEMBLED_PRIORITY, session.source, session.destination).toCanId();
    record.frame.flags = can::FLAG_EXTENDED;
    record.frame.timestampNs = timeNs;
    record.channel = m_channel;
    record.hasTime = m_hasTime;
    return record;
  }

  const dbc::MessageMatcher& m_matcher;
  dbc::DatabaseCodec m_codecs;
  std::vector<trace::SignalValue> m_values;  ///< sized once for the message with the most signals
  FrameWriter& m_writer;
  std::string& m_out;
  DecodeCounts& m_counts;
  std::vector<Channel> m_channels;
  std::size_t m_last{};
  std::string_view m_channel;  ///< the channel whose monitor is running
  bool m_hasTime{};
  std::int64_t m_nextDeadlineNs{NO_DEADLINE};
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
  TransportWriter transport(database, decoder.matcher(), writer, buffer, counts);
  std::int64_t lastTimeNs = 0;
  bool lastHasTime = false;
  while (options.limit == 0 || counts.frames < options.limit) {
    std::optional<can::LogRecord> maybeRecord = reader.next();
    if (!maybeRecord) break;
    maybeRecord->frame.timestampNs = trace::loggedTimeNs(*maybeRecord, reader.format());  // ASC: the offset
    const can::Frame& frame = maybeRecord->frame;
    if ((frame.flags & can::FLAG_ERROR) != 0) {
      ++counts.errorFrames;
      continue;
    }
    lastTimeNs = frame.timestampNs;
    lastHasTime = maybeRecord->hasTime;
    transport.poll(frame.timestampNs, maybeRecord->hasTime);  // timeouts before this frame
    const std::int32_t messageIndex = decoder.match(frame);
    if (messageIndex != trace::FrameDecoder::NO_MATCH) ++counts.matched;
    const std::uint32_t pgn = frame.extended() && (frame.flags & can::FLAG_RTR) == 0 ? j1939::pgnOf(frame.id) : 0;
    std::optional<j1939::Dm1> dm;
    if (isDm(pgn)) dm = j1939::decodeDm1(frame.payload());
    if (dm) {
      writer.appendDmFrame(buffer, *maybeRecord, messageIndex, decoder.decode(frame, messageIndex), *dm,
                           pgn == j1939::PGN_DM2);
    } else {
      writer.appendFrame(buffer, *maybeRecord, messageIndex, decoder.decode(frame, messageIndex));
    }
    ++counts.frames;
    if (pgn == j1939::PGN_TP_CM || pgn == j1939::PGN_TP_DT) transport.onFrame(*maybeRecord);
    if (buffer.size() >= OUTPUT_CHUNK) {
      streams.out.write(buffer);
      buffer.clear();
      if (streams.out.failed()) break;  // e.g. disk full: reading on is pointless
    }
  }
  transport.finish(lastTimeNs, lastHasTime);  // sessions cut off by the end (or --limit)
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
    std::string tp = logName + ": J1939 TP: " + std::to_string(counts.tpMessages) + " messages reassembled";
    for (std::size_t outcome = 0; outcome < j1939::TP_OUTCOME_COUNT; ++outcome) {
      tp += ", " + std::to_string(counts.tpEnded[outcome]) + " " +
            std::string(j1939::tpOutcomeName(static_cast<j1939::TpOutcome>(outcome)));
    }
    streams.err.write(tp + "\n");
  }
  return exitCode;
}

}  // namespace openvcu::cli
