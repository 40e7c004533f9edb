// The schedule sheet import: CSV text -> records -> per-message rows (checked against the
// DBC as they come) -> per-message checks -> the schedule JSON. The rules are in the header.
#include "openvcu/schedule/schedule_import.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/transmit_limits.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/j1939/id.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::schedule {

namespace {

using Json = nlohmann::ordered_json;

/// SAE J1939-76 Safety Header Message PGN 0x0E00 (3584): sent with its SDM, never listed.
constexpr std::uint32_t SAFETY_HEADER_PGN = 0x0E00;
/// The largest 29-bit CAN identifier, 0x1FFFFFFF (536870911).
constexpr std::uint64_t MAX_CAN_ID = 0x1FFF'FFFF;
/// Integral doubles below this magnitude are written as JSON integers ("3", not "3.0").
constexpr double MAX_EXACT_INTEGER = 9007199254740992.0;  // 2^53
constexpr std::string_view UTF8_BOM = "\xEF\xBB\xBF";

enum class Column : std::uint8_t { NodeName, SheetName, UniqueId, Message, Signal, DeltaTime, IsShm, CycleTime, Value };
static_assert(SCHEDULE_CSV_COLUMNS.size() == static_cast<std::size_t>(Column::Value) + 1);

std::string_view columnName(Column column) noexcept {
  return SCHEDULE_CSV_COLUMNS[static_cast<std::size_t>(column)];
}

/// "NodeName,SheetName,...,Value": the header the sheet needs.
std::string columnList() {
  std::string text;
  for (const std::string_view name : SCHEDULE_CSV_COLUMNS) {
    if (!text.empty()) text += ',';
    text += name;
  }
  return text;
}

// ---- diagnostics -------------------------------------------------------------------------

/// Collects what the import finds; line 0 means "the whole file".
class Diagnostics {
 public:
  explicit Diagnostics(const std::string& fileName) : m_fileName(fileName) {}

  void error(std::uint32_t line, std::string message) { add(line, std::move(message), Severity::Error); }
  void warning(std::uint32_t line, std::string message) { add(line, std::move(message), Severity::Warning); }
  void note(std::uint32_t line, std::string message) { add(line, std::move(message), Severity::Note); }
  /// An error about the command line rather than a row: no file in its location.
  void optionError(std::string message) {
    m_entries.push_back(Entry{NO_LINE, Error{std::move(message)}});
    ++m_errors;
  }
  void optionWarning(std::string message) {
    m_entries.push_back(Entry{NO_LINE, Error{std::move(message), {}, Severity::Warning}});
  }

  [[nodiscard]] std::size_t errorCount() const noexcept { return m_errors; }

  /// Everything in line order (whole-file and command-line entries last).
  [[nodiscard]] std::vector<Error> sorted() const {
    std::vector<Entry> entries = m_entries;
    std::stable_sort(entries.begin(), entries.end(),
                     [](const Entry& a, const Entry& b) { return a.sortLine < b.sortLine; });
    std::vector<Error> errors;
    errors.reserve(entries.size());
    for (Entry& entry : entries) errors.push_back(std::move(entry.error));
    return errors;
  }

 private:
  static constexpr std::uint32_t NO_LINE = UINT32_MAX;
  struct Entry {
    std::uint32_t sortLine{};
    Error error;
  };

  void add(std::uint32_t line, std::string message, Severity severity) {
    m_entries.push_back(
        Entry{line == 0 ? NO_LINE - 1 : line, Error{std::move(message), Location{m_fileName, line, 0, {}}, severity}});
    if (severity == Severity::Error) ++m_errors;
  }

  const std::string& m_fileName;
  std::vector<Entry> m_entries;
  std::size_t m_errors{};
};

// ---- CSV ---------------------------------------------------------------------------------

struct CsvRecord {
  std::uint32_t line{};  ///< where the record starts (1-based)
  std::vector<std::string> fields;
};

bool isBlank(char c) noexcept {
  return c == ' ' || c == '\t';
}

std::string_view trimmed(std::string_view text) noexcept {
  while (!text.empty() && isBlank(text.front())) text.remove_prefix(1);
  while (!text.empty() && isBlank(text.back())) text.remove_suffix(1);
  return text;
}

/// Splits RFC 4180 text into records: "," between fields, LF or CRLF (or a lone CR) after
/// a record, fields in double quotes may hold separators, line breaks and doubled quotes.
/// Unquoted fields are trimmed; records whose fields are all empty are dropped. A record
/// with a malformed quote is reported and dropped.
std::vector<CsvRecord> splitCsv(std::string_view text, Diagnostics& diagnostics) {
  std::vector<CsvRecord> records;
  std::size_t pos = 0;
  std::uint32_t line = 1;
  const auto atRecordEnd = [&] { return pos >= text.size() || text[pos] == '\r' || text[pos] == '\n'; };
  const auto skipLineBreak = [&] {
    if (pos < text.size() && text[pos] == '\r') ++pos;
    if (pos < text.size() && text[pos] == '\n') ++pos;
    ++line;
  };
  while (pos < text.size()) {
    CsvRecord record{line, {}};
    bool malformed = false;
    for (;;) {
      while (pos < text.size() && isBlank(text[pos])) ++pos;
      std::string field;
      if (pos < text.size() && text[pos] == '"') {
        const std::uint32_t openLine = line;
        ++pos;
        bool closed = false;
        while (pos < text.size()) {
          const char c = text[pos++];
          if (c == '"') {
            if (pos < text.size() && text[pos] == '"') {
              field += '"';
              ++pos;
              continue;
            }
            closed = true;
            break;
          }
          if (c == '\n') ++line;
          field += c;
        }
        if (!closed) {
          diagnostics.error(openLine, "the quoted field opened here never closes (a '\"' is missing)");
          return records;
        }
        while (pos < text.size() && isBlank(text[pos])) ++pos;
        if (!atRecordEnd() && text[pos] != ',') {
          diagnostics.error(record.line, "text after a closing quote (quote a '\"' inside a field by doubling it)");
          malformed = true;
          while (!atRecordEnd()) ++pos;  // the rest of the line
        }
      } else {
        const std::size_t begin = pos;
        while (!atRecordEnd() && text[pos] != ',') ++pos;
        field = std::string(trimmed(text.substr(begin, pos - begin)));
      }
      record.fields.push_back(std::move(field));
      if (pos < text.size() && text[pos] == ',') {
        ++pos;
        continue;
      }
      skipLineBreak();
      break;
    }
    const bool allEmpty =
        std::all_of(record.fields.begin(), record.fields.end(), [](const std::string& f) { return f.empty(); });
    if (!malformed && !allEmpty) records.push_back(std::move(record));
  }
  return records;
}

// ---- field values ------------------------------------------------------------------------

bool equalsIgnoringCase(std::string_view a, std::string_view b) noexcept {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

/// Empty, or pandas' "nan" for an empty cell.
bool isEmptyCell(std::string_view text) noexcept {
  return text.empty() || equalsIgnoringCase(text, "nan");
}

std::optional<double> parseNumber(std::string_view text) noexcept {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc{} || ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

/// A whole number written in decimal ("61427", pandas' "61427.0") or 0x-hex.
std::optional<std::uint64_t> parseWholeNumber(std::string_view text) noexcept {
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
    std::uint64_t value = 0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data() + 2, end, value, 16);
    if (ec != std::errc{} || ptr != end) return std::nullopt;
    return value;
  }
  const auto maybeNumber = parseNumber(text);
  if (!maybeNumber || *maybeNumber < 0 || *maybeNumber > 1e18 || std::trunc(*maybeNumber) != *maybeNumber) {
    return std::nullopt;
  }
  return static_cast<std::uint64_t>(*maybeNumber);
}

std::optional<bool> parseFlag(std::string_view text) noexcept {
  for (const std::string_view yes : {"1", "true", "yes"}) {
    if (equalsIgnoringCase(text, yes)) return true;
  }
  for (const std::string_view no : {"0", "false", "no"}) {
    if (equalsIgnoringCase(text, no)) return false;
  }
  if (const auto maybeNumber = parseNumber(text); maybeNumber && (*maybeNumber == 0.0 || *maybeNumber == 1.0)) {
    return *maybeNumber == 1.0;  // pandas writes a numeric column as "1.0"
  }
  return std::nullopt;
}

/// What a sheet name says about J1939-76: "shm" -> true, "nonshm" -> false, else nothing.
std::optional<bool> sheetSaysShm(std::string_view sheet) {
  std::string folded;
  for (const char c : sheet) {
    if (c == '-' || c == '_' || c == ' ') continue;
    folded += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (folded == "shm") return true;
  if (folded == "nonshm") return false;
  return std::nullopt;
}

std::string formatNumberText(double value) {
  std::array<char, 32> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc{} ? std::string(text.data(), end) : std::string("?");
}

std::string hexText(std::uint64_t value) {
  std::array<char, 24> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value, 16);
  std::string digits(text.data(), ec == std::errc{} ? end : text.data());
  std::transform(digits.begin(), digits.end(), digits.begin(),
                 [](char c) { return static_cast<char>(std::toupper(static_cast<unsigned char>(c))); });
  return "0x" + digits;
}

std::string idText(const dbc::Message& message) {
  std::string digits = hexText(message.id).substr(2);
  const std::size_t width = message.extended ? 8 : 3;
  if (digits.size() < width) digits.insert(0, width - digits.size(), '0');
  return "0x" + digits;
}

/// "3" for integral values, else the shortest text that reads back the same.
Json jsonNumber(double value) {
  if (std::trunc(value) == value && std::fabs(value) < MAX_EXACT_INTEGER) return static_cast<std::int64_t>(value);
  return value;
}

bool validSignalNamePart(std::string_view name) noexcept {
  if (name.empty() || name.front() == '.' || name.back() == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.';
  });
}

std::string lineText(std::uint32_t line) {
  return "line " + std::to_string(line);
}

std::string suggestion(std::string_view word, const std::vector<std::string>& candidates) {
  if (const auto maybeName = text::didYouMean(word, candidates)) return " (did you mean '" + *maybeName + "'?)";
  return {};
}

// ---- the rows of one message ----------------------------------------------------------------

/// A per-message value and the line that first gave it.
template <typename T>
struct Given {
  T value{};
  std::uint32_t line{};
};

struct SignalValue {
  const dbc::Signal* signal{};
  double value{};
  std::uint32_t line{};
};

struct MessageRows {
  const dbc::Message* message{};
  std::uint32_t firstLine{};
  std::optional<Given<std::string>> node;
  std::optional<Given<std::uint32_t>> cycleMs;
  std::optional<Given<bool>> shm;
  std::optional<Given<std::int64_t>> deltaUs;
  std::string deltaText;                    ///< DeltaTime as written, for messages
  std::optional<Given<bool>> sheetSaysShm;  ///< the first row whose SheetName says shm / nonshm
  std::string sheetName;
  std::vector<SignalValue> values;
};

class Importer {
 public:
  Importer(const dbc::Database& database, const ImportOptions& options, Diagnostics& diagnostics)
      : m_database(database), m_options(options), m_diagnostics(diagnostics) {
    for (const dbc::Message& message : database.messages) {
      if (!message.pseudo) m_messageNames.push_back(message.name);
    }
  }

  /// Reads the header; false (after reporting) when the rows cannot be interpreted.
  bool header(const CsvRecord& record) {
    m_columnIndex.fill(NOT_FOUND);
    if (record.fields.size() == 1 && record.fields.front().find(';') != std::string::npos) {
      m_diagnostics.error(record.line,
                          "the header is separated by ';', not ','; export the sheet as comma-separated "
                          "CSV (the header needs " +
                              columnList() + ")");
      return false;
    }
    std::vector<std::string> expected(SCHEDULE_CSV_COLUMNS.begin(), SCHEDULE_CSV_COLUMNS.end());
    bool good = true;
    for (std::size_t i = 0; i < record.fields.size(); ++i) {
      const std::string& name = record.fields[i];
      const auto known = std::find(SCHEDULE_CSV_COLUMNS.begin(), SCHEDULE_CSV_COLUMNS.end(), name);
      if (known == SCHEDULE_CSV_COLUMNS.end()) {
        std::string message = "unknown column '" + name + "'";
        if (const auto maybeName = text::didYouMean(name, expected)) {
          message += " (did you mean '" + *maybeName + "'?)";
        } else {
          message += " (the columns are " + columnList() + ")";
        }
        m_diagnostics.error(record.line, std::move(message));
        good = false;
        continue;
      }
      std::size_t& slot = m_columnIndex[static_cast<std::size_t>(known - SCHEDULE_CSV_COLUMNS.begin())];
      if (slot != NOT_FOUND) {
        m_diagnostics.error(record.line, "column '" + name + "' appears twice");
        good = false;
        continue;
      }
      slot = i;
    }
    std::string missing;
    for (std::size_t c = 0; c < SCHEDULE_CSV_COLUMNS.size(); ++c) {
      if (m_columnIndex[c] != NOT_FOUND) continue;
      missing += (missing.empty() ? "'" : ", '") + std::string(SCHEDULE_CSV_COLUMNS[c]) + "'";
    }
    if (!missing.empty()) {
      m_diagnostics.error(record.line, "missing column" +
                                           std::string(missing.find(',') != std::string::npos ? "s " : " ") + missing +
                                           " (the header needs " + columnList() + ")");
      good = false;
    }
    m_columnCount = record.fields.size();
    return good;
  }

  void row(const CsvRecord& record) {
    ++m_rowCount;
    if (record.fields.size() != m_columnCount) {
      m_diagnostics.error(record.line, std::to_string(record.fields.size()) + " fields, but the header has " +
                                           std::to_string(m_columnCount) + " columns");
      return;
    }
    m_line = record.line;
    m_record = &record;
    MessageRows* rows = messageRows(field(Column::Message));
    if (rows == nullptr) return;
    const dbc::Message& message = *rows->message;
    nodeName(*rows);
    uniqueId(message);
    cycleTime(*rows);
    isShm(*rows);
    deltaTime(*rows);
    if (const auto maybeSays = sheetSaysShm(field(Column::SheetName)); maybeSays && !rows->sheetSaysShm) {
      rows->sheetSaysShm = Given<bool>{*maybeSays, m_line};
      rows->sheetName = field(Column::SheetName);
    }
    signalValue(*rows);
  }

  /// The per-message checks and the JSON; call after every row.
  Json finish() {
    if (m_rowCount == 0) m_diagnostics.error(0, "no rows after the header: nothing to import");
    for (const MessageRows& rows : m_messages) checkMessage(rows);
    const std::vector<Group> groups = sendGroups();

    // ordered_json keeps its members in a vector: no reference into it survives an insertion,
    // so each part is built on its own and moved in, in the order of the output.
    Json include = Json::array();
    Json messages = Json::object();
    for (const MessageRows& rows : m_messages) {
      include.push_back(rows.message->name);
      Json entry = Json::object();
      entry["cycleMs"] = rows.cycleMs ? rows.cycleMs->value : 0;
      if (rows.node) entry["group"] = rows.node->value;
      if (!rows.values.empty()) {
        Json values = Json::object();
        for (const SignalValue& value : rows.values) values[value.signal->name] = jsonNumber(value.value);
        entry["values"] = std::move(values);
      }
      if (isSdm(rows)) entry["safety"] = Json{{"deltaUs", rows.deltaUs ? rows.deltaUs->value : 0}};
      messages[rows.message->name] = std::move(entry);
    }
    Json schedule = Json::object();
    schedule["include"] = std::move(include);
    schedule["messages"] = std::move(messages);
    if (!groups.empty()) {
      Json groupsJson = Json::object();
      for (const Group& group : groups) groupsJson[group.name] = Json{{"signal", group.key}};
      schedule["groups"] = std::move(groupsJson);
    }
    return schedule;
  }

 private:
  static constexpr std::size_t NOT_FOUND = SIZE_MAX;

  struct Group {
    std::string name;
    std::string key;
  };

  [[nodiscard]] const std::string& field(Column column) const {
    return m_record->fields[m_columnIndex[static_cast<std::size_t>(column)]];
  }

  static bool isSdm(const MessageRows& rows) noexcept { return rows.shm && rows.shm->value; }

  /// The rows of the message named `name`, created on first sight; nullptr after
  /// reporting an unknown or unlistable message.
  MessageRows* messageRows(const std::string& name) {
    if (name.empty()) {
      m_diagnostics.error(m_line, "no Message: every row names the message it belongs to");
      return nullptr;
    }
    if (const auto known = m_messageIndex.find(name); known != m_messageIndex.end()) return &m_messages[known->second];
    const dbc::Message* message = m_database.findMessage(name);
    if (message == nullptr || message->pseudo) {
      m_diagnostics.error(m_line, "unknown message '" + name + "'" + suggestion(name, m_messageNames));
      return nullptr;
    }
    if (message->extended && j1939::pgnOf(message->id) == SAFETY_HEADER_PGN) {
      m_diagnostics.error(m_line, "'" + name +
                                      "' is a J1939-76 safety header (PGN 0x0E00): it goes out with its SDM; "
                                      "list the SDM with IsSHM 1 instead");
      return nullptr;
    }
    if (!m_options.node.empty()) {
      if (!config::sentBy(*message, m_options.node)) {
        const std::vector<std::string> transmitters = message->transmitters();
        m_diagnostics.warning(m_line, "message '" + name + "' is transmitted by " +
                                          (transmitters.empty() ? std::string("no node") : transmitters.front()) +
                                          ", not by " + m_options.node);
      }
    }
    m_messageIndex.emplace(name, m_messages.size());
    MessageRows& rows = m_messages.emplace_back();
    rows.message = message;
    rows.firstLine = m_line;
    return &rows;
  }

  /// Records a per-message value, or reports that it disagrees with an earlier row.
  template <typename T>
  void agree(std::optional<Given<T>>& slot, const T& value, Column column, const std::string& shown,
             const std::string& earlierShown, const dbc::Message& message) {
    if (!slot) {
      slot = Given<T>{value, m_line};
      return;
    }
    if (slot->value == value) return;
    m_diagnostics.error(m_line, std::string(columnName(column)) + " " + shown + " of message '" + message.name +
                                    "' disagrees with " + earlierShown + " on " + lineText(slot->line));
  }

  void nodeName(MessageRows& rows) {
    const std::string& node = field(Column::NodeName);
    if (node.empty()) return;
    const std::string earlier = rows.node ? "'" + rows.node->value + "'" : std::string();
    agree(rows.node, node, Column::NodeName, "'" + node + "'", earlier, *rows.message);
  }

  void uniqueId(const dbc::Message& message) {
    const std::string& text = field(Column::UniqueId);
    if (isEmptyCell(text)) return;
    const auto maybeId = parseWholeNumber(text);
    if (!maybeId || *maybeId > MAX_CAN_ID) {
      m_diagnostics.error(m_line, "UniqueID '" + text + "' is not a CAN ID or PGN (0x-hex or decimal)");
      return;
    }
    const std::uint64_t id = *maybeId;
    bool matches = id == message.id;
    std::string described = "ID " + idText(message);
    if (message.extended) {
      const std::uint32_t pgn = j1939::pgnOf(message.id);
      const std::uint32_t pgnField = (message.id >> 8) & j1939::PGN_MASK;  // PDU1: the destination kept
      matches = matches || id == pgn || id == pgnField;
      described += ", PGN " + hexText(pgn) + " (" + std::to_string(pgn) + ")";
      if (pgnField != pgn) described += " or " + hexText(pgnField) + " (" + std::to_string(pgnField) + ") with its DA";
    }
    if (!matches) {
      m_diagnostics.error(m_line, "UniqueID " + text + " is not message '" + message.name + "' (" + described + ")");
    }
  }

  void cycleTime(MessageRows& rows) {
    const std::string& text = field(Column::CycleTime);
    if (isEmptyCell(text)) return;
    const auto maybeMs = parseWholeNumber(text);
    if (!maybeMs || config::checkCycleMs(static_cast<double>(*maybeMs))) {
      m_diagnostics.error(m_line, "CycleTime '" + text + "' is not whole milliseconds " +
                                      std::to_string(config::MIN_CYCLE_MS) + ".." +
                                      std::to_string(config::MAX_CYCLE_MS));
      return;
    }
    const auto ms = static_cast<std::uint32_t>(*maybeMs);
    const std::string earlier = rows.cycleMs ? std::to_string(rows.cycleMs->value) : std::string();
    agree(rows.cycleMs, ms, Column::CycleTime, std::to_string(ms), earlier, *rows.message);
  }

  void isShm(MessageRows& rows) {
    const std::string& text = field(Column::IsShm);
    if (isEmptyCell(text)) return;
    const auto maybeFlag = parseFlag(text);
    if (!maybeFlag) {
      m_diagnostics.error(m_line, "IsSHM '" + text + "' is not 1/0, true/false or yes/no");
      return;
    }
    const auto shown = [](bool flag) { return std::string(flag ? "1" : "0"); };
    const std::string earlier = rows.shm ? shown(rows.shm->value) : std::string();
    agree(rows.shm, *maybeFlag, Column::IsShm, shown(*maybeFlag), earlier, *rows.message);
  }

  void deltaTime(MessageRows& rows) {
    const std::string& text = field(Column::DeltaTime);
    if (isEmptyCell(text)) return;
    const auto maybeMs = parseNumber(text);
    if (!maybeMs || *maybeMs < 0) {
      m_diagnostics.error(m_line, "DeltaTime '" + text + "' is not a number of milliseconds >= 0");
      return;
    }
    const double us = std::round(*maybeMs * 1000.0);
    if (us > static_cast<double>(config::MAX_CYCLE_MS) * 1000.0) {
      m_diagnostics.error(m_line, "DeltaTime '" + text + "' ms is longer than any cycle time");
      return;
    }
    if (us == 0 && *maybeMs > 0) {
      m_diagnostics.error(m_line, "DeltaTime " + text + " ms rounds to 0 microseconds");
      return;
    }
    const auto deltaUs = static_cast<std::int64_t>(us);
    const std::string earlier = rows.deltaUs ? rows.deltaText : std::string();
    if (!rows.deltaUs) rows.deltaText = text;
    agree(rows.deltaUs, deltaUs, Column::DeltaTime, text, earlier, *rows.message);
  }

  void signalValue(MessageRows& rows) {
    const std::string& name = field(Column::Signal);
    const std::string& valueText = field(Column::Value);
    const dbc::Message& message = *rows.message;
    if (name.empty()) {
      if (!valueText.empty()) {
        m_diagnostics.error(m_line, "Value '" + valueText + "' without a Signal (message '" + message.name + "')");
      }
      return;  // a row that only lists its message
    }
    const dbc::Signal* signal = message.findSignal(name);
    if (signal == nullptr) {
      std::vector<std::string> names;
      names.reserve(message.signals.size());
      for (const dbc::Signal& candidate : message.signals) names.push_back(candidate.name);
      m_diagnostics.error(m_line,
                          "unknown signal '" + name + "' in message '" + message.name + "'" + suggestion(name, names));
      return;
    }
    if (!signal->decodable()) {
      m_diagnostics.error(m_line, "signal '" + name + "' of message '" + message.name + "' cannot be encoded (" +
                                      std::to_string(signal->size) + " bits)");
      return;
    }
    if (valueText.empty()) {
      m_diagnostics.error(m_line, "no Value for signal '" + name + "' of message '" + message.name +
                                      "' (leave Signal empty too to list the message only)");
      return;
    }
    const auto maybeValue = parseNumber(valueText);
    if (!maybeValue) {
      m_diagnostics.error(m_line, "Value '" + valueText + "' of signal '" + name + "' is not a number");
      return;
    }
    const double value = *maybeValue;
    if (signal->minimum < signal->maximum && (value < signal->minimum || value > signal->maximum)) {
      m_diagnostics.error(m_line, "Value " + valueText + " of signal '" + name + "' is outside its DBC range [" +
                                      formatNumberText(signal->minimum) + "|" + formatNumberText(signal->maximum) +
                                      "]");
      return;
    }
    for (const SignalValue& earlier : rows.values) {
      if (earlier.signal != signal) continue;
      if (earlier.value == value) {
        m_diagnostics.warning(m_line, "signal '" + name + "' of message '" + message.name + "' is already set on " +
                                          lineText(earlier.line));
      } else {
        m_diagnostics.error(m_line, "signal '" + name + "' of message '" + message.name + "' is set to " +
                                        formatNumberText(value) + " here and to " + formatNumberText(earlier.value) +
                                        " on " + lineText(earlier.line));
      }
      return;
    }
    rows.values.push_back(SignalValue{signal, value, m_line});
  }

  void checkMessage(const MessageRows& rows) {
    const dbc::Message& message = *rows.message;
    const std::string name = "'" + message.name + "'";
    if (!rows.cycleMs) {
      m_diagnostics.error(rows.firstLine, "no CycleTime for message " + name + " (give it on one of its rows)");
    }
    if (isSdm(rows)) {
      const std::uint32_t line = rows.shm->line;
      if (!message.extended) {
        m_diagnostics.error(line, "message " + name +
                                      " has an 11-bit identifier: a J1939-76 SDM (IsSHM 1) needs a "
                                      "29-bit one");
      }
      if (!rows.deltaUs || rows.deltaUs->value == 0) {
        m_diagnostics.error(rows.deltaUs ? rows.deltaUs->line : line,
                            "message " + name + " is an SDM (IsSHM 1) but its DeltaTime is " +
                                (rows.deltaUs ? std::string("0") : std::string("empty")) +
                                ": J1939-76 needs the SHM-to-SDM delay in ms (> 0)");
      } else if (rows.cycleMs && rows.deltaUs->value >= static_cast<std::int64_t>(rows.cycleMs->value) * 1000) {
        m_diagnostics.error(rows.deltaUs->line, "DeltaTime " + rows.deltaText + " ms of message " + name +
                                                    " is not shorter than its CycleTime " +
                                                    std::to_string(rows.cycleMs->value) + " ms");
      }
    } else if (rows.deltaUs && rows.deltaUs->value > 0) {
      m_diagnostics.warning(rows.deltaUs->line, "DeltaTime " + rows.deltaText + " ms of message " + name +
                                                    " ignored: it is not an SDM (IsSHM is 0)");
    }
    if (rows.sheetSaysShm && rows.sheetSaysShm->value != isSdm(rows)) {
      m_diagnostics.warning(rows.sheetSaysShm->line, "sheet '" + rows.sheetName + "' but IsSHM " +
                                                         (isSdm(rows) ? "1" : "0") + ": message " + name +
                                                         " is imported as " +
                                                         (isSdm(rows) ? "a J1939-76 SDM" : "not J1939-76 protected"));
    }
  }

  /// The send groups in the order first seen, their keys checked; reports what must be
  /// declared or mapped.
  std::vector<Group> sendGroups() {
    std::vector<Group> groups;
    std::vector<std::string> undeclared;
    for (const MessageRows& rows : m_messages) {
      if (!rows.node) continue;
      const std::string& name = rows.node->value;
      if (std::any_of(groups.begin(), groups.end(), [&](const Group& group) { return group.name == name; })) continue;
      const auto mapped = std::find_if(m_options.groupSignals.begin(), m_options.groupSignals.end(),
                                       [&](const auto& entry) { return entry.first == name; });
      if (mapped != m_options.groupSignals.end()) {
        if (m_options.catalog != nullptr) {
          if (const auto found = m_options.catalog->find(mapped->second); !found) {
            m_diagnostics.optionError("--group-signal " + name + "=" + mapped->second + ": " + found.error().message);
          }
        }
        groups.push_back(Group{name, mapped->second});
        continue;
      }
      if (!validSignalNamePart(name)) {
        m_diagnostics.error(rows.node->line, "NodeName '" + name +
                                                 "' cannot name a signal (letters, digits, '_' and '.'); map it "
                                                 "with --group-signal NODE=KEY");
        continue;
      }
      std::string key = std::string(GROUP_SIGNAL_PREFIX) + name;
      if (m_options.catalog == nullptr || !m_options.catalog->indexOf(key)) undeclared.push_back(key);
      groups.push_back(Group{name, std::move(key)});
    }
    for (const auto& entry : m_options.groupSignals) {
      const std::string& node = entry.first;  // not a structured binding: clang 14 cannot capture one
      const auto& key = entry.second;
      if (std::none_of(groups.begin(), groups.end(), [&](const Group& group) { return group.name == node; })) {
        m_diagnostics.optionWarning("--group-signal " + node + "=" + key + ": no row has NodeName '" + node + "'");
      }
    }
    if (!undeclared.empty()) {
      std::string names;
      std::string entries;
      for (const std::string& key : undeclared) {
        names += (names.empty() ? "" : ", ") + key;
        entries += std::string(entries.empty() ? "" : ", ") + "{\"name\": \"" +
                   key.substr(std::string_view("internal.").size()) + "\"}";
      }
      m_diagnostics.note(0, std::string("the send groups switch on ") +
                                (undeclared.size() == 1 ? "an internal signal" : "internal signals") +
                                " that vehicle.json must declare: " + names + "; add \"internalSignals\": [" + entries +
                                "] (initial value 0: the group is off until set), or map a node to an "
                                "existing key with --group-signal NODE=KEY");
    }
    return groups;
  }

  const dbc::Database& m_database;
  const ImportOptions& m_options;
  Diagnostics& m_diagnostics;
  std::vector<std::string> m_messageNames;
  std::array<std::size_t, SCHEDULE_CSV_COLUMNS.size()> m_columnIndex{};
  std::size_t m_columnCount{};
  std::vector<MessageRows> m_messages;
  std::unordered_map<std::string, std::size_t> m_messageIndex;
  const CsvRecord* m_record{};
  std::uint32_t m_line{};
  std::size_t m_rowCount{};
};

}  // namespace

Result<nlohmann::ordered_json> importScheduleCsv(std::string_view text, const std::string& fileName,
                                                 const dbc::Database& database, const ImportOptions& options,
                                                 std::vector<Error>* diagnostics) {
  Diagnostics found(fileName);
  if (text.substr(0, UTF8_BOM.size()) == UTF8_BOM) text.remove_prefix(UTF8_BOM.size());
  std::string converted;
  if (!text::isValidUtf8(text)) {
    converted = text::cp1252ToUtf8(text);
    text = converted;
    found.warning(0, "not UTF-8: read as Windows-1252");
  }
  const std::vector<CsvRecord> records = splitCsv(text, found);
  Json schedule;
  if (records.empty()) {
    if (found.errorCount() == 0) found.error(0, "no header: the first line names the columns " + columnList());
  } else {
    Importer importer(database, options, found);
    if (importer.header(records.front())) {
      for (std::size_t i = 1; i < records.size(); ++i) importer.row(records[i]);
      schedule = importer.finish();
    }
  }
  std::vector<Error> sorted = found.sorted();
  std::optional<Error> firstError;
  for (const Error& error : sorted) {
    if (error.severity == Severity::Error) {
      firstError = error;
      break;
    }
  }
  if (diagnostics != nullptr) diagnostics->insert(diagnostics->end(), sorted.begin(), sorted.end());
  if (firstError) return *firstError;
  return schedule;
}

}  // namespace openvcu::schedule
