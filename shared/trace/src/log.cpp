#include "openvcu/trace/log.hpp"

#include <algorithm>
#include <fstream>

#include "openvcu/can/log_reader.hpp"

namespace openvcu::trace {
namespace {

constexpr double NS_PER_SECOND = 1e9;
/// Progress is published every this many lines (a power of two minus one: a mask).
constexpr std::uint64_t PROGRESS_EVERY_MASK = 1023;
/// Export is written to the file in chunks of about this size.
constexpr std::size_t EXPORT_CHUNK = 256 * 1024;

/// Lines of the file, for the progress fraction (one cheap pass); 0 when unreadable.
std::uint64_t countLines(const std::string& path) {
  std::uint64_t lines = 0;
  std::ifstream in(path, std::ios::binary);
  char buffer[65536];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    lines += static_cast<std::uint64_t>(std::count(buffer, buffer + in.gcount(), '\n'));
    if (!in) break;
  }
  return lines;
}

std::uint16_t channelIndex(std::vector<std::string>& channels, std::string_view channel) {
  if (!channels.empty() && channels.back() == channel) return static_cast<std::uint16_t>(channels.size() - 1);
  const auto found = std::find(channels.begin(), channels.end(), channel);
  if (found != channels.end()) return static_cast<std::uint16_t>(found - channels.begin());
  channels.emplace_back(channel);
  return static_cast<std::uint16_t>(channels.size() - 1);
}

}  // namespace

double LoadedLog::secondsFromStart(std::size_t row) const noexcept {
  return static_cast<double>(frames[row].frame.timestampNs - frames.front().frame.timestampNs) / NS_PER_SECOND;
}

double LoadedLog::duration() const noexcept {
  return frames.size() < 2 ? 0 : secondsFromStart(frames.size() - 1);
}

std::size_t LoadedLog::matchedCount() const noexcept {
  return static_cast<std::size_t>(
      std::count_if(frames.begin(), frames.end(), [](const LogFrame& f) { return f.message >= 0; }));
}

Result<LoadedLog> loadLog(const std::string& path, const dbc::MessageMatcher& matcher, const LoadOptions& options) {
  const std::uint64_t lines = options.progress != nullptr ? countLines(path) : 0;
  auto openResult = can::LogReader::open(path);
  if (!openResult) return openResult.error();
  can::LogReader& reader = *openResult;
  LoadedLog log;
  while (auto maybeRecord = reader.next()) {
    if (log.frames.size() >= options.maxFrames) {
      log.truncated = true;
      break;
    }
    LogFrame entry;
    entry.frame = maybeRecord->frame;
    entry.frame.timestampNs = loggedTimeNs(*maybeRecord, reader.format());
    entry.message = matcher.match(entry.frame.id, entry.frame.extended());
    entry.channel = channelIndex(log.channels, maybeRecord->channel);
    entry.hasTime = maybeRecord->hasTime;
    log.frames.push_back(entry);
    if (lines > 0 && (reader.lineCount() & PROGRESS_EVERY_MASK) == 0) {
      options.progress->store(static_cast<double>(reader.lineCount()) / static_cast<double>(lines));
    }
  }
  log.malformedLines = reader.errorCount();
  if (reader.lastError()) log.lastError = reader.lastError()->toString();
  if (options.progress != nullptr) options.progress->store(1.0);
  return log;
}

namespace {

/// Appends the frames [first, end) of `log` that are not error frames.
std::size_t appendFrames(std::string& out, const LoadedLog& log, std::size_t first, FrameDecoder& decoder,
                         FrameWriter& writer, std::size_t chunk) {
  std::size_t row = first;
  for (; row < log.frames.size() && out.size() < chunk; ++row) {
    const LogFrame& entry = log.frames[row];
    if ((entry.frame.flags & can::FLAG_ERROR) != 0) continue;
    can::LogRecord record;
    record.frame = entry.frame;
    record.channel = log.channels[entry.channel];
    record.hasTime = entry.hasTime;
    writer.appendFrame(out, record, entry.message, decoder.decode(entry.frame, entry.message));
  }
  return row;
}

}  // namespace

void appendLog(std::string& out, const LoadedLog& log, FrameDecoder& decoder, DecodeFormat format) {
  FrameWriter writer(decoder.database(), format);
  writer.appendHeader(out);
  appendFrames(out, log, 0, decoder, writer, static_cast<std::size_t>(-1));
}

Status exportLog(const std::string& path, const LoadedLog& log, FrameDecoder& decoder, DecodeFormat format) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) return Error{"cannot write", Location{path, 0, 0, {}}};
  FrameWriter writer(decoder.database(), format);
  std::string buffer;
  buffer.reserve(EXPORT_CHUNK + EXPORT_CHUNK / 4);
  writer.appendHeader(buffer);
  std::size_t row = 0;
  do {
    row = appendFrames(buffer, log, row, decoder, writer, EXPORT_CHUNK);
    file.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    buffer.clear();
  } while (row < log.frames.size() && file);
  file.flush();
  if (!file) return Error{"write failed", Location{path, 0, 0, {}}};
  return {};
}

std::optional<SignalRef> findSignal(const dbc::Database& database, std::string_view messageSignal) {
  const std::size_t dot = messageSignal.rfind('.');
  if (dot == std::string_view::npos || dot == 0) return std::nullopt;
  const std::string_view messageName = messageSignal.substr(0, dot);
  const std::string_view signalName = messageSignal.substr(dot + 1);
  for (std::size_t m = 0; m < database.messages.size(); ++m) {
    const dbc::Message& message = database.messages[m];
    if (message.name != messageName) continue;
    for (std::size_t s = 0; s < message.signals.size(); ++s) {
      if (message.signals[s].name == signalName) {
        return SignalRef{static_cast<std::int32_t>(m), static_cast<std::uint32_t>(s)};
      }
    }
  }
  return std::nullopt;
}

std::vector<std::string> signalNames(const LoadedLog& log, const dbc::Database& database) {
  std::vector<std::string> names;
  std::vector<bool> seen(database.messages.size());
  for (const LogFrame& entry : log.frames) {
    if (entry.message < 0 || static_cast<std::size_t>(entry.message) >= seen.size()) continue;
    if (seen[static_cast<std::size_t>(entry.message)]) continue;
    seen[static_cast<std::size_t>(entry.message)] = true;
    const dbc::Message& message = database.messages[static_cast<std::size_t>(entry.message)];
    for (const dbc::Signal& signal : message.signals) {
      if (signal.decodable()) names.push_back(message.name + "." + signal.name);
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

SampleRing extractSamples(const LoadedLog& log, FrameDecoder& decoder, SignalRef signal) {
  const auto count = static_cast<std::size_t>(std::count_if(
      log.frames.begin(), log.frames.end(), [&](const LogFrame& entry) { return entry.message == signal.message; }));
  SampleRing ring(count);
  for (std::size_t row = 0; row < log.frames.size(); ++row) {
    const LogFrame& entry = log.frames[row];
    if (entry.message != signal.message) continue;
    for (const SignalValue& value : decoder.decode(entry.frame, entry.message)) {
      if (value.signalIndex == signal.signal) ring.push(log.secondsFromStart(row), value.value.physical);
    }
  }
  return ring;
}

}  // namespace openvcu::trace
