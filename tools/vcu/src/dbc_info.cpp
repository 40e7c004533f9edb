// vcu dbc info: a DBC file's messages and signals as aligned text.
#include <charconv>
#include <cstdio>
#include <optional>

#include "dbc_commands.hpp"
#include "dbc_loading.hpp"
#include "diagnostics.hpp"
#include "openvcu/core/text.hpp"
#include "openvcu/j1939/id.hpp"
#include "text_table.hpp"

namespace openvcu::cli {
namespace {

constexpr std::size_t MAX_COMMENT_WIDTH = 60;  ///< a comment is shown on one line, cut here
constexpr std::string_view NONE = "-";

std::string hex(std::uint32_t value, int digits) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%0*X", digits, value);
  return text;
}

using text::number;

std::string joined(const std::vector<std::string>& items, std::string_view separator) {
  std::string text;
  for (const std::string& item : items) {
    if (!text.empty()) text += separator;
    text += item;
  }
  return text.empty() ? std::string(NONE) : text;
}

std::string orNone(std::string text) {
  return text.empty() ? std::string(NONE) : text;
}

std::string messageId(const dbc::Message& message) {
  return hex(message.id, message.extended ? 8 : 3);
}

std::string nameCell(const std::string& name, const std::string& displayName) {
  return displayName.empty() || displayName == name ? name : name + '/' + displayName;
}

/// The comment on one line: whitespace runs become one space, cut at MAX_COMMENT_WIDTH.
std::string oneLine(std::string_view comment) {
  std::string line;
  bool pendingSpace = false;
  for (const char c : comment) {
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      pendingSpace = !line.empty();
      continue;
    }
    if (pendingSpace) line += ' ';
    pendingSpace = false;
    line += c;
  }
  if (displayWidth(line) > MAX_COMMENT_WIDTH) {
    std::size_t cut = 0;
    for (std::size_t width = 0; cut < line.size(); ++cut) {  // cut on a code point boundary
      if ((static_cast<unsigned char>(line[cut]) & 0xC0u) != 0x80u && ++width > MAX_COMMENT_WIDTH - 3) break;
    }
    line.resize(cut);
    line += "...";
  }
  return orNone(line);
}

std::string bitsCell(const dbc::Signal& signal) {
  std::string text = std::to_string(signal.startBit) + '|' + std::to_string(signal.size) + '@';
  text += signal.byteOrder == dbc::ByteOrder::LittleEndian ? '1' : '0';
  text += signal.isSigned ? '-' : '+';
  return text;
}

std::string typeCell(const dbc::Signal& signal) {
  std::string text;
  switch (signal.valueType) {
    case dbc::ValueType::Integer:
      text = "int";
      break;
    case dbc::ValueType::Float32:
      text = "float32";
      break;
    case dbc::ValueType::Float64:
      text = "float64";
      break;
  }
  if (!signal.decodable()) text += " (not decodable)";
  return text;
}

std::string muxCell(const dbc::Signal& signal) {
  if (signal.muxRole == dbc::MuxRole::None) return std::string(NONE);
  if (signal.muxRole == dbc::MuxRole::Multiplexor) return "M";
  std::string text = "m";
  if (signal.muxRanges.empty()) {
    text += std::to_string(signal.muxValue);
  } else {
    for (std::size_t i = 0; i < signal.muxRanges.size(); ++i) {
      if (i > 0) text += ',';
      text += std::to_string(signal.muxRanges[i].low);
      if (signal.muxRanges[i].high != signal.muxRanges[i].low) text += '-' + std::to_string(signal.muxRanges[i].high);
    }
  }
  if (signal.muxRole == dbc::MuxRole::MultiplexedMultiplexor) text += 'M';
  if (signal.extendedMux && !signal.muxSwitch.empty()) text += " by " + signal.muxSwitch;
  return text;
}

std::string receiversCell(const dbc::Signal& signal) {
  std::vector<std::string> receivers;
  for (const std::string& receiver : signal.receivers) {
    if (receiver != dbc::NO_NODE) receivers.push_back(receiver);
  }
  return joined(receivers, ",");
}

void addMessageRow(TextTable& table, const dbc::Message& message) {
  std::string pgn(NONE), priority(NONE), source(NONE), destination(NONE);
  if (message.extended) {  // every 29-bit ID read as J1939 (what --match j1939 matches on)
    const j1939::Id id = j1939::Id::fromCanId(message.id);
    pgn = hex(id.pgn(), 4) + " (" + std::to_string(id.pgn()) + ')';
    priority = std::to_string(id.priority);
    source = hex(id.sourceAddress, 2);
    if (id.isPdu1()) destination = hex(id.pduSpecific, 2);
  }
  table.addRow({messageId(message), message.extended ? "ext" : "std", nameCell(message.name, message.displayName),
                std::to_string(message.length), joined(message.transmitters(), ","), pgn, priority, source, destination,
                message.cycleTimeMs ? std::to_string(*message.cycleTimeMs) + " ms" : std::string(NONE),
                std::string(dbc::toString(message.frameFormat)), oneLine(message.comment)});
}

void appendSignals(std::string& out, const dbc::Message& message) {
  out += '\n';
  out += nameCell(message.name, message.displayName) + ' ' + messageId(message) + (message.extended ? " ext" : " std") +
         ", " + std::to_string(message.signals.size()) + (message.signals.size() == 1 ? " signal\n" : " signals\n");
  if (message.signals.empty()) return;
  TextTable table({"SIGNAL", "BITS", "TYPE", "FACTOR", "OFFSET", "RANGE", "UNIT", "MUX", "VALUES", "RECEIVERS"});
  for (const dbc::Signal& signal : message.signals) {
    table.addRow(
        {nameCell(signal.name, signal.displayName), bitsCell(signal), typeCell(signal), number(signal.factor),
         number(signal.offset), '[' + number(signal.minimum) + '|' + number(signal.maximum) + ']', orNone(signal.unit),
         muxCell(signal),
         signal.valueDescriptions.empty() ? std::string(NONE) : std::to_string(signal.valueDescriptions.size()),
         receiversCell(signal)});
  }
  table.appendTo(out, "  ");
}

/// The message --message names: its name, long name, or ID (0x18FEF1FE or decimal).
const dbc::Message* findMessage(const dbc::Database& database, const std::string& wanted) {
  for (const dbc::Message& message : database.messages) {
    if (message.name == wanted || message.displayName == wanted) return &message;
  }
  const bool isHex = wanted.size() > 2 && wanted[0] == '0' && (wanted[1] == 'x' || wanted[1] == 'X');
  std::uint32_t id = 0;
  const char* first = wanted.data() + (isHex ? 2 : 0);
  const char* last = wanted.data() + wanted.size();
  const auto parsed = std::from_chars(first, last, id, isHex ? 16 : 10);
  if (parsed.ec != std::errc{} || parsed.ptr != last) return nullptr;
  for (const dbc::Message& message : database.messages) {
    if (!message.pseudo && (message.id == id || message.declaredId == id)) return &message;
  }
  return nullptr;
}

}  // namespace

ExitCode runInfo(const InfoOptions& options, Streams streams) {
  std::optional<dbc::Database> maybeDatabase = loadDatabase({options.file}, streams.err, false);
  if (!maybeDatabase) return ExitCode::Failure;
  const dbc::Database& database = *maybeDatabase;

  std::vector<const dbc::Message*> shown;
  std::string out;
  if (!options.message.empty()) {
    const dbc::Message* message = findMessage(database, options.message);
    if (message == nullptr) {
      std::vector<std::string> names;
      for (const dbc::Message& candidate : database.messages) names.push_back(candidate.name);
      std::string reason = "no message '" + options.message + "'";
      if (auto suggestion = text::didYouMean(options.message, names)) reason += "; did you mean '" + *suggestion + "'?";
      report(streams.err, Error{std::move(reason), Location{options.file, 0, 0, {}}});
      return ExitCode::Failure;
    }
    shown.push_back(message);
  } else {
    const DatabaseCounts counts = countDatabase(database);
    out += options.file + ": " + std::to_string(counts.messages) + " messages, " + std::to_string(counts.signals) +
           " signals, " + std::to_string(counts.nodes) + " nodes\n";
    if (!database.version.empty()) out += "version: " + database.version + '\n';
    std::vector<std::string> nodeNames;
    for (const dbc::Node& node : database.nodes) nodeNames.push_back(node.name);
    out += "nodes: " + joined(nodeNames, " ") + "\n\n";
    for (const dbc::Message& message : database.messages) shown.push_back(&message);
  }

  TextTable messages({"ID", "IDE", "MESSAGE", "LEN", "TX", "PGN", "PRIO", "SA", "DA", "CYCLE", "FORMAT", "COMMENT"});
  for (const dbc::Message* message : shown) addMessageRow(messages, *message);
  messages.appendTo(out);
  for (const dbc::Message* message : shown) appendSignals(out, *message);
  streams.out.write(out);
  return ExitCode::Ok;
}

}  // namespace openvcu::cli
