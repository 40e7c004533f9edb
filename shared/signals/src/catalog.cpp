#include "openvcu/signals/catalog.hpp"

#include <cassert>
#include <cmath>

#include "openvcu/core/text.hpp"

namespace openvcu::signals {

namespace {

// 64-bit FNV-1a (Fowler/Noll/Vo): offset basis 0xcbf29ce484222325, prime 0x100000001b3.
// Why FNV-1a: tiny, no dependency, and byte-order independent because we feed bytes.
constexpr std::uint64_t FNV_OFFSET_BASIS = 0xcbf29ce484222325ULL;
constexpr std::uint64_t FNV_PRIME = 0x100000001b3ULL;

class Fnv1a {
 public:
  void addByte(std::uint8_t byte) noexcept {
    m_state ^= byte;
    m_state *= FNV_PRIME;
  }
  void addBytes(std::string_view bytes) noexcept {
    for (const char c : bytes) addByte(static_cast<std::uint8_t>(c));
  }
  /// Little-endian, so the hash is the same on every host.
  void addInteger(std::uint64_t value) noexcept {
    for (int shift = 0; shift < 64; shift += 8) addByte(static_cast<std::uint8_t>(value >> shift));
  }
  [[nodiscard]] std::uint64_t value() const noexcept { return m_state; }

 private:
  std::uint64_t m_state{FNV_OFFSET_BASIS};
};

std::string_view lastComponent(std::string_view key) noexcept {
  const std::size_t dot = key.rfind('.');
  return dot == std::string_view::npos ? key : key.substr(dot + 1);
}

}  // namespace

std::optional<std::string> valueText(const SignalInfo& signal, double value) {
  if (!std::isfinite(value) || std::trunc(value) != value || std::fabs(value) > 9.0e18) return std::nullopt;
  const auto integral = static_cast<std::int64_t>(value);
  for (const auto& [number, text] : signal.valueTexts) {
    if (number == integral) return text;
  }
  return std::nullopt;
}

std::string_view signalKindName(SignalKind kind) noexcept {
  switch (kind) {
    case SignalKind::Bus:
      return "Bus";
    case SignalKind::Internal:
      return "Internal";
  }
  return "?";
}

std::string_view signalDirectionName(SignalDirection direction) noexcept {
  switch (direction) {
    case SignalDirection::Received:
      return "received";
    case SignalDirection::Transmitted:
      return "transmitted";
    case SignalDirection::Internal:
      return "internal";
  }
  return "?";
}

std::uint64_t computeLayoutHash(std::span<const SignalInfo> signals) noexcept {
  Fnv1a hash;
  hash.addBytes("openvcu.signals");
  hash.addInteger(SIGNAL_TABLE_FORMAT_VERSION);
  hash.addInteger(signals.size());
  for (const SignalInfo& signal : signals) {
    hash.addBytes(signal.key);
    hash.addByte(0);  // ends the key: ("ab", "c") and ("a", "bc") hash differently
    hash.addByte(static_cast<std::uint8_t>(signal.kind));
  }
  return hash.value();
}

Catalog::Catalog() : m_layoutHash(computeLayoutHash({})) {}

Result<Catalog> Catalog::create(std::vector<SignalInfo> signals) {
  if (signals.size() > MAX_SIGNALS) {
    return Error{"too many signals: " + std::to_string(signals.size()) + " (at most " + std::to_string(MAX_SIGNALS) +
                 ")"};
  }
  Catalog catalog;
  catalog.m_keys.reserve(signals.size());
  catalog.m_indexByKey.reserve(signals.size());
  for (std::size_t i = 0; i < signals.size(); ++i) {
    const std::string& key = signals[i].key;
    if (key.empty()) return Error{"signal " + std::to_string(i) + " has an empty key"};
    const auto [position, inserted] = catalog.m_indexByKey.emplace(key, static_cast<SignalIndex>(i));
    if (!inserted) {
      return Error{"duplicate signal key '" + key + "' (signals " + std::to_string(position->second) + " and " +
                   std::to_string(i) + ")"};
    }
    catalog.m_keys.push_back(key);
  }
  catalog.m_signals = std::move(signals);
  catalog.m_layoutHash = computeLayoutHash(catalog.m_signals);
  return catalog;
}

const SignalInfo& Catalog::operator[](SignalIndex index) const noexcept {
  assert(index < m_signals.size());
  return m_signals[index];
}

std::optional<SignalIndex> Catalog::indexOf(std::string_view key) const noexcept {
  const auto found = m_indexByKey.find(key);
  if (found == m_indexByKey.end()) return std::nullopt;
  return found->second;
}

Result<SignalIndex> Catalog::find(std::string_view key) const {
  if (const auto maybeIndex = indexOf(key)) return *maybeIndex;
  std::string message = "unknown signal '" + std::string(key) + "'";
  if (const auto maybeSuggestion = suggest(key)) message += " (did you mean '" + *maybeSuggestion + "'?)";
  return Error{std::move(message)};
}

std::optional<std::string> Catalog::suggest(std::string_view key) const {
  if (auto maybeClose = text::didYouMean(key, m_keys)) return maybeClose;
  // A key typed without its "BUS.MESSAGE." prefix: suggest the one key that ends in it.
  const std::string_view tail = lastComponent(key);
  std::optional<std::string> maybeOnly;
  for (const std::string& candidate : m_keys) {
    if (lastComponent(candidate) != tail) continue;
    if (maybeOnly) return std::nullopt;  // ambiguous: several messages carry this signal
    maybeOnly = candidate;
  }
  return maybeOnly;
}

}  // namespace openvcu::signals
