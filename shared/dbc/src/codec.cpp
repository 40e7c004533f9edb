#include "openvcu/dbc/codec.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace openvcu::dbc {
namespace {

RawKind kindOf(const Signal& sig) {
  if (sig.valueType == ValueType::Float32) return RawKind::Float32;
  if (sig.valueType == ValueType::Float64) return RawKind::Float64;
  return sig.isSigned ? RawKind::Signed : RawKind::Unsigned;
}

CompiledSignal layout(const Signal& sig, std::uint32_t index) {
  CompiledSignal out;
  out.index = index;
  out.size = static_cast<std::uint8_t>(sig.size);
  out.mask = sig.size >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << sig.size) - 1;
  out.factor = sig.factor;
  out.offset = sig.offset;
  out.kind = kindOf(sig);
  out.byteOrder = sig.byteOrder;
  out.firstByte = sig.startBit / 8;
  if (sig.byteOrder == ByteOrder::LittleEndian) {
    out.shift = static_cast<std::uint8_t>(sig.startBit % 8);
    // 64-bit sum: a start bit near 2^32 must not wrap around into the frame.
    out.lastByte = static_cast<std::uint32_t>((std::uint64_t{sig.startBit} + sig.size - 1) / 8);
    out.wide = out.shift + sig.size > 64;
  } else {
    // Position of the LSB counted MSB-first from the first byte's bit 7.
    const std::uint32_t lsbLinear = (7 - sig.startBit % 8) + sig.size - 1;
    out.lastByte = out.firstByte + lsbLinear / 8;
    out.wide = lsbLinear > 63;
    out.shift = static_cast<std::uint8_t>(out.wide ? 71 - lsbLinear : 63 - lsbLinear);
  }
  return out;
}

/// The word form of a compiled signal whose bits lie in bytes 0..7 (lastByte < 8, not wide).
WordSignal wordForm(const CompiledSignal& sig) {
  WordSignal out;
  out.factor = sig.factor;
  out.offset = sig.offset;
  out.index = sig.index;
  out.kind = sig.kind;
  out.signBit = sig.kind == RawKind::Signed ? std::uint64_t{1} << (sig.size - 1) : 0;
  out.rightShift = static_cast<std::uint8_t>(64 - sig.size);
  const std::uint32_t byteShift = sig.firstByte * 8;
  if (sig.byteOrder == ByteOrder::LittleEndian) {
    const std::uint32_t msb = byteShift + sig.shift + sig.size - 1;  // bit of the LSB-first word
    out.leftShift = static_cast<std::uint8_t>(63 - msb);
  } else {
    // extractFromWord: the signal sits at bits shift..shift+size-1 of (swapped << byteShift).
    out.leftShift = static_cast<std::uint8_t>(byteShift + 64 - sig.shift - sig.size);
    out.bigEndian = 1;
  }
  return out;
}

/// Whether a compiled signal can take the plain fast path.
bool wordDecodable(const CompiledSignal& sig) {
  const bool integer = sig.kind == RawKind::Signed || (sig.kind == RawKind::Unsigned && sig.size < 64);
  return integer && !sig.wide && sig.lastByte < 8 && sig.switchSlot < 0 && sig.ownSlot < 0;
}

/// (byte, bit) of bit k (0 = LSB) of a compiled signal.
std::pair<std::uint32_t, std::uint32_t> bitPosition(const CompiledSignal& sig, std::uint32_t k) {
  if (sig.byteOrder == ByteOrder::LittleEndian) {
    const std::uint32_t position = sig.firstByte * 8 + sig.shift + k;
    return {position / 8, position % 8};
  }
  const std::uint32_t lsbLinear = sig.firstByte * 8 + (sig.wide ? 71u : 63u) - sig.shift;
  const std::uint32_t linear = lsbLinear - k;
  return {linear / 8, 7 - linear % 8};
}

}  // namespace

MessageCodec MessageCodec::compile(const Database& database, const Message& message) {
  MessageCodec codec;
  codec.m_length = message.length;
  const std::size_t count = message.signals.size();
  codec.m_byIndex.assign(count, -1);

  // Depth in the selection chain (0 = always present); -1 = cannot be decoded.
  std::vector<int> depth(count, 0);
  for (std::size_t i = 0; i < count; ++i) {
    const Signal* cursor = &message.signals[i];
    int steps = 0;
    bool usable = true;
    while (usable) {
      if (!cursor->decodable()) usable = false;
      // Selected by a switch: "mN"/"mNM", or an "M" nested through SG_MUL_VAL_ (muxSwitch set).
      const bool multiplexed = cursor->muxRole == MuxRole::Multiplexed ||
                               cursor->muxRole == MuxRole::MultiplexedMultiplexor || !cursor->muxSwitch.empty();
      if (!multiplexed) break;
      if (cursor->muxSwitch.empty() || steps > static_cast<int>(count)) {
        usable = false;
        break;
      }
      cursor = message.findSignal(cursor->muxSwitch);
      if (!cursor) usable = false;
      ++steps;
    }
    depth[i] = usable ? steps : -1;
  }

  std::vector<std::uint32_t> order;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (depth[i] >= 0) {
      order.push_back(i);
    } else {
      codec.m_skipped.push_back(i);
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return depth[a] < depth[b]; });

  // Slots for multiplexors that select at least one compiled signal.
  std::vector<int> slotOf(count, -1);
  int nextSlot = 0;
  for (const std::uint32_t i : order) {
    const Signal& sig = message.signals[i];
    if (sig.muxSwitch.empty()) continue;
    const Signal* sw = message.findSignal(sig.muxSwitch);
    const auto switchIndex = static_cast<std::size_t>(sw - message.signals.data());
    if (slotOf[switchIndex] < 0 && nextSlot < static_cast<int>(MAX_MUX_SLOTS)) slotOf[switchIndex] = nextSlot++;
  }

  for (const std::uint32_t i : order) {
    const Signal& sig = message.signals[i];
    CompiledSignal compiled = layout(sig, i);
    compiled.ownSlot = static_cast<std::int16_t>(slotOf[i]);
    if (!sig.muxSwitch.empty()) {
      const Signal* sw = message.findSignal(sig.muxSwitch);
      const int slot = slotOf[static_cast<std::size_t>(sw - message.signals.data())];
      if (slot < 0) {  // more than MAX_MUX_SLOTS multiplexors: not decodable
        codec.m_skipped.push_back(i);
        continue;
      }
      compiled.switchSlot = static_cast<std::int16_t>(slot);
      compiled.rangeBegin = static_cast<std::uint32_t>(codec.m_ranges.size());
      if (sig.muxRanges.empty()) {
        codec.m_ranges.push_back(MuxRange{sig.muxValue, sig.muxValue});
      } else {
        codec.m_ranges.insert(codec.m_ranges.end(), sig.muxRanges.begin(), sig.muxRanges.end());
      }
      compiled.rangeCount = static_cast<std::uint16_t>(codec.m_ranges.size() - compiled.rangeBegin);
    }
    codec.m_byIndex[i] = static_cast<std::int32_t>(codec.m_signals.size());
    codec.m_signals.push_back(compiled);
    codec.m_limits.emplace_back(sig.minimum, sig.maximum);
  }
  std::sort(codec.m_skipped.begin(), codec.m_skipped.end());

  codec.m_plain = std::all_of(codec.m_signals.begin(), codec.m_signals.end(), wordDecodable);
  if (codec.m_plain) {
    for (const CompiledSignal& compiled : codec.m_signals) {
      codec.m_word.push_back(wordForm(compiled));
      codec.m_plainBytes = std::max(codec.m_plainBytes, compiled.lastByte + 1);
    }
  }

  // Initial payload: J1939 "not available" ones or zeros, then the start values.
  codec.m_initial.assign(message.length, message.isJ1939() ? 0xFF : 0x00);
  for (const CompiledSignal& compiled : codec.m_signals) {
    const Signal& sig = message.signals[compiled.index];
    if (compiled.switchSlot >= 0) continue;
    const auto start = database.startValueRaw(sig);
    if (!start) continue;
    DecodedValue raw;
    raw.kind = compiled.kind;
    if (compiled.kind == RawKind::Float32 || compiled.kind == RawKind::Float64) {
      raw.rawFloat = *start;
    } else if (compiled.kind == RawKind::Signed) {
      raw.rawSigned = static_cast<std::int64_t>(std::llround(*start));
    } else {
      raw.rawUnsigned = *start <= 0 ? 0 : static_cast<std::uint64_t>(std::llround(*start));
    }
    (void)codec.encodeRaw(compiled.index, raw, codec.m_initial);
  }
  return codec;
}

const CompiledSignal* MessageCodec::find(std::uint32_t signalIndex) const noexcept {
  if (signalIndex >= m_byIndex.size() || m_byIndex[signalIndex] < 0) return nullptr;
  return &m_signals[static_cast<std::size_t>(m_byIndex[signalIndex])];
}

EncodeStatus MessageCodec::encodeRaw(std::uint32_t signalIndex, const DecodedValue& raw,
                                     std::span<std::uint8_t> buffer) const noexcept {
  const CompiledSignal* sig = find(signalIndex);
  if (!sig) return EncodeStatus::NotEncodable;
  if (sig->lastByte >= buffer.size()) return EncodeStatus::BufferTooShort;
  std::uint64_t bits = 0;
  switch (sig->kind) {
    case RawKind::Unsigned:
      if (raw.rawUnsigned > sig->mask) return EncodeStatus::OutOfRange;
      bits = raw.rawUnsigned;
      break;
    case RawKind::Signed: {
      const std::int64_t limit = sig->size >= 64 ? std::numeric_limits<std::int64_t>::max()
                                                 : (std::int64_t{1} << (sig->size - 1)) - 1;
      if (raw.rawSigned > limit || raw.rawSigned < -limit - 1) return EncodeStatus::OutOfRange;
      bits = static_cast<std::uint64_t>(raw.rawSigned) & sig->mask;
      break;
    }
    case RawKind::Float32: {
      const auto narrow = static_cast<float>(raw.rawFloat);
      std::uint32_t word;
      std::memcpy(&word, &narrow, sizeof word);
      bits = word;
      break;
    }
    case RawKind::Float64:
      std::memcpy(&bits, &raw.rawFloat, sizeof bits);
      break;
  }
  for (std::uint32_t k = 0; k < sig->size; ++k) {
    const auto [byte, bit] = bitPosition(*sig, k);
    const auto flag = static_cast<std::uint8_t>(1u << bit);
    if ((bits >> k) & 1u) {
      buffer[byte] = static_cast<std::uint8_t>(buffer[byte] | flag);
    } else {
      buffer[byte] = static_cast<std::uint8_t>(buffer[byte] & ~flag);
    }
  }
  return EncodeStatus::Ok;
}

EncodeStatus MessageCodec::encode(std::uint32_t signalIndex, double physical,
                                  std::span<std::uint8_t> buffer) const noexcept {
  const CompiledSignal* sig = find(signalIndex);
  if (!sig || !std::isfinite(physical) || sig->factor == 0.0) return EncodeStatus::NotEncodable;
  // [min|max] is checked when the DBC gives a real range (min < max); "[0|0]" means none.
  const auto& [minimum, maximum] = m_limits[static_cast<std::size_t>(m_byIndex[signalIndex])];
  if (minimum < maximum) {
    const double tolerance = 1e-9 * std::max({1.0, std::fabs(minimum), std::fabs(maximum)});
    if (physical < minimum - tolerance || physical > maximum + tolerance) return EncodeStatus::OutOfRange;
  }
  DecodedValue raw;
  raw.kind = sig->kind;
  const double scaled = (physical - sig->offset) / sig->factor;
  if (sig->kind == RawKind::Float32 || sig->kind == RawKind::Float64) {
    raw.rawFloat = scaled;
  } else {
    const double rounded = std::nearbyint(scaled);
    if (sig->kind == RawKind::Signed) {
      if (rounded < -9.2233720368547758e18 || rounded >= 9.2233720368547758e18) return EncodeStatus::OutOfRange;
      raw.rawSigned = static_cast<std::int64_t>(rounded);
    } else {
      if (rounded < 0 || rounded >= 1.8446744073709552e19) return EncodeStatus::OutOfRange;
      raw.rawUnsigned = static_cast<std::uint64_t>(rounded);
    }
  }
  return encodeRaw(signalIndex, raw, buffer);
}

DatabaseCodec::DatabaseCodec(const Database& database) {
  m_codecs.reserve(database.messages.size());
  for (const Message& msg : database.messages) m_codecs.push_back(MessageCodec::compile(database, msg));
}

}  // namespace openvcu::dbc
