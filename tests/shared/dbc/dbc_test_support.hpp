#pragma once
// Test helpers for the DBC suites: parse inline text, find diagnostics, read fixtures.

#include "openvcu/core/text.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/parser.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::dbc::test {

inline constexpr std::string_view TEST_FILE = "test.dbc";

/// The fixture folder: every *.dbc here is round-tripped by test_round_trip.cpp.
inline std::filesystem::path fixtureDir() { return std::filesystem::path(OPENVCU_SOURCE_DIR) / "tests/data/dbc"; }

inline std::string readFixture(const std::string& name) {
  std::string reason;
  const auto content = text::readFile((fixtureDir() / name).string(), &reason);
  return content.value_or(std::string{});
}

inline ParseOutput parseText(std::string_view text) { return parse(text, TEST_FILE); }

/// Every diagnostic of `severity` whose message contains `fragment`.
inline std::vector<Error> diagnosticsWith(const ParseOutput& output, Severity severity, std::string_view fragment) {
  std::vector<Error> found;
  for (const Error& diagnostic : output.diagnostics) {
    if (diagnostic.severity == severity && diagnostic.message.find(fragment) != std::string::npos) {
      found.push_back(diagnostic);
    }
  }
  return found;
}

inline bool hasWarning(const ParseOutput& output, std::string_view fragment) {
  return !diagnosticsWith(output, Severity::Warning, fragment).empty();
}

inline bool hasError(const ParseOutput& output, std::string_view fragment) {
  return !diagnosticsWith(output, Severity::Error, fragment).empty();
}

/// All diagnostics on one line each, for INFO() when a check fails.
inline std::string describe(const ParseOutput& output) {
  std::string text;
  for (const Error& diagnostic : output.diagnostics) text += diagnostic.toString() + '\n';
  return text;
}

/// Index of a signal in its message, for the codec's signalIndex arguments.
inline std::uint32_t signalIndex(const Message& message, std::string_view name) {
  const auto it = std::find_if(message.signals.begin(), message.signals.end(),
                               [&](const Signal& signal) { return signal.name == name; });
  return static_cast<std::uint32_t>(it - message.signals.begin());
}

/// One decoded signal as the visitor reported it.
struct Visited {
  std::uint32_t index{};
  DecodedValue value;
};

inline std::vector<Visited> decodeAll(const MessageCodec& codec, std::span<const std::uint8_t> payload,
                                      DecodeSummary* summary = nullptr) {
  std::vector<Visited> visited;
  const DecodeSummary result = codec.decode(payload, [&](std::uint32_t index, const DecodedValue& value) {
    visited.push_back(Visited{index, value});
  });
  if (summary) *summary = result;
  return visited;
}

inline const Visited* findVisited(const std::vector<Visited>& visited, std::uint32_t index) {
  const auto it = std::find_if(visited.begin(), visited.end(), [&](const Visited& v) { return v.index == index; });
  return it == visited.end() ? nullptr : &*it;
}

inline constexpr std::uint32_t CLASSIC_LENGTH = 8;

/// "12 34 AB" -> {0x12, 0x34, 0xAB}
inline std::vector<std::uint8_t> hexBytes(std::string_view hex) {
  std::vector<std::uint8_t> out;
  std::size_t i = 0;
  while (i < hex.size()) {
    if (hex[i] == ' ') {
      ++i;
      continue;
    }
    out.push_back(static_cast<std::uint8_t>(std::stoul(std::string(hex.substr(i, 2)), nullptr, 16)));
    i += 2;
  }
  return out;
}

/// A database with one message "M" (ID 1, `length` bytes) holding `signals` (SG_ lines),
/// followed by `extra` statements.
inline ParseOutput oneMessage(const std::string& signals, std::uint32_t length = CLASSIC_LENGTH,
                              const std::string& extra = "") {
  return parseText("BO_ 1 M: " + std::to_string(length) + " Vcu\n" + signals + extra);
}

/// The first message of a parse that must have no errors.
inline const Message& onlyMessage(const ParseOutput& parsed) {
  INFO(describe(parsed));
  REQUIRE_FALSE(parsed.hasErrors());
  REQUIRE(!parsed.database.messages.empty());
  return parsed.database.messages[0];
}

/// The value the visitor reported for signal `index`; fails the test when it was not visited.
inline DecodedValue visitedValue(const std::vector<Visited>& visited, std::uint32_t index) {
  const Visited* found = findVisited(visited, index);
  REQUIRE(found != nullptr);
  return found->value;
}

/// Decodes and returns signal `index`'s value; fails the test when it was not visited.
inline DecodedValue decodeOne(const MessageCodec& sut, std::span<const std::uint8_t> payload, std::uint32_t index) {
  return visitedValue(decodeAll(sut, payload), index);
}

}  // namespace openvcu::dbc::test
