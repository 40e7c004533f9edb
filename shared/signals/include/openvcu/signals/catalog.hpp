#pragma once
// The signal catalog: the ordered list of every signal of one stack instance, built from
// the configuration (every signal of every DBC message on every bus, plus the internal
// signals). It is the in-process half of the signal table: names, units, ranges and value
// texts stay here; the shared-memory table (table.hpp) holds only the values, addressed by
// the catalog's index. Every process builds the same catalog from the same configuration,
// and layoutHash() lets the table prove it (docs/design/signal-table.md).
//
//   Catalog::create({{"VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "%", 0, 100, ...},
//                    {"internal.operator.start", "", 0, 1, ...}})
//     -> index 0 and 1; find("VIC.HVESSD2_PGN61585.HS_FastUpdSoc")
//     -> error "unknown signal '...HS_FastUpdSoc' (did you mean '...HS_FastUpdSOC'?)"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "openvcu/core/result.hpp"

namespace openvcu::signals {

/// Version of the shared-memory layout (header, slot and plane formats). It is part of
/// every layout hash, so processes built with different layouts never attach to each
/// other's tables. Bump it whenever src/layout.hpp changes.
inline constexpr std::uint32_t SIGNAL_TABLE_FORMAT_VERSION = 2;  // 2: watches

/// Position of a signal in its catalog and of its slot in the table (0-based, dense).
using SignalIndex = std::uint32_t;

/// Upper bound on the number of signals in one catalog (a sanity limit, not a layout one).
inline constexpr std::size_t MAX_SIGNALS = 1'000'000;

enum class SignalKind : std::uint8_t {
  Bus,       ///< a signal of a DBC message on a bus
  Internal,  ///< operator switches, send-group enables, GPIO lines, FSM state, heartbeats
};

/// "Bus" / "Internal".
[[nodiscard]] std::string_view signalKindName(SignalKind kind) noexcept;

/// Which way a signal flows, seen from this VCU (shared/config derives it: a bus signal is
/// Transmitted when the VCU's DBC node is among its message's transmitters).
enum class SignalDirection : std::uint8_t {
  Received,     ///< a signal of a message other nodes send; can-rx writes it from the bus
  Transmitted,  ///< a signal of a message this VCU sends; can-tx sends it
  Internal,     ///< not on a bus: operator switches, send groups, GPIO levels, statuses
};

/// "received" / "transmitted" / "internal".
[[nodiscard]] std::string_view signalDirectionName(SignalDirection direction) noexcept;

/// Who wrote a value: each service's writer id (config::SERVICES), stamped on its writes.
using WriterId = std::uint16_t;
/// The owner of a signal no service owns (and "never written" in a command plane).
inline constexpr WriterId NO_OWNER = 0;

/// What the configuration says about one signal. Only `key` and `kind` (and the order of
/// the signals) shape the shared table; the rest is metadata for display and checks.
/// `direction`, `owner` and `reported` are the ownership contract (docs/design/contracts.md):
/// the owner is the one service that decides the signal's value and answers commands for it.
struct SignalInfo {
  std::string key;   ///< "VIC.HVESSD2_PGN61585.HS_FastUpdSOC", "internal.operator.start"
  std::string unit;  ///< "%", "V"; empty when none
  double minimum{};  ///< the DBC range (physical value)
  double maximum{};
  std::string comment;  ///< the DBC comment; empty when none
  std::string message;  ///< "HVESSD2_PGN61585"; empty for internal signals
  std::string bus;      ///< logical bus name ("vehicle"); empty for internal signals
  SignalKind kind{SignalKind::Bus};
  std::vector<std::pair<std::int64_t, std::string>> valueTexts;  ///< VAL_ table: 0 "Open", 1 "Closed"
  SignalDirection direction{SignalDirection::Received};
  WriterId owner{NO_OWNER};  ///< writer id of the owning service (config::serviceOfWriter names it)
  /// A status the stack reports (FSM state, heartbeats, bus health, DM1, GPIO levels): it is
  /// written by its owner alone and no command may set it.
  bool reported{false};
};

/// The value-table text of `value` ("Closed" for 1), when `value` is an integer the table names.
[[nodiscard]] std::optional<std::string> valueText(const SignalInfo& signal, double value);

/// An ordered, immutable list of signals with O(1) index access and hashed key lookup.
/// @note immutable after create(): thread-safe to share between threads for reading.
class Catalog {
 public:
  /// Refuses an empty key, a duplicate key (naming both indices) and more than MAX_SIGNALS.
  static Result<Catalog> create(std::vector<SignalInfo> signals);

  Catalog();  ///< the empty catalog

  [[nodiscard]] std::size_t size() const noexcept { return m_signals.size(); }
  [[nodiscard]] bool empty() const noexcept { return m_signals.empty(); }

  /// The signal at `index` (precondition: index < size(), checked by assert).
  [[nodiscard]] const SignalInfo& operator[](SignalIndex index) const noexcept;
  [[nodiscard]] std::span<const SignalInfo> signals() const noexcept { return m_signals; }
  /// The keys in catalog order (the candidates of "did you mean").
  [[nodiscard]] std::span<const std::string> keys() const noexcept { return m_keys; }

  /// The index of `key`, or empty when unknown.
  /// @note noexcept and allocation-free (heterogeneous hash lookup).
  [[nodiscard]] std::optional<SignalIndex> indexOf(std::string_view key) const noexcept;

  /// The index of `key`, or an error "unknown signal 'X'" with a "did you mean" suggestion.
  [[nodiscard]] Result<SignalIndex> find(std::string_view key) const;

  /// The known key closest to a mistyped `key`: a small edit distance on the whole key, or
  /// else the only key whose last component ("HS_FastUpdSOC") equals `key`'s.
  [[nodiscard]] std::optional<std::string> suggest(std::string_view key) const;

  /// 64-bit FNV-1a over the format version, the count, and each key and kind in order.
  /// Equal hashes <=> the same table layout (up to hash collisions).
  [[nodiscard]] std::uint64_t layoutHash() const noexcept { return m_layoutHash; }

 private:
  struct KeyHash {
    using is_transparent = void;
    std::size_t operator()(std::string_view key) const noexcept { return std::hash<std::string_view>{}(key); }
  };
  using IndexMap = std::unordered_map<std::string, SignalIndex, KeyHash, std::equal_to<>>;

  std::vector<SignalInfo> m_signals;
  std::vector<std::string> m_keys;
  IndexMap m_indexByKey;
  std::uint64_t m_layoutHash{};
};

/// The layout hash of an ordered list of (key, kind): what Catalog::layoutHash() returns.
[[nodiscard]] std::uint64_t computeLayoutHash(std::span<const SignalInfo> signals) noexcept;

}  // namespace openvcu::signals
