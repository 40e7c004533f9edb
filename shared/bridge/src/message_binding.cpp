#include "openvcu/bridge/message_binding.hpp"

#include <cmath>

#include "openvcu/config/catalog.hpp"

namespace openvcu::bridge {

MessageBinding MessageBinding::bind(const dbc::Database& database, std::size_t messageIndex,
                                    const signals::Catalog* catalog) {
  const dbc::Message& message = database.messages[messageIndex];
  MessageBinding binding;
  binding.m_messageIndex = messageIndex;
  binding.m_message = &message;
  binding.m_codec = dbc::MessageCodec::compile(database, message);
  binding.m_signals.resize(message.signals.size());
  for (std::size_t s = 0; s < message.signals.size(); ++s) {
    const dbc::Signal& signal = message.signals[s];
    SignalBinding& bound = binding.m_signals[s];
    if (catalog != nullptr) {
      if (const auto maybeIndex = catalog->indexOf(config::signalKey(message, signal))) bound.slot = *maybeIndex;
    }
    bound.limits = Limits{signal.minimum, signal.maximum};
    bound.multiplexed = signal.muxRole == dbc::MuxRole::Multiplexed;
  }
  return binding;
}

std::optional<std::uint32_t> MessageBinding::signalIndex(std::string_view name) const noexcept {
  if (m_message == nullptr) return std::nullopt;
  for (std::uint32_t s = 0; s < m_message->signals.size(); ++s) {
    if (m_message->signals[s].name == name) return s;
  }
  return std::nullopt;
}

DecodeResult MessageBinding::decodeInto(signals::SignalTable& table, std::span<const std::uint8_t> payload,
                                        std::int64_t nowNs, std::uint16_t source, RangeCheck range) const noexcept {
  DecodeResult result;
  const dbc::DecodeSummary summary =
      m_codec.decode(payload, [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
        const SignalBinding& signal = m_signals[signalIndex];
        if (signal.slot == NO_SLOT) return;
        signals::Quality quality = signals::Quality::Valid;
        if (range == RangeCheck::Mark && !signal.limits.contains(value.physical)) {
          quality = signals::Quality::OutOfRange;
          ++result.outOfRange;
        }
        table.writeBus(signal.slot, value.physical, nowNs, source, quality);
        ++result.written;
      });
  result.decoded = summary.decoded;
  result.missing = summary.missing;
  return result;
}

void MessageBinding::markBusQuality(signals::SignalTable& table, signals::Quality quality) const noexcept {
  for (const SignalBinding& signal : m_signals) {
    if (signal.slot != NO_SLOT) table.markBusQuality(signal.slot, quality);
  }
}

EncodeResult MessageBinding::encodeFrom(const signals::SignalTable& table, std::span<std::uint8_t> buffer) const noexcept {
  return encodeFrom(buffer, [&table](std::uint32_t, std::optional<signals::SignalIndex> maybeSlot) noexcept {
    std::optional<double> maybeValue;
    if (!maybeSlot) return maybeValue;
    if (const auto snapshot = table.read(*maybeSlot)) {
      if (const auto effective = signals::effectiveCommand(*snapshot)) maybeValue = effective->value;
    }
    return maybeValue;
  });
}

dbc::DecodeSummary MessageBinding::decodeValues(std::span<const std::uint8_t> payload,
                                                std::span<double> values) const noexcept {
  return m_codec.decode(payload, [values](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
    if (signalIndex < values.size()) values[signalIndex] = value.physical;
  });
}

std::optional<double> MessageBinding::value(std::uint32_t signal, std::span<const std::uint8_t> payload) const noexcept {
  std::optional<double> maybeValue;
  (void)m_codec.decode(payload, [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
    if (signalIndex == signal) maybeValue = value.physical;
  });
  return maybeValue;
}

dbc::EncodeStatus MessageBinding::encodeClamped(std::uint32_t signal, double value,
                                                std::span<std::uint8_t> buffer) const noexcept {
  if (signal >= m_signals.size() || !std::isfinite(value)) return dbc::EncodeStatus::NotEncodable;
  return m_codec.encode(signal, m_signals[signal].limits.clamp(value), buffer);
}

DatabaseBinding::DatabaseBinding(const dbc::Database& database) {
  m_messages.reserve(database.messages.size());
  for (std::size_t m = 0; m < database.messages.size(); ++m) {
    m_messages.push_back(MessageBinding::bind(database, m, nullptr));
  }
}

DatabaseBinding::DatabaseBinding(const dbc::Database& database, const signals::Catalog& catalog) {
  m_messages.reserve(database.messages.size());
  for (std::size_t m = 0; m < database.messages.size(); ++m) {
    m_messages.push_back(MessageBinding::bind(database, m, &catalog));
  }
}

std::optional<SignalRef> DatabaseBinding::find(std::string_view message, std::string_view signal) const noexcept {
  for (const MessageBinding& binding : m_messages) {
    if (binding.message().name != message) continue;
    if (const auto maybeSignal = binding.signalIndex(signal)) return SignalRef{binding.messageIndex(), *maybeSignal};
  }
  return std::nullopt;
}

}  // namespace openvcu::bridge
