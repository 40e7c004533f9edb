#pragma once
// The one bridge between a DBC message and the signal table: built once at load from the
// message and the catalog, it holds the message's compiled codec and, per DBC signal, its
// table slot (config::signalKey looked up in the catalog; none when the catalog lacks it)
// and its DBC range. Frames then go into the table's bus plane and out of its command and
// override planes without a look-up, a string or an allocation.
//
//   const bridge::DatabaseBinding bindings(vehicle.database, catalog);        // at load
//   const bridge::MessageBinding& hvessd2 = bindings[messageIndex];
//   // can-rx: a received frame, range-checked
//   const bridge::DecodeResult decoded =
//       hvessd2.decodeInto(table, frame.payload(), nowNs, 0xF3, bridge::RangeCheck::Mark);
//   // -> HS_FastUpdSOC 87.5 lands in slot "VIC.HVESSD2_PGN61585.HS_FastUpdSOC" (bus plane,
//   //    source 0xF3, time nowNs, Valid; OutOfRange when outside [0|100])
//   // can-tx: a frame from the effective commands (override, else command)
//   hvessd2.encodeFrom(table, payload);
//   // ecu-sim / the HMI's trace: values by signal, no table
//   const auto soc = bindings.find("HVESSD2_PGN61585", "HS_FastUpdSOC");   // a SignalRef
//   const std::optional<double> value = bindings[soc->message].value(soc->signal, payload);
//
// Multiplexed signals: decoding visits only the active ones (the codec's rule); encodeFrom
// never writes a multiplexed ("mN") signal. Signals the codec cannot compile (over 64 bits,
// a float of the wrong size) are never decoded, and encoding one fails (NotEncodable).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/model.hpp"
#include "openvcu/signals/catalog.hpp"
#include "openvcu/signals/table.hpp"

namespace openvcu::bridge {

/// One signal of one DBC message: the message's index in Database::messages and the
/// signal's in Message::signals. Resolved once (DatabaseBinding::find), used per frame.
struct SignalRef {
  std::size_t message{};
  std::uint32_t signal{};
  friend bool operator==(const SignalRef&, const SignalRef&) = default;
};

/// A signal's DBC range [minimum|maximum]; minimum >= maximum ("[0|0]") means none.
struct Limits {
  double minimum{};
  double maximum{};
  [[nodiscard]] bool any() const noexcept { return minimum < maximum; }
  /// true without a range; else minimum <= value <= maximum.
  [[nodiscard]] bool contains(double value) const noexcept {
    return !any() || (value >= minimum && value <= maximum);
  }
  /// `value` moved into the range (unchanged without one).
  [[nodiscard]] double clamp(double value) const noexcept { return any() ? std::clamp(value, minimum, maximum) : value; }
};

/// How decodeInto() sets the quality of what it writes.
enum class RangeCheck : std::uint8_t {
  Mark,  ///< outside the DBC range: Quality::OutOfRange (a received frame, can-rx)
  None,  ///< always Quality::Valid (what this node sent itself, can-tx)
};

/// What one decodeInto() did.
struct DecodeResult {
  std::uint16_t decoded{};     ///< signals decoded (active and inside the payload)
  std::uint16_t written{};     ///< ... of them written to the table (those with a slot)
  std::uint16_t outOfRange{};  ///< ... of those written with Quality::OutOfRange
  std::uint16_t missing{};     ///< active signals not (fully) inside the payload
};

/// What one encodeFrom() did.
struct EncodeResult {
  std::uint16_t encoded{};  ///< signals written into the buffer
  std::uint16_t errors{};   ///< signals with a value the codec refused (their bits kept)
};

/// The precompiled mapping of one DBC message's signals to table slots.
/// @note immutable after bind(): thread-safe to share for reading. Every per-frame member is
///       noexcept and allocation-free; the Database it was bound from must outlive it.
class MessageBinding {
 public:
  MessageBinding() = default;

  /// Binds database.messages[messageIndex]: compiles its codec and looks each signal's key
  /// up in `catalog` (nullptr: no slots, for users without a table). Allocates: load only.
  static MessageBinding bind(const dbc::Database& database, std::size_t messageIndex,
                             const signals::Catalog* catalog);

  [[nodiscard]] std::size_t messageIndex() const noexcept { return m_messageIndex; }
  [[nodiscard]] const dbc::Message& message() const noexcept { return *m_message; }
  [[nodiscard]] const dbc::MessageCodec& codec() const noexcept { return m_codec; }
  /// Message::signals.size(): every DBC signal, compiled or not.
  [[nodiscard]] std::uint32_t signalCount() const noexcept { return static_cast<std::uint32_t>(m_signals.size()); }
  /// The table slot of DBC signal `signal`; empty when the catalog has none (or out of range).
  [[nodiscard]] std::optional<signals::SignalIndex> slot(std::uint32_t signal) const noexcept {
    if (signal >= m_signals.size() || m_signals[signal].slot == NO_SLOT) return std::nullopt;
    return m_signals[signal].slot;
  }
  /// The DBC range of `signal` (precondition: signal < signalCount()).
  [[nodiscard]] Limits limits(std::uint32_t signal) const noexcept { return m_signals[signal].limits; }
  /// The index of the signal named `name`, or empty. @note noexcept, allocation-free, O(signals).
  [[nodiscard]] std::optional<std::uint32_t> signalIndex(std::string_view name) const noexcept;

  // ---- into the table ------------------------------------------------------------------

  /// Decodes `payload` and writes each decoded signal that has a slot to the table's bus
  /// plane with `nowNs` and `source`; quality Valid, or OutOfRange outside its DBC range
  /// when `range` is Mark. Signals without a slot are skipped.
  /// @note noexcept, allocation-free; as thread-safe as SignalTable::writeBus.
  DecodeResult decodeInto(signals::SignalTable& table, std::span<const std::uint8_t> payload, std::int64_t nowNs,
                          std::uint16_t source, RangeCheck range) const noexcept;
  /// Marks the bus-plane quality of every bound slot (can-rx: Stale when the message timed out).
  void markBusQuality(signals::SignalTable& table, signals::Quality quality) const noexcept;

  // ---- out of the table ----------------------------------------------------------------

  /// Encodes into `buffer`, for each signal except multiplexed ("mN") ones, the value
  /// `valueOf(signal, slot)` returns (std::optional<double>; empty: the signal's bits are
  /// left as they are). `slot` is the signal's std::optional<signals::SignalIndex>.
  /// @note noexcept and allocation-free when valueOf is.
  template <typename ValueOf>
  EncodeResult encodeFrom(std::span<std::uint8_t> buffer, ValueOf&& valueOf) const noexcept;
  /// encodeFrom with each slot's effective command (override, else command); a signal with
  /// no slot, no command or a read that failed keeps its bits (e.g. the initial payload's).
  EncodeResult encodeFrom(const signals::SignalTable& table, std::span<std::uint8_t> buffer) const noexcept;

  // ---- values by signal, without a table (ecu-sim, the HMI's trace) ------------------------

  /// The codec's decode: visit(signal, const dbc::DecodedValue&) per active decoded signal.
  template <typename Visitor>
  dbc::DecodeSummary decode(std::span<const std::uint8_t> payload, Visitor&& visit) const noexcept {
    return m_codec.decode(payload, std::forward<Visitor>(visit));
  }
  /// values[signal] = physical value of each decoded signal (the others keep theirs);
  /// precondition: values.size() >= signalCount(). Returns the codec's summary.
  dbc::DecodeSummary decodeValues(std::span<const std::uint8_t> payload, std::span<double> values) const noexcept;
  /// The physical value of one signal in `payload`; empty when it is not decoded (not
  /// active, not inside the payload, not decodable).
  [[nodiscard]] std::optional<double> value(std::uint32_t signal, std::span<const std::uint8_t> payload) const noexcept;
  /// Encodes `value` moved into the signal's DBC range (a non-finite value is ignored:
  /// NotEncodable, nothing written).
  dbc::EncodeStatus encodeClamped(std::uint32_t signal, double value, std::span<std::uint8_t> buffer) const noexcept;

 private:
  static constexpr signals::SignalIndex NO_SLOT = static_cast<signals::SignalIndex>(-1);
  struct SignalBinding {
    signals::SignalIndex slot{NO_SLOT};
    Limits limits;
    bool multiplexed{};  ///< muxRole Multiplexed: never encoded from values
  };

  std::size_t m_messageIndex{};
  const dbc::Message* m_message{};
  dbc::MessageCodec m_codec;
  std::vector<SignalBinding> m_signals;  ///< by Message::signals index
};

/// A MessageBinding for every message of a database, by its index in Database::messages.
/// @note immutable after construction: thread-safe to share for reading.
class DatabaseBinding {
 public:
  DatabaseBinding() = default;
  /// Every message bound without slots (values by signal only).
  explicit DatabaseBinding(const dbc::Database& database);
  /// Every message bound to `catalog`'s slots. Allocates: load only.
  DatabaseBinding(const dbc::Database& database, const signals::Catalog& catalog);

  /// precondition: messageIndex < size().
  [[nodiscard]] const MessageBinding& operator[](std::size_t messageIndex) const noexcept {
    return m_messages[messageIndex];
  }
  [[nodiscard]] std::size_t size() const noexcept { return m_messages.size(); }
  /// The signal `signal` of the message named `message`; empty when either is unknown.
  /// @note noexcept, allocation-free, O(messages + signals).
  [[nodiscard]] std::optional<SignalRef> find(std::string_view message, std::string_view signal) const noexcept;

 private:
  std::vector<MessageBinding> m_messages;
};

// ---------------------------------------------------------------- inline

template <typename ValueOf>
EncodeResult MessageBinding::encodeFrom(std::span<std::uint8_t> buffer, ValueOf&& valueOf) const noexcept {
  EncodeResult result;
  for (std::uint32_t s = 0; s < m_signals.size(); ++s) {
    const SignalBinding& signal = m_signals[s];
    if (signal.multiplexed) continue;  // which mux page to send is not a table value (docs/design/can-tx.md)
    const std::optional<signals::SignalIndex> maybeSlot =
        signal.slot == NO_SLOT ? std::nullopt : std::optional<signals::SignalIndex>(signal.slot);
    const std::optional<double> maybeValue = valueOf(s, maybeSlot);
    if (!maybeValue) continue;
    if (m_codec.encode(s, *maybeValue, buffer) == dbc::EncodeStatus::Ok) {
      ++result.encoded;
    } else {
      ++result.errors;
    }
  }
  return result;
}

}  // namespace openvcu::bridge
