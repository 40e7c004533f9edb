#pragma once
// SAE J1939-81 NAME: the 64-bit identity of a controller application (CA). It is the data of
// the Address Claimed message (PGN 60928), least significant byte first, and it decides every
// address contest: the numerically lower NAME has the higher priority and keeps the address.
//
//   bit 63      arbitrary address capable (AAC): may move to another address
//   bits 62-60  industry group (3 = construction equipment)
//   bits 59-56  vehicle system instance
//   bits 55-49  vehicle system (within the industry group)
//   bit 48      reserved (sent as 0)
//   bits 47-40  function (0..127 for every industry group, 128..253 by industry group
//               and vehicle system)
//   bits 39-35  function instance
//   bits 34-32  ECU instance
//   bits 31-21  manufacturer code (assigned by SAE)
//   bits 20-0   identity number (the manufacturer's serial)
//
//   AAC 1, IG 3, VSI 10, VS 0x55, function 0x80, FI 21, ECU 5, manufacturer 0x5A5,
//   identity 0x12345 -> 0xBAAA80ADB4A12345 -> on the bus 45 23 A1 B4 AD 80 AA BA

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace openvcu::j1939 {

inline constexpr std::size_t NAME_LENGTH = 8;  ///< the Address Claimed payload, 8 bytes

inline constexpr std::uint8_t NAME_MAX_INDUSTRY_GROUP = 0x7;             ///< 3 bits, 7
inline constexpr std::uint8_t NAME_MAX_VEHICLE_SYSTEM_INSTANCE = 0xF;    ///< 4 bits, 15
inline constexpr std::uint8_t NAME_MAX_VEHICLE_SYSTEM = 0x7F;            ///< 7 bits, 127
inline constexpr std::uint8_t NAME_MAX_FUNCTION = 0xFF;                  ///< 8 bits, 255
inline constexpr std::uint8_t NAME_MAX_FUNCTION_INSTANCE = 0x1F;         ///< 5 bits, 31
inline constexpr std::uint8_t NAME_MAX_ECU_INSTANCE = 0x7;               ///< 3 bits, 7
inline constexpr std::uint16_t NAME_MAX_MANUFACTURER_CODE = 0x7FF;       ///< 11 bits, 2047
inline constexpr std::uint32_t NAME_MAX_IDENTITY_NUMBER = 0x1FFFFF;      ///< 21 bits, 2097151

using NamePayload = std::array<std::uint8_t, NAME_LENGTH>;

/// The NAME's fields. toValue() keeps the low bits of each field that fit its width;
/// fits() says whether every field fits (a configuration checks it before use).
struct Name {
  bool arbitraryAddressCapable{};      ///< 1 bit
  std::uint8_t industryGroup{};        ///< 3 bits
  std::uint8_t vehicleSystemInstance{};///< 4 bits
  std::uint8_t vehicleSystem{};        ///< 7 bits
  bool reserved{};                     ///< 1 bit, 0 when sent by us
  std::uint8_t function{};             ///< 8 bits
  std::uint8_t functionInstance{};     ///< 5 bits
  std::uint8_t ecuInstance{};          ///< 3 bits
  std::uint16_t manufacturerCode{};    ///< 11 bits
  std::uint32_t identityNumber{};      ///< 21 bits

  /// Every field within its width.
  [[nodiscard]] constexpr bool fits() const noexcept {
    return industryGroup <= NAME_MAX_INDUSTRY_GROUP &&
           vehicleSystemInstance <= NAME_MAX_VEHICLE_SYSTEM_INSTANCE &&
           vehicleSystem <= NAME_MAX_VEHICLE_SYSTEM && functionInstance <= NAME_MAX_FUNCTION_INSTANCE &&
           ecuInstance <= NAME_MAX_ECU_INSTANCE && manufacturerCode <= NAME_MAX_MANUFACTURER_CODE &&
           identityNumber <= NAME_MAX_IDENTITY_NUMBER;
  }

  /// The 64-bit NAME (layout above); fields wider than their width are cut to it.
  [[nodiscard]] constexpr std::uint64_t toValue() const noexcept {
    return (static_cast<std::uint64_t>(arbitraryAddressCapable) << 63) |
           (static_cast<std::uint64_t>(industryGroup & NAME_MAX_INDUSTRY_GROUP) << 60) |
           (static_cast<std::uint64_t>(vehicleSystemInstance & NAME_MAX_VEHICLE_SYSTEM_INSTANCE) << 56) |
           (static_cast<std::uint64_t>(vehicleSystem & NAME_MAX_VEHICLE_SYSTEM) << 49) |
           (static_cast<std::uint64_t>(reserved) << 48) |
           (static_cast<std::uint64_t>(function) << 40) |
           (static_cast<std::uint64_t>(functionInstance & NAME_MAX_FUNCTION_INSTANCE) << 35) |
           (static_cast<std::uint64_t>(ecuInstance & NAME_MAX_ECU_INSTANCE) << 32) |
           (static_cast<std::uint64_t>(manufacturerCode & NAME_MAX_MANUFACTURER_CODE) << 21) |
           (identityNumber & NAME_MAX_IDENTITY_NUMBER);
  }

  /// The fields of a 64-bit NAME; fromValue(n).toValue() == n for every n.
  [[nodiscard]] static constexpr Name fromValue(std::uint64_t value) noexcept {
    Name name;
    name.arbitraryAddressCapable = ((value >> 63) & 1u) != 0;
    name.industryGroup = static_cast<std::uint8_t>((value >> 60) & NAME_MAX_INDUSTRY_GROUP);
    name.vehicleSystemInstance = static_cast<std::uint8_t>((value >> 56) & NAME_MAX_VEHICLE_SYSTEM_INSTANCE);
    name.vehicleSystem = static_cast<std::uint8_t>((value >> 49) & NAME_MAX_VEHICLE_SYSTEM);
    name.reserved = ((value >> 48) & 1u) != 0;
    name.function = static_cast<std::uint8_t>((value >> 40) & NAME_MAX_FUNCTION);
    name.functionInstance = static_cast<std::uint8_t>((value >> 35) & NAME_MAX_FUNCTION_INSTANCE);
    name.ecuInstance = static_cast<std::uint8_t>((value >> 32) & NAME_MAX_ECU_INSTANCE);
    name.manufacturerCode = static_cast<std::uint16_t>((value >> 21) & NAME_MAX_MANUFACTURER_CODE);
    name.identityNumber = static_cast<std::uint32_t>(value & NAME_MAX_IDENTITY_NUMBER);
    return name;
  }

  /// Equal when the 64-bit values are equal (fields are compared as sent).
  friend constexpr bool operator==(const Name& a, const Name& b) noexcept {
    return a.toValue() == b.toValue();
  }
};

/// J1939-81 priority rule: `a` wins an address contest against `b` when its 64-bit NAME is
/// numerically lower. Equal NAMEs win against nobody.
[[nodiscard]] constexpr bool hasPriorityOver(const Name& a, const Name& b) noexcept {
  return a.toValue() < b.toValue();
}

/// The 8 Address Claimed bytes of a NAME, least significant byte first.
/// 0xBAAA80ADB4A12345 -> 45 23 A1 B4 AD 80 AA BA.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr NamePayload encodeName(const Name& name) noexcept {
  const std::uint64_t value = name.toValue();
  NamePayload bytes{};
  for (std::size_t i = 0; i < NAME_LENGTH; ++i) bytes[i] = static_cast<std::uint8_t>((value >> (8 * i)) & 0xFFu);
  return bytes;
}

/// The NAME in an Address Claimed payload; empty unless exactly 8 bytes arrive.
/// 45 23 A1 B4 AD 80 AA BA -> 0xBAAA80ADB4A12345.
/// @note thread-safe and real-time safe.
[[nodiscard]] constexpr std::optional<Name> decodeName(std::span<const std::uint8_t> data) noexcept {
  if (data.size() != NAME_LENGTH) return std::nullopt;
  std::uint64_t value = 0;
  for (std::size_t i = 0; i < NAME_LENGTH; ++i) value |= static_cast<std::uint64_t>(data[i]) << (8 * i);
  return Name::fromValue(value);
}

namespace name_example {
inline constexpr Name EXAMPLE{true, 3, 10, 0x55, false, 0x80, 21, 5, 0x5A5, 0x12345};
inline constexpr std::uint64_t EXAMPLE_VALUE = 0xBAAA80ADB4A12345u;
inline constexpr NamePayload EXAMPLE_BYTES{0x45, 0x23, 0xA1, 0xB4, 0xAD, 0x80, 0xAA, 0xBA};
}  // namespace name_example

static_assert(name_example::EXAMPLE.fits());
static_assert(name_example::EXAMPLE.toValue() == name_example::EXAMPLE_VALUE);
static_assert(Name::fromValue(name_example::EXAMPLE_VALUE).toValue() == name_example::EXAMPLE_VALUE);
static_assert(encodeName(name_example::EXAMPLE) == name_example::EXAMPLE_BYTES);
static_assert(decodeName(name_example::EXAMPLE_BYTES) == name_example::EXAMPLE);
// The AAC bit is the most significant: a NAME that may move loses to one that may not.
static_assert(hasPriorityOver(Name{false, 7}, Name{true, 0}));
static_assert(!hasPriorityOver(name_example::EXAMPLE, name_example::EXAMPLE));

}  // namespace openvcu::j1939
