#pragma once
// Small text helpers shared by parsers and tools.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace openvcu::text {

/// Levenshtein edit distance (case-sensitive). O(|a|*|b|) time, O(|b|) memory.
std::size_t editDistance(std::string_view a, std::string_view b);

/// The candidate closest to `word` if it is close enough to be a plausible typo
/// (distance <= max(2, |word|/3)); ties go to the first candidate.
/// "HS_HiUBusCnctSts" with candidates {"HS_HiUBusCnctnSts"} -> "HS_HiUBusCnctnSts".
std::optional<std::string> didYouMean(std::string_view word, std::span<const std::string> candidates);

/// true when `bytes` is well-formed UTF-8.
bool isValidUtf8(std::string_view bytes) noexcept;

/// Appends the UTF-8 encoding of a Unicode code point (at most 0x10FFFF): 0xE9 -> "\xC3\xA9".
void appendUtf8(std::string& out, std::uint32_t codePoint);

/// Converts Windows-1252 (a superset of printable Latin-1) text to UTF-8.
std::string cp1252ToUtf8(std::string_view bytes);

/// Reads a whole file under the input-file rule (input_file.hpp: regular files only, at
/// most input::TEXT_FILE's 64 MiB, a pending SIGTERM ends the read); on failure returns
/// nullopt and the reason in *errorMessage ("not a regular file (directory)").
std::optional<std::string> readFile(const std::string& path, std::string* errorMessage);

/// A number as people read it in messages: the shortest text that reads back as the same
/// double ("0.1", "3600000", "1.8e+19"); "nan", "inf", "-inf" for the non-finite ones.
/// @note noexcept apart from the string's allocation.
std::string number(double value);

/// Glob-style match with `*` and `?` (used for signal patterns like "VIC.*SOC*").
bool globMatch(std::string_view pattern, std::string_view text) noexcept;

}  // namespace openvcu::text
