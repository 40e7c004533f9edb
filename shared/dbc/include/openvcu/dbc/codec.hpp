#pragma once
// The per-frame codec: each signal precompiled to a byte window, a shift and a mask
// (dbcppp's "prestored masks and fixed offsets"), so decoding a frame is a handful of
// loads and shifts per signal. Compiled once at load; decode and encode are noexcept
// and allocate nothing. A classic frame of a "plain" message (no multiplexing, integer
// signals, all in bytes 0..7) decodes from one 64-bit word with two shifts per signal.
//
//   MessageCodec codec = MessageCodec::compile(db, *db.findMessage(0x0CEFF321, true));
//   codec.decode(payload, [&](std::uint32_t signalIndex, const DecodedValue& value) {
//     table[signalIndex] = value.physical;   // only active multiplexed signals are visited
//   });

#include "openvcu/dbc/model.hpp"

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace openvcu::dbc {

enum class RawKind : std::uint8_t { Unsigned, Signed, Float32, Float64 };

/// One decoded signal. `raw` holds the bits as a number of `kind`.
struct DecodedValue {
  RawKind kind{RawKind::Unsigned};
  union {
    std::uint64_t rawUnsigned;
    std::int64_t rawSigned;
    double rawFloat;  ///< float32 and float64 signals
  };
  double physical{};  ///< raw * factor + offset

  DecodedValue() : rawUnsigned(0) {}
};

struct DecodeSummary {
  std::uint16_t decoded{};  ///< signals visited
  std::uint16_t missing{};  ///< active signals not (fully) inside the received bytes
};

enum class EncodeStatus : std::uint8_t {
  Ok,
  OutOfRange,     ///< outside the DBC [min|max] or not representable in the signal's bits
  NotEncodable,   ///< longer than 64 bits, or not finite
  BufferTooShort, ///< the signal does not fit in the buffer
};

/// Layout of one signal, derived from the model. Plain data.
struct CompiledSignal {
  std::uint64_t mask{};        ///< `size` low bits set
  double factor{1.0};
  double offset{};
  std::uint32_t index{};       ///< position in Message::signals
  std::uint32_t firstByte{};   ///< start of the 8/9-byte window
  std::uint32_t lastByte{};    ///< last byte the signal needs (inclusive)
  std::uint32_t rangeBegin{};  ///< into MessageCodec's mux ranges
  std::uint16_t rangeCount{};
  std::int16_t switchSlot{-1}; ///< multiplexor slot that selects this signal, -1 if none
  std::int16_t ownSlot{-1};    ///< slot this multiplexor stores its raw value in, -1 if none
  std::uint8_t shift{};        ///< right shift applied to the window
  std::uint8_t size{};
  RawKind kind{RawKind::Unsigned};
  ByteOrder byteOrder{ByteOrder::LittleEndian};
  bool wide{};                 ///< window spans 9 bytes (unaligned signals of 58..64 bits)
};

/// A signal of a "plain" message (see MessageCodec::isPlain) as two shifts of one 64-bit
/// word: (word << leftShift) moves the signal's MSB to bit 63, >> rightShift (64 - size)
/// right-aligns it, and the xor/subtract with signBit sign-extends. Plain data.
struct WordSignal {
  double factor{1.0};
  double offset{};
  std::uint64_t signBit{};     ///< 1 << (size - 1) for signed signals, 0 for unsigned
  std::uint32_t index{};       ///< position in Message::signals
  std::uint8_t leftShift{};
  std::uint8_t rightShift{};
  std::uint8_t bigEndian{};    ///< 0: word of bytes 0..7 LSB-first; 1: the byte-swapped word
  RawKind kind{RawKind::Unsigned};
};

class MessageCodec {
 public:
  static constexpr std::size_t MAX_MUX_SLOTS = 32;

  MessageCodec() = default;
  /// Compiles a message. Signals that are not decodable (over 64 bits, a float of the
  /// wrong size) or whose multiplexor is not decodable are left out and listed in
  /// skippedSignals().
  static MessageCodec compile(const Database& database, const Message& message);

  /// Decodes the active signals that lie inside `payload` and calls
  /// visit(signalIndex, DecodedValue) for each, multiplexors before the signals they select.
  /// @note noexcept, allocation-free, reentrant.
  template <typename Visitor>
  DecodeSummary decode(std::span<const std::uint8_t> payload, Visitor&& visit) const noexcept;

  /// Encodes a physical value (rounded to the nearest raw step, range-checked) into
  /// `buffer`; the other bits are left untouched.
  EncodeStatus encode(std::uint32_t signalIndex, double physical,
                      std::span<std::uint8_t> buffer) const noexcept;
  /// Encodes a raw value (integer signals: the two's complement bits; floats: the value).
  EncodeStatus encodeRaw(std::uint32_t signalIndex, const DecodedValue& raw,
                         std::span<std::uint8_t> buffer) const noexcept;
  /// The message's initial payload: ones in every bit for J1939 messages (J1939-71
  /// "not available"), zeros otherwise, then each signal's GenSigStartValue.
  [[nodiscard]] std::span<const std::uint8_t> initialPayload() const noexcept { return m_initial; }

  [[nodiscard]] std::uint32_t length() const noexcept { return m_length; }
  [[nodiscard]] std::span<const CompiledSignal> signals() const noexcept { return m_signals; }
  [[nodiscard]] const std::vector<std::uint32_t>& skippedSignals() const noexcept { return m_skipped; }
  /// Compiled layout of Message::signals[signalIndex], or nullptr if it was skipped.
  [[nodiscard]] const CompiledSignal* find(std::uint32_t signalIndex) const noexcept;
  /// No multiplexing, integer signals only (unsigned ones under 64 bits), all within bytes
  /// 0..7: a classic frame holding all of them decodes through wordSignals().
  [[nodiscard]] bool isPlain() const noexcept { return m_plain; }
  [[nodiscard]] std::span<const WordSignal> wordSignals() const noexcept { return m_word; }

  /// Extracts one signal's raw value from a buffer holding at least lastByte + 9 bytes.
  static DecodedValue extract(const CompiledSignal& signal, const std::uint8_t* padded) noexcept;
  /// Masks, sign-extends and scales a signal's raw bits (right-aligned).
  static DecodedValue toValue(const CompiledSignal& signal, std::uint64_t bits) noexcept;
  /// Classic-frame fast path: `word` holds payload bytes 0..7 (byte 0 least significant),
  /// and the signal lies within them (lastByte < 8, so never `wide`).
  static DecodedValue extractFromWord(const CompiledSignal& signal, std::uint64_t word) noexcept;

 private:
  [[nodiscard]] bool selected(const CompiledSignal& signal, const std::uint64_t* slots,
                              std::uint32_t activeSlots) const noexcept;

  // The plain fast path's data first: it is what a decode of a classic frame touches.
  bool m_plain{};
  std::uint32_t m_plainBytes{};           ///< bytes a frame needs to hold every signal
  std::vector<WordSignal> m_word;         ///< m_signals in the same order, when m_plain
  std::vector<CompiledSignal> m_signals;  ///< multiplexors first, then what they select
  std::vector<MuxRange> m_ranges;
  std::vector<std::pair<double, double>> m_limits;  ///< DBC [min|max] per m_signals entry
  std::vector<std::int32_t> m_byIndex;    ///< Message::signals index -> m_signals index or -1
  std::vector<std::uint8_t> m_initial;
  std::vector<std::uint32_t> m_skipped;
  std::uint32_t m_length{};
};

/// Codecs for every message of a database, by the message's index in Database::messages.
class DatabaseCodec {
 public:
  DatabaseCodec() = default;
  explicit DatabaseCodec(const Database& database);
  [[nodiscard]] const MessageCodec& operator[](std::size_t messageIndex) const noexcept {
    return m_codecs[messageIndex];
  }
  [[nodiscard]] std::size_t size() const noexcept { return m_codecs.size(); }

 private:
  std::vector<MessageCodec> m_codecs;
};

// ---------------------------------------------------------------- inline hot path

inline DecodedValue MessageCodec::extract(const CompiledSignal& signal,
                                          const std::uint8_t* padded) noexcept {
  const std::uint8_t* window = padded + signal.firstByte;
  std::uint64_t bits = 0;
  if (signal.byteOrder == ByteOrder::LittleEndian) {
    std::uint64_t word = 0;
    for (int k = 7; k >= 0; --k) word = (word << 8) | window[k];  // compiles to one load
    bits = word >> signal.shift;
    if (signal.wide) bits |= static_cast<std::uint64_t>(window[8]) << (64 - signal.shift);
  } else {
    std::uint64_t word = 0;
    for (int k = 0; k < 8; ++k) word = (word << 8) | window[k];  // compiles to load + bswap
    if (signal.wide) {
      // 72-bit window: shift (71 - lsb) is 1..7 here.
      bits = (word << (8 - signal.shift)) | (static_cast<std::uint64_t>(window[8]) >> signal.shift);
    } else {
      bits = word >> signal.shift;
    }
  }
  return toValue(signal, bits);
}

inline DecodedValue MessageCodec::toValue(const CompiledSignal& signal, std::uint64_t bits) noexcept {
  bits &= signal.mask;

  DecodedValue value;
  value.kind = signal.kind;
  switch (signal.kind) {
    case RawKind::Unsigned:
      value.rawUnsigned = bits;
      // Under 64 bits the value fits int64: one signed conversion instead of x86-64's
      // branchy unsigned 64-bit to double sequence, same result.
      value.physical = (signal.size < 64 ? static_cast<double>(static_cast<std::int64_t>(bits))
                                         : static_cast<double>(bits)) *
                           signal.factor +
                       signal.offset;
      break;
    case RawKind::Signed: {
      const std::uint64_t signBit = std::uint64_t{1} << (signal.size - 1);
      value.rawSigned = static_cast<std::int64_t>((bits ^ signBit) - signBit);
      value.physical = static_cast<double>(value.rawSigned) * signal.factor + signal.offset;
      break;
    }
    case RawKind::Float32: {
      const auto narrow = static_cast<std::uint32_t>(bits);
      float f;
      std::memcpy(&f, &narrow, sizeof f);
      value.rawFloat = static_cast<double>(f);
      value.physical = value.rawFloat * signal.factor + signal.offset;
      break;
    }
    case RawKind::Float64: {
      double d;
      std::memcpy(&d, &bits, sizeof d);
      value.rawFloat = d;
      value.physical = d * signal.factor + signal.offset;
      break;
    }
  }
  return value;
}

inline DecodedValue MessageCodec::extractFromWord(const CompiledSignal& signal, std::uint64_t word) noexcept {
  const unsigned byteShift = signal.firstByte * 8;
  if (signal.byteOrder == ByteOrder::LittleEndian) return toValue(signal, word >> (byteShift + signal.shift));
  // Bytes 0..7 MSB-first, moved so the signal's first byte leads, as extract()'s window.
  return toValue(signal, (__builtin_bswap64(word) << byteShift) >> signal.shift);
}

inline bool MessageCodec::selected(const CompiledSignal& signal, const std::uint64_t* slots,
                                   std::uint32_t activeSlots) const noexcept {
  if (signal.switchSlot < 0) return true;
  const auto slot = static_cast<std::uint32_t>(signal.switchSlot);
  if ((activeSlots & (1u << slot)) == 0) return false;
  const std::uint64_t switchValue = slots[slot];
  for (std::uint32_t r = 0; r < signal.rangeCount; ++r) {
    const MuxRange& range = m_ranges[signal.rangeBegin + r];
    if (switchValue >= range.low && switchValue <= range.high) return true;
  }
  return false;
}

template <typename Visitor>
DecodeSummary MessageCodec::decode(std::span<const std::uint8_t> payload, Visitor&& visit) const noexcept {
  // Windows read up to 9 bytes past a signal's first byte: decode from a zero-padded copy
  // so no signal ever reads outside the received bytes.
  constexpr std::size_t PAD = 9;
  const std::size_t length = payload.size();
  DecodeSummary summary;
  std::uint64_t slots[MAX_MUX_SLOTS];
  std::uint32_t activeSlots = 0;
  if (length <= 8) {
    // Classic frames: one 64-bit word, a shift and a mask per signal (no padded copy).
    static_assert(std::endian::native == std::endian::little, "the word fast path assumes a little-endian host");
    std::uint64_t word = 0;
    if (length == 8) {
      std::memcpy(&word, payload.data(), 8);  // fixed size: one load, not a memcpy call
    } else {
      for (std::size_t k = 0; k < length; ++k) word |= static_cast<std::uint64_t>(payload[k]) << (8 * k);
    }
    if (m_plain && length >= m_plainBytes) {
      // Plain message, every signal present: no selection, no length test, no kind switch;
      // the byte order picks one of two words by index instead of a branch.
      const std::uint64_t words[2] = {word, __builtin_bswap64(word)};
      for (const WordSignal& signal : m_word) {
        const std::uint64_t bits = (words[signal.bigEndian] << signal.leftShift) >> signal.rightShift;
        const std::uint64_t raw = (bits ^ signal.signBit) - signal.signBit;
        DecodedValue value;
        value.kind = signal.kind;
        if (signal.signBit != 0) {
          value.rawSigned = static_cast<std::int64_t>(raw);
        } else {
          value.rawUnsigned = raw;
        }
        value.physical = static_cast<double>(static_cast<std::int64_t>(raw)) * signal.factor + signal.offset;
        visit(signal.index, value);
      }
      summary.decoded = static_cast<std::uint16_t>(m_word.size());
      return summary;
    }
    for (const CompiledSignal& signal : m_signals) {
      if (!selected(signal, slots, activeSlots)) continue;
      if (signal.lastByte >= length) {
        ++summary.missing;
        continue;
      }
      const DecodedValue value = extractFromWord(signal, word);
      if (signal.ownSlot >= 0) {
        const auto slot = static_cast<std::uint32_t>(signal.ownSlot);
        slots[slot] = value.kind == RawKind::Signed ? static_cast<std::uint64_t>(value.rawSigned) & signal.mask
                                                    : value.rawUnsigned;
        activeSlots |= 1u << slot;
      }
      ++summary.decoded;
      visit(signal.index, value);
    }
    return summary;
  }
  std::array<std::uint8_t, 64 + PAD> small;
  const std::uint8_t* padded = nullptr;
  if (length <= 64) {
    if (length != 0) std::memcpy(small.data(), payload.data(), length);  // an empty span may be null
    std::memset(small.data() + length, 0, small.size() - length);
    padded = small.data();
  }

  for (const CompiledSignal& signal : m_signals) {
    if (!selected(signal, slots, activeSlots)) continue;
    if (signal.lastByte >= length) {
      ++summary.missing;
      continue;
    }
    DecodedValue value;
    if (padded != nullptr) {
      value = extract(signal, padded);
    } else {
      // Transport-protocol sized payload (> 64 bytes): copy just this signal's window.
      std::array<std::uint8_t, PAD + 1> window{};
      const std::size_t available = std::min<std::size_t>(PAD, length - signal.firstByte);
      std::memcpy(window.data(), payload.data() + signal.firstByte, available);
      CompiledSignal local = signal;
      local.firstByte = 0;
      value = extract(local, window.data());
    }
    if (signal.ownSlot >= 0) {
      const auto slot = static_cast<std::uint32_t>(signal.ownSlot);
      // The bit pattern selects: a signed 8-bit multiplexor reading -128 selects m128.
      slots[slot] = value.kind == RawKind::Signed
                        ? static_cast<std::uint64_t>(value.rawSigned) & signal.mask
                        : value.rawUnsigned;
      activeSlots |= 1u << slot;
    }
    ++summary.decoded;
    visit(signal.index, value);
  }
  return summary;
}

}  // namespace openvcu::dbc
