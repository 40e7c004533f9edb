#include "openvcu/can/log_reader.hpp"

#include <cstring>
#include <istream>
#include <limits>
#include <span>

#include "openvcu/core/input_file.hpp"

#include "asc_parser.hpp"
#include "candump_parser.hpp"

namespace openvcu::can {
namespace {

/// Read chunk: big enough that a line never needs more than one refill, small enough to
/// stay in L2. Lines are parsed in place in this buffer.
constexpr std::size_t BUFFER_SIZE = 64 * 1024;
static_assert(BUFFER_SIZE > 2 * LogReader::MAX_LINE_LENGTH);

bool startsWith(std::string_view text, std::string_view prefix) noexcept {
  return text.substr(0, prefix.size()) == prefix;
}

bool endsWithAsc(const std::string& path) noexcept {
  if (path.size() < 4) return false;
  const std::string_view suffix = std::string_view(path).substr(path.size() - 4);
  return detail::equalsIgnoreCase(suffix, ".asc");
}

/// A line that only an ASC log starts with.
bool isAscHeader(std::string_view trimmed) noexcept {
  return startsWith(trimmed, "date ") || startsWith(trimmed, "base ") ||
         startsWith(trimmed, "internal events logged") || startsWith(trimmed, "no internal events logged") ||
         startsWith(trimmed, "Begin Triggerblock") || startsWith(trimmed, "Begin TriggerBlock");
}

}  // namespace

struct LogReader::Impl {
  std::optional<input::InputFile> file;  // set by open()
  std::istream* input{};                 // the constructor's stream (the caller owns it)
  std::string sourceName;
  LogFormat format{LogFormat::Auto};
  detail::AscParser asc;
  ErrorHandler errorHandler;
  std::optional<Error> lastError;
  std::uint64_t errorCount{};
  std::uint64_t recordCount{};
  std::uint64_t lineNumber{};
  bool afterErrorFrame{};  // candump -e continues an error frame on lines starting with a TAB

  std::unique_ptr<char[]> buffer{new char[BUFFER_SIZE]};
  std::size_t begin{};    // first unread byte
  std::size_t end{};      // one past the last byte read
  std::size_t scanned{};  // bytes after `begin` already searched for '\n'
  bool endOfInput{};
  bool discarding{};  // inside a line longer than MAX_LINE_LENGTH

  void report(std::uint32_t column, std::string_view message) {
    ++errorCount;
    if (!lastError) lastError.emplace();
    lastError->message.clear();  // keeps the capacity of the previous error
    appendEscapedControlCharacters(lastError->message, message);  // a CR quoted from the line stays printable
    lastError->location.file.assign(sourceName);
    constexpr auto MAX_LINE = std::numeric_limits<std::uint32_t>::max();
    lastError->location.line = lineNumber > MAX_LINE ? MAX_LINE : static_cast<std::uint32_t>(lineNumber);
    lastError->location.column = column;
    if (errorHandler) errorHandler(*lastError);
  }

  /// Moves up to `space` bytes from the input into `destination`; 0 at the end. A file
  /// opened by open() is read under the input-file rule: a pending SIGTERM/SIGINT, growth
  /// beyond input::CAN_LOG's limit or a read error ends the input and is reported.
  std::size_t fill(char* destination, std::size_t space) {
    if (file) {
      const input::InputFile::ReadOutcome outcome = file->read(std::span<char>(destination, space));
      if (outcome.status == input::InputFile::ReadStatus::Data) return outcome.count;
      if (outcome.status != input::InputFile::ReadStatus::End) report(0, file->describe(outcome).message);
      return 0;
    }
    return fillFromStream(destination, space);
  }

  /// Moves up to `space` bytes from the stream into `destination` without waiting for
  /// more than is already available once one byte has arrived (keeps `candump | tool` live).
  std::size_t fillFromStream(char* destination, std::size_t space) {
    try {
      std::streambuf* source = input->rdbuf();
      if (source == nullptr) return 0;
      std::streamsize available = source->in_avail();
      std::size_t count = 0;
      if (available <= 0) {
        const auto first = source->sbumpc();
        if (std::char_traits<char>::eq_int_type(first, std::char_traits<char>::eof())) return 0;
        destination[count++] = std::char_traits<char>::to_char_type(first);
        available = source->in_avail();
      }
      if (available > 0 && count < space) {
        const auto want = static_cast<std::streamsize>(space - count) < available
                              ? static_cast<std::streamsize>(space - count)
                              : available;
        count += static_cast<std::size_t>(source->sgetn(destination + count, want));
      }
      return count;
    } catch (...) {  // a stream with exceptions enabled, or a throwing custom streambuf
      report(0, "read error");
      return 0;
    }
  }

  /// The next line without its line ending; `overlong` when it exceeded MAX_LINE_LENGTH
  /// (then `line` is empty). false at the end of the input.
  bool readLine(std::string_view& line, bool& overlong) {
    overlong = false;
    for (;;) {
      const std::size_t pending = end - begin;
      const void* newline = std::memchr(buffer.get() + begin + scanned, '\n', pending - scanned);
      if (newline != nullptr) {
        const std::size_t length = static_cast<std::size_t>(static_cast<const char*>(newline) - (buffer.get() + begin));
        line = std::string_view(buffer.get() + begin, length);
        begin += length + 1;
        scanned = 0;
        if (discarding || length > LogReader::MAX_LINE_LENGTH) {
          discarding = false;
          overlong = true;
          line = {};
        } else if (!line.empty() && line.back() == '\r') {
          line.remove_suffix(1);
        }
        return true;
      }
      scanned = pending;
      if (pending > LogReader::MAX_LINE_LENGTH) {  // keep memory bounded: drop the line's bytes
        discarding = true;
        begin = end = scanned = 0;
      }
      if (endOfInput) {
        if (begin == end && !discarding) return false;
        line = std::string_view(buffer.get() + begin, end - begin);  // no final newline
        begin = end = scanned = 0;
        overlong = discarding;
        if (discarding) line = {};
        discarding = false;
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        return true;
      }
      if (begin > 0) {
        std::memmove(buffer.get(), buffer.get() + begin, end - begin);
        end -= begin;
        begin = 0;
      }
      const std::size_t count = fill(buffer.get() + end, BUFFER_SIZE - end);
      if (count == 0) endOfInput = true;
      end += count;
    }
  }

  /// Decides the format from the first significant line when it is still Auto.
  void detectFormat(std::string_view trimmed) noexcept {
    format = isAscHeader(trimmed) ? LogFormat::VectorAsc : LogFormat::Candump;
  }

  std::optional<LogRecord> next() {
    std::string_view line;
    bool overlong = false;
    while (readLine(line, overlong)) {
      ++lineNumber;
      if (overlong) {
        report(1, "line longer than 4096 characters");
        continue;
      }
      if (lineNumber == 1 && startsWith(line, "\xEF\xBB\xBF")) line.remove_prefix(3);  // UTF-8 BOM
      const bool continuation = afterErrorFrame && !line.empty() && line[0] == '\t';
      afterErrorFrame = false;
      std::size_t first = 0;
      while (first < line.size() && detail::isSpace(line[first])) ++first;
      const std::string_view trimmed = line.substr(first);
      if (continuation || trimmed.empty() || trimmed[0] == '#' || startsWith(trimmed, "//")) continue;
      if (format == LogFormat::Auto) detectFormat(trimmed);

      LogRecord record;
      record.line = lineNumber;
      detail::LineError error;
      const detail::LineResult result = format == LogFormat::VectorAsc ? asc.parseLine(line, record, error)
                                                                       : detail::parseCandumpLine(line, record, error);
      if (result == detail::LineResult::Frame) {
        ++recordCount;
        afterErrorFrame = (record.frame.flags & FLAG_ERROR) != 0;
        return record;
      }
      if (result == detail::LineResult::Error) report(error.column, error.message);
    }
    return std::nullopt;
  }
};

LogReader::LogReader(std::unique_ptr<Impl> impl) noexcept : m_impl(std::move(impl)) {}

LogReader::LogReader(std::istream& input, std::string sourceName, LogFormat format) : m_impl(std::make_unique<Impl>()) {
  m_impl->input = &input;
  m_impl->sourceName = std::move(sourceName);
  m_impl->format = format;
}

Result<LogReader> LogReader::open(const std::string& path, LogFormat format) {
  Result<input::InputFile> openResult = input::InputFile::open(path, input::CAN_LOG);
  if (!openResult) {
    Error error = openResult.error();
    constexpr std::string_view CANNOT_OPEN = "cannot open: ";
    if (error.message.compare(0, CANNOT_OPEN.size(), CANNOT_OPEN) == 0) {
      error.message.replace(0, CANNOT_OPEN.size(), "cannot open log: ");
    }
    return error;
  }
  auto impl = std::make_unique<Impl>();
  impl->file.emplace(std::move(*openResult));
  impl->sourceName = path;
  impl->format = (format == LogFormat::Auto && endsWithAsc(path)) ? LogFormat::VectorAsc : format;
  return LogReader(std::move(impl));
}

LogReader::LogReader(LogReader&&) noexcept = default;
LogReader& LogReader::operator=(LogReader&&) noexcept = default;
LogReader::~LogReader() = default;

std::optional<LogRecord> LogReader::next() {
  return m_impl->next();
}
void LogReader::setErrorHandler(ErrorHandler handler) {
  m_impl->errorHandler = std::move(handler);
}
const std::optional<Error>& LogReader::lastError() const noexcept {
  return m_impl->lastError;
}
std::uint64_t LogReader::errorCount() const noexcept {
  return m_impl->errorCount;
}
std::uint64_t LogReader::recordCount() const noexcept {
  return m_impl->recordCount;
}
std::uint64_t LogReader::lineCount() const noexcept {
  return m_impl->lineNumber;
}
LogFormat LogReader::format() const noexcept {
  return m_impl->format;
}

}  // namespace openvcu::can
