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

namespace openvcu {

struct Location {
  std::string file;      ///< file name as the user gave it; empty when not from a file
  std::uint32_t line{};  ///< 1-based; 0 when unknown
  std::uint32_t column{};///< 1-based; 0 when unknown
  std::string jsonPath;  ///< JSON pointer ("/states/3/name") for JSON inputs

  static Location json(std::string file, std::string path) {
    return Location{std::move(file), 0, 0, std::move(path)};
  }
  /// "file:line:col", "file:line", "file: /json/path" or "" depending on what is known.
  [[nodiscard]] std::string toString() const;
};

enum class Severity : std::uint8_t { Error, Warning, Note };

struct Error {
  std::string message;
  Location location{};
  Severity severity{Severity::Error};

  /// "file:line:col: message" (warnings: "file:line:col: warning: message").
  [[nodiscard]] std::string toString() const;
};

}  // namespace openvcu
