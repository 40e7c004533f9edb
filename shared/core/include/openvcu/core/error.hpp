#pragma once
// Errors with a location, the first tier of openvcu's error handling (STYLE.md 4):
// start-up, configuration and file loading report one of these; `main` prints
// toString() on one line and exits non-zero.
//
//   Error{"unknown keyword", Location{"vehicle.dbc", 12, 3}}.toString()
//     -> "vehicle.dbc:12:3: unknown keyword"
//   Error{"must be a number", Location::json("vehicle.json", "/buses/0/bitrate")}
//     -> "vehicle.json: /buses/0/bitrate: must be a number"

#include <cstdint>
#include <string>
#include <string_view>

namespace openvcu {

struct Location {
  std::string file;      ///< file name as the user gave it; empty when not from a file
  std::uint32_t line{};  ///< 1-based; 0 when unknown
  std::uint32_t column{};///< 1-based; 0 when unknown
  std::string jsonPath;  ///< JSON pointer ("/states/3/name") for JSON inputs

  static Location json(std::string file, std::string path) {
    return Location{std::move(file), 0, 0, std::move(path)};
  }
  /// "file:line:col", "file:line", "file: /json/path" or "" depending on what is known;
  /// control characters escaped as in escapeControlCharacters().
  [[nodiscard]] std::string toString() const;
};

enum class Severity : std::uint8_t { Error, Warning, Note };

struct Error {
  std::string message;
  Location location{};
  Severity severity{Severity::Error};

  /// "file:line:col: message" (warnings: "file:line:col: warning: message"), always one
  /// line: control characters in the file name and message are escaped (issue 19), so a
  /// NUL or newline quoted from the input never reaches a terminal or log raw.
  [[nodiscard]] std::string toString() const;
};

/// `text` with control characters escaped: NUL -> "\0", LF -> "\n", CR -> "\r", other
/// C0 bytes and DEL -> "\xHH"; TAB and bytes from 0x80 (UTF-8) kept.
/// "bad\nname" (a real newline) -> "bad\\nname" (a backslash and an n).
/// Escaping never changes text without control characters, so it may be applied twice.
std::string escapeControlCharacters(std::string_view text);
/// The same, appended to `out` (allocation-free when `out` has the capacity).
void appendEscapedControlCharacters(std::string& out, std::string_view text);

}  // namespace openvcu
