#include "openvcu/trace/frame_decoder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace openvcu::trace {

FrameDecoder::FrameDecoder(const dbc::Database& database, dbc::MatchMode mode)
    : m_database(&database), m_matcher(database, mode), m_codecs(database) {
  std::size_t most = 1;
  for (const dbc::Message& message : database.messages) most = std::max(most, message.signals.size());
  m_values.resize(most);  // the codec visits each signal at most once
}

std::span<const SignalValue> FrameDecoder::decode(const can::Frame& frame, std::int32_t messageIndex) noexcept {
  if (messageIndex < 0 || static_cast<std::size_t>(messageIndex) >= m_database->messages.size()) return {};
  if ((frame.flags & can::FLAG_RTR) != 0) return {};
  std::size_t decoded = 0;
  m_codecs[static_cast<std::size_t>(messageIndex)].decode(
      frame.payload(), [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
        m_values[decoded++] = SignalValue{signalIndex, value};
      });
  return {m_values.data(), decoded};
}

std::int64_t loggedTimeNs(const can::LogRecord& record, can::LogFormat format) noexcept {
  if (format == can::LogFormat::VectorAsc) return std::llround(record.timeSeconds * 1e9);
  return record.frame.timestampNs;
}

void appendDecodedText(std::string& out, const dbc::Message& message, std::span<const SignalValue> values) {
  char number[32];
  for (const SignalValue& value : values) {
    const dbc::Signal& signal = message.signals[value.signalIndex];
    out += signal.name;
    out += '=';
    std::snprintf(number, sizeof number, "%.6g", value.value.physical);
    out += number;
    if (const std::string* description = signal.describe(static_cast<std::int64_t>(value.value.rawUnsigned))) {
      out += " \"";
      out += *description;
      out += '"';
    } else if (!signal.unit.empty()) {
      out += ' ';
      out += signal.unit;
    }
    out += "  ";
  }
}

}  // namespace openvcu::trace
