// The computed fields exactly as can-tx's Scheduler::compute calls them (moved here from
// tests/services/can-tx/test_scheduler.cpp, issue 20).
#include "openvcu/j1939/computed_fields.hpp"

#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <string>

using namespace openvcu::j1939;

namespace {

std::span<const std::uint8_t> bytesOf(const std::string& text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

}  // namespace

TEST_CASE("CRC-8 SAE J1850 and the J1939-71 4-bit checksum") {
  const std::string check = "123456789";
  CHECK(crc8SaeJ1850(bytesOf(check)) == 0x4B);
  // s = 0x01 + 0x02 + (ID bytes 0x18 + 0xFE + 0xF1 + 0x21) = 0x22B; (0x22 + 0x22B) & 0xF = 0xD
  const std::array<std::uint8_t, 2> payload{0x01, 0x02};
  CHECK(j1939Checksum4(payload, 0x18FEF121) == 0x0D);
}

TEST_CASE("CRC-8 SAE J1850 of nothing is the initial value after the final XOR") {
  CHECK(crc8SaeJ1850({}) == 0x00);  // 0xFF ^ 0xFF
  constexpr std::array<std::uint8_t, 1> ZERO{0x00};
  CHECK(crc8SaeJ1850(ZERO) == 0x3B);  // 0xFF through the polynomial 8 times, then ^ 0xFF
}

TEST_CASE("sum8 wraps at 256 and xor8 is the XOR of the bytes") {
  constexpr std::array<std::uint8_t, 2> WRAPS{0xFF, 0x02};
  constexpr std::array<std::uint8_t, 2> MIXED{0x0F, 0xF1};
  CHECK(sum8(WRAPS) == 0x01);
  CHECK(xor8(MIXED) == 0xFE);
  CHECK(sum8({}) == 0);
  CHECK(xor8({}) == 0);
}

TEST_CASE("rolling counter starts at its start value and wraps at its modulo") {
  constexpr std::uint64_t START = 14;
  constexpr std::uint64_t MODULO = 16;
  RollingCounter sut(START, MODULO);

  CHECK(sut.next() == 14);
  CHECK(sut.next() == 15);
  CHECK(sut.next() == 0);
  CHECK(sut.peek() == 1);
}

TEST_CASE("rolling counter without a modulo keeps counting") {
  RollingCounter sut(255, 0);

  CHECK(sut.next() == 255);
  CHECK(sut.next() == 256);  // the caller keeps the signal's bits
}
