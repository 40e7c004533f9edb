#include "openvcu/trace/frame_writer.hpp"

#include <charconv>
#include <cmath>
#include <cstring>

#include "openvcu/core/text.hpp"
#include "openvcu/dbc/matcher.hpp"

namespace openvcu::trace {
namespace {

/// 2^53: integral doubles below it print as integers, like the oracle's jnum.
constexpr double EXACT_INTEGER_LIMIT = 9007199254740992.0;
constexpr std::int64_t NS_PER_SECOND = 1'000'000'000;
constexpr std::int64_t NS_PER_MICROSECOND = 1'000;
/// Longest text of one number: a shortest double is at most 24 characters
/// ("-2.2250738585072014e-308"), an int64 20, a time 30 ("-9223372036.854775808").
constexpr std::size_t MAX_NUMBER_CHARS = 32;
/// The fixed text of one JSON frame or CSV row, with room to spare.
constexpr std::size_t FIXED_FRAME_CHARS = 96;

// The put* functions write at `p` into room the caller reserved and return the new end
// (why: one bounds reservation per frame instead of a capacity check per piece).

char* put(char* p, std::string_view text) noexcept {
  std::memcpy(p, text.data(), text.size());
  return p + text.size();
}

template <typename Integer>
char* putInteger(char* p, Integer value) noexcept {
  return std::to_chars(p, p + MAX_NUMBER_CHARS, value).ptr;
}

char* putNumber(char* p, double value, bool quoteNonFinite) noexcept {
  if (std::isnan(value)) return put(p, quoteNonFinite ? "\"nan\"" : "nan");
  if (std::isinf(value)) {
    if (value > 0) return put(p, quoteNonFinite ? "\"inf\"" : "inf");
    return put(p, quoteNonFinite ? "\"-inf\"" : "-inf");
  }
  if (std::fabs(value) < EXACT_INTEGER_LIMIT && value == std::trunc(value)) {
    return putInteger(p, static_cast<std::int64_t>(value));  // -0.0 -> 0
  }
  return std::to_chars(p, p + MAX_NUMBER_CHARS, value).ptr;  // shortest round-trip text
}

char* putRaw(char* p, const dbc::DecodedValue& value, bool quoteNonFinite) noexcept {
  switch (value.kind) {
    case dbc::RawKind::Unsigned:
      return putInteger(p, value.rawUnsigned);
    case dbc::RawKind::Signed:
      return putInteger(p, value.rawSigned);
    case dbc::RawKind::Float32:
    case dbc::RawKind::Float64:
      return putNumber(p, value.rawFloat, quoteNonFinite);
  }
  return p;
}

/// `value` zero-padded to `width` digits.
char* putPadded(char* p, std::uint64_t value, std::size_t width) noexcept {
  for (std::size_t i = width; i > 0; --i) {
    p[i - 1] = static_cast<char>('0' + value % 10);
    value /= 10;
  }
  return p + width;
}

char* putSeconds(char* p, std::int64_t nanoseconds) noexcept {
  std::uint64_t magnitude = static_cast<std::uint64_t>(nanoseconds);
  if (nanoseconds < 0) {
    *p++ = '-';
    magnitude = ~magnitude + 1;  // two's complement negation, defined for INT64_MIN too
  }
  p = putInteger(p, magnitude / NS_PER_SECOND);
  *p++ = '.';
  const std::uint64_t fraction = magnitude % NS_PER_SECOND;
  if (fraction % NS_PER_MICROSECOND == 0) return putPadded(p, fraction / NS_PER_MICROSECOND, 6);
  return putPadded(p, fraction, 9);
}

/// Grows `out` by `room` bytes to write into; finish() trims it to what was written.
char* reserveRoom(std::string& out, std::size_t room) {
  const std::size_t used = out.size();
  out.resize(used + room);
  return out.data() + used;
}

void finish(std::string& out, const char* end) noexcept {
  out.resize(static_cast<std::size_t>(end - out.data()));
}

std::string jsonKey(std::string_view name) {
  std::string key;
  appendJsonString(key, name);
  key += ':';
  return key;
}

/// "by the responder, reason 1 AlreadyInSession", "T1 ran out", "bad sequence number", ...
std::string sessionEndReason(const j1939::TpSessionEnd& end) {
  switch (end.outcome) {
    case j1939::TpOutcome::Aborted:
      return "by the " + std::string(j1939::tpSideName(end.abortedBy)) + ", reason " +
             std::to_string(static_cast<unsigned>(end.abortReason)) + " " +
             std::string(j1939::tpAbortReasonName(end.abortReason));
    case j1939::TpOutcome::TimedOut: return std::string(j1939::tpTimerName(end.timer)) + " ran out";
    case j1939::TpOutcome::Replaced: return "a new announcement for the same addresses";
    case j1939::TpOutcome::ProtocolError:
    case j1939::TpOutcome::Refused: return std::string(j1939::tpErrorText(end.error));
    case j1939::TpOutcome::Incomplete: return "the log ended";
    case j1939::TpOutcome::Completed: break;
  }
  return {};
}

void appendTpObject(std::string& out, const j1939::TpSessionInfo& session) {
  out += ",\"tp\":{\"pgn\":";
  out += std::to_string(session.pgn);
  out += ",\"sa\":";
  out += std::to_string(session.source);
  out += ",\"da\":";
  out += std::to_string(session.destination);
  out += ",\"size\":";
  out += std::to_string(session.size);
  out += session.broadcast ? ",\"bam\":true}" : ",\"bam\":false}";
}

/// Removes the closing "}\n" of the JSON object just written, to add keys to it.
void reopenJsonObject(std::string& out) { out.resize(out.size() - 2); }

std::string csvField(std::string_view text) {
  std::string field;
  appendCsvField(field, text);
  return field;
}

}  // namespace

void appendNumber(std::string& out, double value, bool quoteNonFinite) {
  finish(out, putNumber(reserveRoom(out, MAX_NUMBER_CHARS), value, quoteNonFinite));
}

void appendRaw(std::string& out, const dbc::DecodedValue& value, bool quoteNonFinite) {
  finish(out, putRaw(reserveRoom(out, MAX_NUMBER_CHARS), value, quoteNonFinite));
}

void appendSeconds(std::string& out, std::int64_t nanoseconds) {
  finish(out, putSeconds(reserveRoom(out, MAX_NUMBER_CHARS), nanoseconds));
}

void appendJsonString(std::string& out, std::string_view text) {
  static constexpr char HEX[] = "0123456789abcdef";
  const bool utf8 = text::isValidUtf8(text);
  out += '"';
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20 || (!utf8 && byte >= 0x80)) {
      const char escape[] = {'\\', 'u', '0', '0', HEX[byte >> 4], HEX[byte & 0x0F]};
      out.append(escape, sizeof escape);
    } else {
      out += c;
    }
  }
  out += '"';
}

void appendCsvField(std::string& out, std::string_view text) {
  if (text.find_first_of(",\"\r\n") == std::string_view::npos) {
    out += text;
    return;
  }
  out += '"';
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
}

FrameWriter::FrameWriter(const dbc::Database& database, DecodeFormat format) : m_format(format) {
  m_messages.reserve(database.messages.size());
  for (const dbc::Message& message : database.messages) {
    MessageText text;
    if (format == DecodeFormat::Jsonl) {
      appendJsonString(text.name, message.displayName);
    } else {
      appendCsvField(text.name, message.displayName);
    }
    text.signalNames.reserve(message.signals.size());
    for (const dbc::Signal& signal : message.signals) {
      text.signalNames.push_back(format == DecodeFormat::Jsonl ? jsonKey(signal.displayName)
                                                               : csvField(signal.displayName));
      text.longestSignalName = std::max(text.longestSignalName, text.signalNames.back().size());
    }
    m_messages.push_back(std::move(text));
  }
}

void FrameWriter::appendHeader(std::string& out) const {
  if (m_format == DecodeFormat::Csv) out += "t,bus,id,ext,msg,signal,raw,physical\n";
}

void FrameWriter::rememberChannel(std::string_view channel) {
  if (channel == m_channel && !m_channelText.empty()) return;
  m_channel.assign(channel);
  m_channelText.clear();
  if (m_format == DecodeFormat::Jsonl) {
    appendJsonString(m_channelText, channel);
  } else {
    appendCsvField(m_channelText, channel);
  }
}

void FrameWriter::appendFrame(std::string& out, const can::LogRecord& record, std::int32_t messageIndex,
                              std::span<const SignalValue> values) {
  rememberChannel(record.channel);
  const MessageText* message = nullptr;
  if (messageIndex != dbc::MessageMatcher::NO_MATCH && static_cast<std::size_t>(messageIndex) < m_messages.size()) {
    message = &m_messages[static_cast<std::size_t>(messageIndex)];
  }
  if (message == nullptr) values = {};
  if (m_format == DecodeFormat::Jsonl) {
    appendJsonFrame(out, record, message, values);
  } else {
    appendCsvFrame(out, record, message, values);
  }
}

void FrameWriter::appendJsonFrame(std::string& out, const can::LogRecord& record, const MessageText* message,
                                  std::span<const SignalValue> values) const {
  std::size_t room = FIXED_FRAME_CHARS + 2 * MAX_NUMBER_CHARS + m_channelText.size();
  if (message != nullptr)
    room += message->name.size() + values.size() * 2 * (message->longestSignalName + MAX_NUMBER_CHARS + 1);
  char* p = reserveRoom(out, room);
  p = put(p, "{\"t\":");
  p = record.hasTime ? putSeconds(p, record.frame.timestampNs) : put(p, "null");
  p = put(p, ",\"bus\":");
  p = put(p, m_channelText);
  p = put(p, ",\"id\":");
  p = putInteger(p, record.frame.id);
  p = put(p, record.frame.extended() ? ",\"ext\":true,\"msg\":" : ",\"ext\":false,\"msg\":");
  if (message == nullptr) {
    finish(out, put(p, "null,\"signals\":{},\"raw\":{}}\n"));
    return;
  }
  p = put(p, message->name);
  p = put(p, ",\"signals\":{");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) *p++ = ',';
    p = put(p, message->signalNames[values[i].signalIndex]);
    p = putNumber(p, values[i].value.physical, true);
  }
  p = put(p, "},\"raw\":{");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) *p++ = ',';
    p = put(p, message->signalNames[values[i].signalIndex]);
    p = putRaw(p, values[i].value, true);
  }
  finish(out, put(p, "}}\n"));
}

void FrameWriter::appendCsvFrame(std::string& out, const can::LogRecord& record, const MessageText* message,
                                 std::span<const SignalValue> values) const {
  const std::size_t rows = values.empty() ? 1 : values.size();
  std::size_t prefixRoom = FIXED_FRAME_CHARS + 2 * MAX_NUMBER_CHARS + m_channelText.size();
  std::size_t rowRoom = 2 * MAX_NUMBER_CHARS + 4;
  if (message != nullptr) {
    prefixRoom += message->name.size();
    rowRoom += message->longestSignalName;
  }
  char* p = reserveRoom(out, rows * (prefixRoom + rowRoom));
  // The row prefix "t,bus,id,ext,msg," is written once, then copied for each further row.
  char* const prefix = p;
  if (record.hasTime) p = putSeconds(p, record.frame.timestampNs);
  *p++ = ',';
  p = put(p, m_channelText);
  *p++ = ',';
  p = putInteger(p, record.frame.id);
  p = put(p, record.frame.extended() ? ",true," : ",false,");
  if (message != nullptr) p = put(p, message->name);
  *p++ = ',';
  const std::size_t prefixLength = static_cast<std::size_t>(p - prefix);
  if (values.empty()) {
    finish(out, put(p, ",,\n"));
    return;
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) {
      std::memcpy(p, prefix, prefixLength);  // no overlap: p is past the first row
      p += prefixLength;
    }
    p = put(p, message->signalNames[values[i].signalIndex]);
    *p++ = ',';
    p = putRaw(p, values[i].value, false);
    *p++ = ',';
    p = putNumber(p, values[i].value.physical, false);
    *p++ = '\n';
  }
  finish(out, p);
}

const FrameWriter::MessageText* FrameWriter::messageText(std::int32_t messageIndex) const noexcept {
  if (messageIndex < 0 || static_cast<std::size_t>(messageIndex) >= m_messages.size()) return nullptr;
  return &m_messages[static_cast<std::size_t>(messageIndex)];
}

void FrameWriter::appendDmFrame(std::string& out, const can::LogRecord& record, std::int32_t messageIndex,
                                std::span<const SignalValue> values, const j1939::Dm1& dm, bool previouslyActive) {
  if (m_format == DecodeFormat::Jsonl) {
    appendFrame(out, record, messageIndex, values);
    reopenJsonObject(out);
    appendJsonDm(out, dm, previouslyActive);
    out += "}\n";
    return;
  }
  // CSV: the signal rows (or the one empty row of an unknown frame), then the DM rows.
  if (messageText(messageIndex) != nullptr) appendFrame(out, record, messageIndex, values);
  rememberChannel(record.channel);
  appendCsvDmRows(out, record, messageIndex, dm, previouslyActive);
}

void FrameWriter::appendTransportMessage(std::string& out, const can::LogRecord& record,
                                         const j1939::TpSessionInfo& session, std::int32_t messageIndex,
                                         std::span<const SignalValue> values, const j1939::Dm1* dm,
                                         bool previouslyActive) {
  if (m_format == DecodeFormat::Jsonl) {
    appendFrame(out, record, messageIndex, values);
    reopenJsonObject(out);
    appendTpObject(out, session);
    if (dm != nullptr) appendJsonDm(out, *dm, previouslyActive);
    out += "}\n";
    return;
  }
  if (dm == nullptr || messageText(messageIndex) != nullptr) appendFrame(out, record, messageIndex, values);
  rememberChannel(record.channel);
  if (dm != nullptr) appendCsvDmRows(out, record, messageIndex, *dm, previouslyActive);
}

void FrameWriter::appendTransportEnd(std::string& out, const can::LogRecord& record, const j1939::TpSessionEnd& end,
                                     std::int32_t messageIndex) {
  rememberChannel(record.channel);
  const std::string reason = sessionEndReason(end);
  if (m_format == DecodeFormat::Jsonl) {
    appendFrame(out, record, messageIndex, {});
    reopenJsonObject(out);
    appendTpObject(out, end.session);
    out += ",\"tp_end\":{\"outcome\":";
    appendJsonString(out, j1939::tpOutcomeName(end.outcome));
    out += ",\"reason\":";
    appendJsonString(out, reason);
    out += ",\"received\":";
    out += std::to_string(end.session.packetsReceived);
    out += ",\"packets\":";
    out += std::to_string(end.session.packets);
    out += ",\"start\":";
    appendSeconds(out, end.session.startNs);
    out += "}}\n";
    return;
  }
  appendCsvPrefix(out, record, "tp_end");
  appendCsvField(out, std::string(j1939::tpOutcomeName(end.outcome)) + ": " + reason + ", " +
                          std::to_string(end.session.packetsReceived) + " of " +
                          std::to_string(end.session.packets) + " packets");
  out += ",,\n";
}

void FrameWriter::appendJsonDm(std::string& out, const j1939::Dm1& dm, bool previouslyActive) const {
  out += previouslyActive ? ",\"dm1\":{\"type\":\"DM2\",\"lamps\":{" : ",\"dm1\":{\"type\":\"DM1\",\"lamps\":{";
  const auto lamp = [&out](std::string_view key, j1939::LampStatus status, bool last) {
    out += '"';
    out += key;
    out += "\":\"";
    out += j1939::lampStatusName(status);
    out += last ? "\"" : "\",";
  };
  lamp("malfunction", dm.lamps.malfunction, false);
  lamp("redStop", dm.lamps.redStop, false);
  lamp("amberWarning", dm.lamps.amberWarning, false);
  lamp("protect", dm.lamps.protect, true);
  out += "},\"dtcs\":[";
  bool first = true;
  for (const j1939::Dtc& dtc : dm.activeDtcs()) {
    if (!first) out += ',';
    first = false;
    out += "{\"spn\":";
    out += std::to_string(dtc.spn);
    out += ",\"fmi\":";
    out += std::to_string(dtc.fmi);
    out += ",\"oc\":";
    out += std::to_string(dtc.occurrenceCount);
    out += dtc.spnConversionMethod ? ",\"cm\":1}" : ",\"cm\":0}";
  }
  out += "]}";
}

void FrameWriter::appendCsvPrefix(std::string& out, const can::LogRecord& record,
                                  std::string_view messageField) const {
  if (record.hasTime) appendSeconds(out, record.frame.timestampNs);
  out += ',';
  out += m_channelText;
  out += ',';
  out += std::to_string(record.frame.id);
  out += record.frame.extended() ? ",true," : ",false,";
  out += messageField;  // already escaped
  out += ',';
}

void FrameWriter::appendCsvDmRows(std::string& out, const can::LogRecord& record, std::int32_t messageIndex,
                                  const j1939::Dm1& dm, bool previouslyActive) const {
  const MessageText* message = messageText(messageIndex);
  const std::string_view messageField = message != nullptr ? std::string_view(message->name)
                                        : previouslyActive ? std::string_view("DM2")
                                                           : std::string_view("DM1");
  const auto row = [&](std::string_view signal, unsigned value) {
    appendCsvPrefix(out, record, messageField);
    out += signal;
    const std::string number = std::to_string(value);
    out += ',';
    out += number;
    out += ',';
    out += number;
    out += '\n';
  };
  row("lamp.malfunction", static_cast<unsigned>(dm.lamps.malfunction));
  row("lamp.redStop", static_cast<unsigned>(dm.lamps.redStop));
  row("lamp.amberWarning", static_cast<unsigned>(dm.lamps.amberWarning));
  row("lamp.protect", static_cast<unsigned>(dm.lamps.protect));
  std::size_t number = 0;
  for (const j1939::Dtc& dtc : dm.activeDtcs()) {
    const std::string name = "dtc" + std::to_string(++number);
    row(name + ".spn", dtc.spn);
    row(name + ".fmi", dtc.fmi);
    row(name + ".oc", dtc.occurrenceCount);
    row(name + ".cm", dtc.spnConversionMethod ? 1u : 0u);
  }
}

}  // namespace openvcu::trace
